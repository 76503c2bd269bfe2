#!/usr/bin/env bash
# Builds the book's own C++ for the Cornell box (The Next Week, v4) with anchor.cc as its
# driver. Usage: examples/book-anchor/build.sh [DIR]   (default: target/book-anchor)
#
# BOOK_REPO: where to clone the books' repository from (default: GitHub; a local clone
#            or mirror works). The commit is pinned: the v4 `dev` branch's head that
#            ../../docs/nextweek.md was measured at.
# CXX, CXXFLAGS: the compiler and flags (default: g++ -std=c++17 -O3 -march=x86-64-v3).
set -euo pipefail

BOOK_COMMIT=d3e5bf95bd10414f840b184e4f57e52e4c54a493
BOOK_REPO=${BOOK_REPO:-https://github.com/RayTracing/raytracing.github.io}
CXX=${CXX:-g++}
CXXFLAGS=${CXXFLAGS:--std=c++17 -O3 -march=x86-64-v3}

here=$(cd "$(dirname "$0")" && pwd)
out=${1:-target/book-anchor}
mkdir -p "$out"
out=$(cd "$out" && pwd)

if [ ! -d "$out/book/.git" ]; then
    rm -rf "$out/book"
    git init -q "$out/book"
    git -C "$out/book" remote add origin "$BOOK_REPO"
fi
if [ "$(git -C "$out/book" rev-parse -q --verify HEAD || true)" != "$BOOK_COMMIT" ]; then
    git -C "$out/book" fetch -q --depth 1 origin "$BOOK_COMMIT"
    git -C "$out/book" checkout -q --detach "$BOOK_COMMIT"
fi

src="$out/src"
rm -rf "$src"
mkdir -p "$src"
cp "$out/book/src/TheNextWeek/"*.h "$out/book/src/TheNextWeek/main.cc" "$src/"

# Three lines of cornell_box() and nothing else: width, samples and depth from the
# command line, and the render through the driver's ray counter.
sed -i \
    -e '/^void cornell_box() {/,/^}/{
s/cam\.image_width       = 600;/cam.image_width       = anchor_width;/
s/cam\.samples_per_pixel = 200;/cam.samples_per_pixel = anchor_spp;/
s/cam\.max_depth         = 50;/cam.max_depth         = anchor_depth;/
s/cam\.render(world);/anchor_render(cam, world);/
}' "$src/main.cc"
changed=$(diff "$out/book/src/TheNextWeek/main.cc" "$src/main.cc" | grep -c '^>' || true)
if [ "$changed" != 4 ]; then
    echo "build.sh: expected to change 4 lines of cornell_box() in main.cc, changed $changed" >&2
    exit 2
fi
cp "$here/anchor.cc" "$src/"

# shellcheck disable=SC2086
"$CXX" $CXXFLAGS -I"$src" -I"$out/book/src" -o "$out/book-anchor" "$src/anchor.cc"
# The same with std::mt19937 in place of glibc's rand() (a diagnostic: docs/nextweek.md).
# shellcheck disable=SC2086
"$CXX" $CXXFLAGS -DANCHOR_MT19937 -I"$src" -I"$out/book/src" -o "$out/book-anchor-mt19937" "$src/anchor.cc"
echo "$out/book-anchor, $out/book-anchor-mt19937  (book $BOOK_COMMIT, $CXX $CXXFLAGS)"
