// A driver for The Next Week's own C++ (the books' repository, src/TheNextWeek/), used
// by rtow as an anchor: the Cornell box rendered by the book's code, with the size,
// samples per pixel, depth and seed taken from the command line.
//
//   book-anchor WIDTH SPP DEPTH SEED > out.ppm
//
// build.sh compiles this file against a copy of the book's main.cc in which only
// cornell_box() is touched, three lines of it (sed, see build.sh): its width, samples and
// depth read the globals below instead of 600, 200 and 50, and `cam.render(world)`
// becomes `anchor_render(cam, world)`. Everything else (the scene, camera, materials,
// quads, instances, the gamma-2 8-bit P3 PPM on stdout, the progress on stderr) is the
// book's. The seed goes to srand(): the book draws every random number from rand().
//
// On stderr, after the book's "Done.", one line: `rays N`, the number of rays traced,
// counted as rtow counts them: one per intersection query of the world, i.e. every call
// of camera::ray_color with depth > 0 (a wrapper around the world counts the calls of
// its hit(); the objects below it are not wrapped).

// Every standard header the book and stb_image include, before the macro below can touch them.
#include <algorithm>
#include <cassert>
#include <cmath>
#include <cstdarg>
#include <cstddef>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <climits>
#include <iostream>
#include <limits>
#include <memory>
#include <string>
#include <vector>

#ifdef ANCHOR_MT19937
// A diagnostic build (build.sh's book-anchor-mt19937): the book's rand() replaced by the
// 31 high bits of std::mt19937, seeded with the same seed, to tell the book's geometry and
// estimator apart from glibc's rand() (an additive lagged Fibonacci generator, lags 3 and
// 31). Nothing else changes.
#include <random>
static std::mt19937 anchor_mt;
static int anchor_rand() { return int(anchor_mt() >> 1); }
static void anchor_srand(unsigned seed) { anchor_mt.seed(seed); }
#define rand anchor_rand
#else
static void anchor_srand(unsigned seed) { std::srand(seed); }
#endif

#include "rtweekend.h"

#include "camera.h"
#include "hittable.h"

static int anchor_width = 120;
static int anchor_spp = 16;
static int anchor_depth = 50;

namespace {

class counting_world : public hittable {
  public:
    explicit counting_world(const hittable& inner) : inner(inner) {}

    bool hit(const ray& r, interval ray_t, hit_record& rec) const override {
        ++rays;
        return inner.hit(r, ray_t, rec);
    }

    aabb bounding_box() const override { return inner.bounding_box(); }

    mutable unsigned long long rays = 0;

  private:
    const hittable& inner;
};

void anchor_render(camera& cam, const hittable& world) {
    counting_world counted(world);
    cam.render(counted);
    std::fprintf(stderr, "rays %llu\n", counted.rays);
}

bool parse(const char* text, long min, long max, long& out) {
    char* end = nullptr;
    long v = std::strtol(text, &end, 10);
    if (end == text || *end != '\0' || v < min || v > max)
        return false;
    out = v;
    return true;
}

} // namespace

// The book's main() is renamed and never called; renamed, it lacks the implicit return 0.
#pragma GCC diagnostic push
#pragma GCC diagnostic ignored "-Wreturn-type"
#define main book_main
#include "main.cc"
#undef main
#pragma GCC diagnostic pop

int main(int argc, char** argv) {
    long width, spp, depth, seed;
    if (argc != 5 || !parse(argv[1], 1, 100000, width) || !parse(argv[2], 1, 1000000, spp)
        || !parse(argv[3], 1, 100000, depth) || !parse(argv[4], 0, 4294967295L, seed)) {
        std::fprintf(stderr, "usage: book-anchor WIDTH SPP DEPTH SEED > out.ppm"
                             " (positive integers; the seed 0 to 2^32-1)\n");
        return 2;
    }
    anchor_width = int(width);
    anchor_spp = int(spp);
    anchor_depth = int(depth);
    anchor_srand(unsigned(seed));
    cornell_box();
    return 0;
}
