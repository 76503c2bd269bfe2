// A driver for The Rest of Your Life's own C++ (the books' repository,
// src/TheRestOfYourLife/), used by rtow as an anchor: the book's final Cornell box (a glass
// sphere and a tall white box, light sampling through a mixture of the light quad and the
// sphere) rendered by the book's code, with the size, samples per pixel, depth and
// seed taken from the command line.
//
//   book3-anchor WIDTH SPP DEPTH SEED > out.ppm
//
// build.sh compiles this file against a copy of the book's main.cc in which five lines are
// touched (sed, see build.sh): `int main() {` becomes `void anchor_scene() {` (a function
// the driver calls: renamed but still int, it would flow off its end, undefined behaviour),
// the width, samples and depth read the globals below instead of 600, 100 and 50, and
// `cam.render(world, lights)` becomes `anchor_render(cam, world, lights)`. Everything else (the scene, camera with its stratified sub-pixel grid of
// floor(sqrt(SPP))^2 samples, materials, pdfs, the 8-bit P3 PPM on stdout, the progress on
// stderr) is the book's. The book draws every random number from rand(); the driver calls
// srand(SEED) as the render starts (the scene draws nothing while built).
//
// On stderr, after the book's "Done.", one line: `rays N`, the number of rays traced,
// counted as rtow counts them: one per intersection query of the world (a wrapper around
// the world counts the calls of its hit(); the lights' pdf queries are not counted).

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
// A diagnostic build (build.sh's book3-anchor-mt19937): the book's rand() replaced by the 31
// high bits of std::mt19937 seeded with the same seed, as book-anchor-mt19937 does (anchor.cc).
#include <random>
static std::mt19937 anchor_mt;
static int anchor_rand() { return int(anchor_mt() >> 1); }
static void anchor_srand(unsigned seed) {
    std::srand(seed);
    anchor_mt.seed(seed);
}
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
static unsigned anchor_seed = 0;

namespace {

class counting_world : public hittable {
  public:
    explicit counting_world(const hittable& inner) : inner(inner) {}

    bool hit(const ray& r, interval ray_t, hit_record& rec) const override {
        ++rays;
        return inner.hit(r, ray_t, rec);
    }

    aabb bounding_box() const override { return inner.bounding_box(); }

    double pdf_value(const point3& origin, const vec3& direction) const override {
        return inner.pdf_value(origin, direction);
    }

    vec3 random(const point3& origin) const override { return inner.random(origin); }

    mutable unsigned long long rays = 0;

  private:
    const hittable& inner;
};

void anchor_render(camera& cam, const hittable& world, const hittable& lights) {
    counting_world counted(world);
    anchor_srand(anchor_seed);
    cam.render(counted, lights);
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

// The book's main(), as anchor_scene().
#include "main.cc"

int main(int argc, char** argv) {
    long width, spp, depth, seed;
    if (argc != 5 || !parse(argv[1], 1, 100000, width) || !parse(argv[2], 1, 1000000, spp)
        || !parse(argv[3], 1, 100000, depth) || !parse(argv[4], 0, 4294967295L, seed)) {
        std::fprintf(stderr, "usage: book3-anchor WIDTH SPP DEPTH SEED > out.ppm"
                             " (positive integers; the seed 0 to 2^32-1)\n");
        return 2;
    }
    anchor_width = int(width);
    anchor_spp = int(spp);
    anchor_depth = int(depth);
    anchor_seed = unsigned(seed);
    anchor_srand(1); // the state the book's own program starts in (nothing is drawn before the render)
    anchor_scene();
    return 0;
}
