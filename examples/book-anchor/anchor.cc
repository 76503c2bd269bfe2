// A driver for The Next Week's own C++ (the books' repository, src/TheNextWeek/), used
// by rtow as an anchor: three of the book's scenes rendered by the book's code, with the
// size, samples per pixel, depth and seed taken from the command line.
//
//   book-anchor [SCENE] WIDTH SPP DEPTH SEED > out.ppm
//
// SCENE is cornell_box (the default), cornell_smoke or final_scene, the book's functions of
// those names. build.sh compiles this file against a copy of the book's main.cc in which
// only those three functions are touched (sed, see build.sh): in cornell_box() and
// cornell_smoke() the width, samples and depth read the globals below instead of 600, 200
// and 50; final_scene() takes them as arguments already; in all three `cam.render(world)`
// becomes `anchor_render(cam, world)`. Everything else (the scenes, camera, materials,
// quads, instances, media, textures, the gamma-2 8-bit P3 PPM on stdout, the progress on
// stderr) is the book's.
//
// The book draws every random number from rand(). The scene is built in the state the
// book's own program starts in (glibc's, as after srand(1)), so final_scene()'s random box
// heights, cloud of spheres and Perlin tables are the book's and the same under every seed;
// then, as the render starts, srand(SEED). cornell_box() and cornell_smoke() draw nothing
// while they are built. final_scene() reads earthmap.jpg through the book's own search,
// RTW_IMAGES first: the driver requires RTW_IMAGES to name a folder holding it (the book
// would otherwise print an error and render a cyan earth).
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
// 31). Only the render's numbers: the scene is built from glibc's rand() as in the book, so
// final_scene()'s layout and Perlin tables are the same in both builds.
#include <random>
static std::mt19937 anchor_mt;
static bool anchor_rendering = false;
static int anchor_rand() { return anchor_rendering ? int(anchor_mt() >> 1) : std::rand(); }
static void anchor_srand(unsigned seed) {
    std::srand(seed);
    anchor_mt.seed(seed);
}
static void anchor_start_render() { anchor_rendering = true; }
#define rand anchor_rand
#else
static void anchor_srand(unsigned seed) { std::srand(seed); }
static void anchor_start_render() {}
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

    mutable unsigned long long rays = 0;

  private:
    const hittable& inner;
};

void anchor_render(camera& cam, const hittable& world) {
    counting_world counted(world);
    anchor_srand(anchor_seed);
    anchor_start_render();
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
    // The scene: the first argument when there are five.
    const char* scene = "cornell_box";
    if (argc == 6) {
        scene = argv[1];
        --argc;
        ++argv;
    }
    const bool known = !std::strcmp(scene, "cornell_box") || !std::strcmp(scene, "cornell_smoke")
                       || !std::strcmp(scene, "final_scene");
    long width, spp, depth, seed;
    if (!known || argc != 5 || !parse(argv[1], 1, 100000, width)
        || !parse(argv[2], 1, 1000000, spp) || !parse(argv[3], 1, 100000, depth)
        || !parse(argv[4], 0, 4294967295L, seed)) {
        std::fprintf(stderr, "usage: book-anchor [cornell_box|cornell_smoke|final_scene] WIDTH SPP"
                             " DEPTH SEED > out.ppm (positive integers; the seed 0 to 2^32-1)\n");
        return 2;
    }
    anchor_width = int(width);
    anchor_spp = int(spp);
    anchor_depth = int(depth);
    anchor_seed = unsigned(seed);
    // The state the book's own program starts in, for whatever the scene draws while built.
    anchor_srand(1);
    if (!std::strcmp(scene, "cornell_box")) {
        cornell_box();
    } else if (!std::strcmp(scene, "cornell_smoke")) {
        cornell_smoke();
    } else {
        const char* dir = std::getenv("RTW_IMAGES");
        std::string map = std::string(dir ? dir : "") + "/earthmap.jpg";
        std::FILE* f = dir ? std::fopen(map.c_str(), "rb") : nullptr;
        if (!f) {
            std::fprintf(stderr, "book-anchor: final_scene needs RTW_IMAGES, a folder with the"
                                 " book's earthmap.jpg (%s)\n", dir ? "not found there" : "not set");
            return 2;
        }
        std::fclose(f);
        final_scene(anchor_width, anchor_spp, anchor_depth);
    }
    return 0;
}
