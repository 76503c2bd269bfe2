#!/bin/bash
# The figures of docs/shards.md ("Figures"). Run on a quiet
# machine (nothing else building or rendering), from the repository root:
#
#   cargo build --release
#   examples/shard-figures.sh                        # 1 and 2
#   RTOW_F32=/path/to/old/rtow examples/shard-figures.sh   # and 3
#
# 1. The overhead of splitting: N shards on N cores (N processes of one
#    thread each, at the same time) against one process with N threads, same
#    image: wall time and total CPU time (user + sys of every process), the
#    median of REPEAT runs, for both splits. The merged image is checked.
# 2. Merge time: 16 parts of a 1200x675 render (`rtow merge`'s own read /
#    merge / write times and the process's wall time), median of REPEAT.
# 3. With RTOW_F32 (an rtow built from main before the fixed-point film, i.e.
#    the f32 accumulation): `rtow bench` of both binaries, interleaved, so the
#    cost of the exact accumulation shows as a Mrays/s difference.
#
# Environment: RTOW [target/release/rtow], N [nproc], REPEAT [5],
# SCENE_ARGS [final --width 1200 --height 675 --spp 64 --depth 50],
# MERGE_SIZE [--width 1200 --height 675],
# BENCH_ARGS [--width 400 --height 225 --spp 32 --depth 50].
set -euo pipefail
rtow=$(realpath "${RTOW:-target/release/rtow}")
f32=${RTOW_F32:+$(realpath "$RTOW_F32")}
n=${N:-$(nproc)}
repeat=${REPEAT:-5}
read -r -a scene <<<"${SCENE_ARGS:-final --width 1200 --height 675 --spp 64 --depth 50}"
work=$(mktemp -d)
trap 'rm -rf "$work"' EXIT
cd "$work"
hash_of() { sed -n 's/.*"image_hash": *"\([0-9a-f]*\)".*/\1/p' "$1"; }
median() { sort -g | awk '{v[NR]=$1} END {print (NR%2) ? v[(NR+1)/2] : (v[NR/2]+v[NR/2+1])/2}'; }
# Runs a command; appends "wall cpu" (seconds; cpu = user + sys of it and its children) to file $1.
timed() {
    local out=$1
    shift
    local t
    t=$({ TIMEFORMAT='%R %U %S'; time "$@" >/dev/null; } 2>&1 | tail -1)
    awk '{printf "%.3f %.3f\n", $1, $2 + $3}' <<<"$t" >>"$out"
}
shards() { # SPLIT
    local k
    for k in $(seq "$n"); do
        "$rtow" render "${scene[@]}" --threads 1 --split "$1" --shard "$k/$n" -q -o "part-$1-$k.rtfilm" &
    done
    wait
}

echo "rtow: $("$rtow" --version)"
echo "render: ${scene[*]}; N = $n; $repeat repetitions (medians)"
echo
echo "## 1. Overhead of splitting: $n shards on $n cores against one process with $n threads"
for r in $(seq "$repeat"); do
    timed one.t "$rtow" render "${scene[@]}" --threads "$n" -q -o one.png --stats-json one.json
    timed samples.t shards samples
    timed rows.t shards rows
done
want=$(hash_of one.json)
for split in samples rows; do
    "$rtow" merge part-"$split"-*.rtfilm -q -o "$split.png" --stats-json "$split.json"
    [ "$(hash_of "$split.json")" = "$want" ] || { echo "error: the $split shards merge into another image" >&2; exit 1; }
done
w1=$(cut -d' ' -f1 one.t | median)
c1=$(cut -d' ' -f2 one.t | median)
printf '| run | wall s | CPU s (user+sys) | CPU vs one process |\n|---|---:|---:|---:|\n'
printf '| one process, %s threads | %.2f | %.2f | - |\n' "$n" "$w1" "$c1"
for split in samples rows; do
    w=$(cut -d' ' -f1 "$split.t" | median)
    c=$(cut -d' ' -f2 "$split.t" | median)
    printf '| %s shards by %s, 1 thread each | %.2f | %.2f | %+.1f%% |\n' "$n" "$split" "$w" "$c" \
        "$(awk -v a="$c" -v b="$c1" 'BEGIN {print 100 * (a / b - 1)}')"
done
echo "(merged images identical to the one-process image: hash $want)"

echo
echo "## 2. Merge time: 16 parts (${MERGE_SIZE:---width 1200 --height 675})"
for k in $(seq 16); do
    # shellcheck disable=SC2086
    "$rtow" render final ${MERGE_SIZE:---width 1200 --height 675} --spp 32 --depth 50 --shard "$k/16" -q -o "m-$k.rtfilm"
done
ls -l m-1.rtfilm | awk '{printf "part size: %.1f MB each\n", $5 / 1e6}'
for r in $(seq "$repeat"); do
    timed merge.t "$rtow" merge m-*.rtfilm -q -o merged.png --float merged.exr --stats-json "merge-$r.json"
    sed -n 's/.*"\(read\|merge\|write\)_seconds": *\([0-9.e-]*\).*/\1 \2/p' "merge-$r.json" >>merge-parts.t
done
printf 'rtow merge, 16 parts -> PNG + EXR: %.3f s wall, %.3f s CPU (medians)\n' \
    "$(cut -d' ' -f1 merge.t | median)" "$(cut -d' ' -f2 merge.t | median)"
for what in read merge write; do
    printf '  %s: %.3f s\n' "$what" "$(awk -v w="$what" '$1 == w {print $2}' merge-parts.t | median)"
done

if [ -n "$f32" ]; then
    echo
    echo "## 3. Cost of the exact accumulation: rtow bench, f32 film ($f32) and fixed-point film, interleaved"
    for r in $(seq "$repeat"); do
        for b in f32:"$f32" fixed:"$rtow"; do
            # shellcheck disable=SC2086
            "${b#*:}" bench final ${BENCH_ARGS:---width 400 --height 225 --spp 32 --depth 50} --threads 1 --repeat 3 \
                --json "bench-${b%%:*}-$r.json" >/dev/null 2>&1
        done
    done
    for b in f32 fixed; do
        for k in scalar simd; do
            # Mrays/s of kernel k (the first kernel entry whose name starts with k) in each run.
            m=$(for f in bench-"$b"-*.json; do
                python3 -c 'import json,sys; d=json.load(open(sys.argv[1])); print(next(e.get("stats", e)["mrays_per_s"] for e in d["kernels"] if e.get("stats", e)["kernel"].startswith(sys.argv[2])))' "$f" "$k"
            done | median)
            printf '%s film, %s kernel: %.2f Mrays/s (median of %s)\n' "$b" "$k" "$m" "$repeat"
        done
    done
fi
