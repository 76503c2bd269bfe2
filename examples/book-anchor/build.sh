#!/usr/bin/env bash
# Builds the book's own C++ for three scenes of The Next Week (v4): cornell_box(),
# cornell_smoke() and final_scene(), with anchor.cc as its driver.
# Usage: examples/book-anchor/build.sh [DIR]   (default: target/book-anchor)
#
# BOOK_REPO: where to clone the books' repository from (default: GitHub; a local clone
#            or mirror works). The commit is pinned: the v4 `dev` branch's head that
#            ../../docs/books.md was measured at.
# CXX, CXXFLAGS: the compiler and flags (default: g++ -std=c++17 -O3 -march=x86-64-v3).
# DIAGNOSTICS=1: also the diagnostic variants book-anchor-{metal,metal-white,grey-mt19937}.
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

# Only what the driver needs, and nothing else: in cornell_box() and cornell_smoke(), width,
# samples and depth from the command line (four lines each, with the render); final_scene()
# takes them as arguments already, so only its render changes (one line). Every render goes
# through the driver's ray counter.
sed -i \
    -e '/^void cornell_box() {/,/^}/{
s/cam\.image_width       = 600;/cam.image_width       = anchor_width;/
s/cam\.samples_per_pixel = 200;/cam.samples_per_pixel = anchor_spp;/
s/cam\.max_depth         = 50;/cam.max_depth         = anchor_depth;/
s/cam\.render(world);/anchor_render(cam, world);/
}' \
    -e '/^void cornell_smoke() {/,/^}/{
s/cam\.image_width       = 600;/cam.image_width       = anchor_width;/
s/cam\.samples_per_pixel = 200;/cam.samples_per_pixel = anchor_spp;/
s/cam\.max_depth         = 50;/cam.max_depth         = anchor_depth;/
s/cam\.render(world);/anchor_render(cam, world);/
}' \
    -e '/^void final_scene(int image_width, int samples_per_pixel, int max_depth) {/,/^}/{
s/cam\.render(world);/anchor_render(cam, world);/
}' "$src/main.cc"
# The guard: each function must have changed in exactly the lines expected.
changed_in() { # FUNCTION-HEADER-PREFIX
    diff <(sed -n "/^$1/,/^}/p" "$out/book/src/TheNextWeek/main.cc") \
        <(sed -n "/^$1/,/^}/p" "$src/main.cc") | grep -c '^>' || true
}
for expect in "void cornell_box() {:4" "void cornell_smoke() {:4" \
    "void final_scene(int image_width, int samples_per_pixel, int max_depth) {:1"; do
    fn=${expect%:*}
    want=${expect##*:}
    got=$(changed_in "$fn")
    if [ "$got" != "$want" ]; then
        echo "build.sh: expected to change $want lines of ${fn% \{} in main.cc, changed $got" >&2
        exit 2
    fi
done
changed=$(diff "$out/book/src/TheNextWeek/main.cc" "$src/main.cc" | grep -c '^>' || true)
if [ "$changed" != 9 ]; then
    echo "build.sh: expected to change 9 lines of main.cc, changed $changed" >&2
    exit 2
fi
cp "$here/anchor.cc" "$src/"

# shellcheck disable=SC2086
"$CXX" $CXXFLAGS -I"$src" -I"$out/book/src" -o "$out/book-anchor" "$src/anchor.cc"
# final_scene()'s random layout as the book draws it (box heights, cloud centres).
cp "$here/final-layout.cc" "$src/"
# shellcheck disable=SC2086
"$CXX" $CXXFLAGS -I"$src" -I"$out/book/src" -o "$out/book-final-layout" "$src/final-layout.cc"
# The same with std::mt19937 in place of glibc's rand() (a diagnostic: docs/books.md).
# shellcheck disable=SC2086
"$CXX" $CXXFLAGS -DANCHOR_MT19937 -I"$src" -I"$out/book/src" -o "$out/book-anchor-mt19937" "$src/anchor.cc"

# DIAGNOSTICS=1: three variants of book-anchor, each the book with some of its known
# differences from rtow taken away, to tell them apart (docs/books.md, "The Cornell smoke
# and the final scene"): `-metal` the metal as fixed upstream after this commit (unit reflected
# direction plus fuzz times a unit vector: RayTracing/raytracing.github.io#1496 and #1499; rtow's
# metal), `-metal-white`
# also keeps pure-white texels white (rtow's fix of the byte overflow: a channel of 255 became 256.0, out of a byte's range),
# `-grey-mt19937` also makes final_scene()'s marble sphere a grey lambertian 0.5 and draws the
# render's numbers from std::mt19937. One line changed per difference, each checked.
variant() { # NAME CXX-EXTRA FILE:SED-EXPRESSION...
    local name=$1 extra=$2 dir="$out/src-$1"
    shift 2
    rm -rf "$dir"
    cp -r "$src" "$dir"
    for edit in "$@"; do
        local file=${edit%%:*} expr=${edit#*:}
        sed -i -e "$expr" "$dir/$file"
        if [ "$(diff "$src/$file" "$dir/$file" | grep -c '^>' || true)" != 1 ]; then
            echo "build.sh: variant $name: expected to change 1 line of $file" >&2
            exit 2
        fi
    done
    # shellcheck disable=SC2086
    "$CXX" $CXXFLAGS $extra -I"$dir" -I"$out/book/src" -o "$out/book-anchor-$name" "$dir/anchor.cc"
}
if [ "${DIAGNOSTICS:-0}" = 1 ]; then
    metal='material.h:s/^        scattered = ray(rec\.p, reflected + fuzz\*random_in_unit_sphere(), r_in\.time());$/        scattered = ray(rec.p, unit_vector(reflected) + fuzz*random_unit_vector(), r_in.time());/'
    white='rtw_stb_image.h:s/^            \*bptr = static_cast<unsigned char>(\*fptr \* 256\.0);$/            *bptr = *fptr >= 1.0f ? 255 : static_cast<unsigned char>(*fptr * 256.0);/'
    grey='main.cc:s/^    world\.add(make_shared<sphere>(point3(220,280,300), 80, make_shared<lambertian>(pertext)));$/    world.add(make_shared<sphere>(point3(220,280,300), 80, make_shared<lambertian>(color(.5,.5,.5))));/'
    variant metal "" "$metal"
    variant metal-white "" "$metal" "$white"
    variant grey-mt19937 -DANCHOR_MT19937 "$metal" "$white" "$grey"
fi

# The Rest of Your Life's final Cornell box (its main.cc) with anchor-rol.cc: five lines, main()
# made the function the driver calls, width, samples and depth from the command line, and the
# render through the driver's ray counter.
src3="$out/src-rol"
rm -rf "$src3"
mkdir -p "$src3"
cp "$out/book/src/TheRestOfYourLife/"*.h "$out/book/src/TheRestOfYourLife/main.cc" "$src3/"
sed -i \
    -e 's/^int main() {$/void anchor_scene() {/' \
    -e 's/^    cam\.image_width       = 600;$/    cam.image_width       = anchor_width;/' \
    -e 's/^    cam\.samples_per_pixel = 100;$/    cam.samples_per_pixel = anchor_spp;/' \
    -e 's/^    cam\.max_depth         = 50;$/    cam.max_depth         = anchor_depth;/' \
    -e 's/^    cam\.render(world, lights);$/    anchor_render(cam, world, lights);/' \
    "$src3/main.cc"
changed=$(diff "$out/book/src/TheRestOfYourLife/main.cc" "$src3/main.cc" | grep -c '^>' || true)
if [ "$changed" != 5 ]; then
    echo "build.sh: expected to change 5 lines of The Rest of Your Life's main.cc, changed $changed" >&2
    exit 2
fi
cp "$here/anchor-rol.cc" "$src3/"
# shellcheck disable=SC2086
"$CXX" $CXXFLAGS -I"$src3" -I"$out/book/src" -o "$out/book3-anchor" "$src3/anchor-rol.cc"
# shellcheck disable=SC2086
"$CXX" $CXXFLAGS -DANCHOR_MT19937 -I"$src3" -I"$out/book/src" -o "$out/book3-anchor-mt19937" "$src3/anchor-rol.cc"
diag=""
if [ "${DIAGNOSTICS:-0}" = 1 ]; then diag=", $out/book-anchor-{metal,metal-white,grey-mt19937}"; fi
echo "$out/book-anchor, $out/book-anchor-mt19937$diag, $out/book-final-layout, $out/book3-anchor, $out/book3-anchor-mt19937  (book $BOOK_COMMIT, $CXX $CXXFLAGS)"
