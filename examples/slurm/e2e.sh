#!/bin/bash
# End to end on this machine: a single-node Slurm from Debian's packages runs
# the job-array example (render-shard.sbatch, one task per shard; merge.sbatch
# after it with --dependency=afterok), and the merged image must be bit for bit
# the one-process render (same image hash, same PNG bytes); a shard rerun
# alone writes the identical part.
#
#   examples/slurm/e2e.sh          install if needed, start, test, stop what it started
#   examples/slurm/e2e.sh up       install if needed and start (left running)
#   examples/slurm/e2e.sh down     stop the daemons this script's state folder names
#
# Needs root and apt-get (Debian/Ubuntu) the first time, to install slurm-wlm
# and munge; runs without a terminal (CI). Idempotent: a second run reuses the
# packages, the munge key and any daemon already running from its state folder.
# Made for containers: no cgroups (proctrack/linuxproc, task/none), no systemd;
# Slurm's configuration, state and logs live in $RTOW_SLURM_STATE
# [/var/tmp/rtow-slurm], nothing is written to /etc/slurm.
#
# Environment: RTOW (an rtow binary; default: the one `cargo test --release` builds,
# as .ci/run does), RTOW_SHARDS [4], RTOW_SPLIT [samples],
# RTOW_ARGS [a small final-scene render], RTOW_SLURM_TIMEOUT seconds [300].
set -euo pipefail

here=$(cd "$(dirname "$0")" && pwd)
repo=$(cd "$here/../.." && pwd)
state=${RTOW_SLURM_STATE:-/var/tmp/rtow-slurm}
shards=${RTOW_SHARDS:-4}
split=${RTOW_SPLIT:-samples}
args=${RTOW_ARGS:---width 192 --height 108 --spp 16 --depth 50 --seed 0}
timeout=${RTOW_SLURM_TIMEOUT:-300}
host=$(hostname -s)
export SLURM_CONF=$state/slurm.conf

say() { echo "slurm-e2e: $*"; }
die() {
    echo "slurm-e2e: error: $*" >&2
    exit 1
}

install_packages() {
    local missing=0 c
    for c in munged munge unmunge slurmctld slurmd sbatch squeue scontrol sinfo; do
        command -v "$c" >/dev/null 2>&1 || missing=1
    done
    [ "$missing" = 0 ] && return
    [ "$(id -u)" = 0 ] || die "slurm-wlm and munge are not installed, and installing them needs root"
    command -v apt-get >/dev/null || die "slurm-wlm and munge are not installed and there is no apt-get here"
    say "installing slurm-wlm and munge (apt-get)"
    export DEBIAN_FRONTEND=noninteractive
    apt-get update -q </dev/null
    apt-get install -y -q slurm-wlm munge </dev/null
}

# Our daemons are the ones whose pid files in $state name a live process.
alive() { [ -s "$1" ] && kill -0 "$(cat "$1")" 2>/dev/null; }

start_munge() {
    if munge -n </dev/null 2>/dev/null | unmunge >/dev/null 2>&1; then
        return # already running (ours from an earlier run, or the system's)
    fi
    if [ ! -s /etc/munge/munge.key ]; then
        say "creating a munge key"
        install -d -o munge -g munge -m 0700 /etc/munge
        if command -v mungekey >/dev/null; then
            mungekey --create --keyfile=/etc/munge/munge.key
        else
            dd if=/dev/urandom of=/etc/munge/munge.key bs=1024 count=1 status=none
        fi
        chown munge:munge /etc/munge/munge.key
        chmod 0400 /etc/munge/munge.key
    fi
    install -d -o munge -g munge -m 0755 /run/munge
    install -d -o munge -g munge -m 0700 /var/lib/munge /var/log/munge
    say "starting munged"
    runuser -u munge -- /usr/sbin/munged --pid-file=/run/munge/munged.pid
    cp /run/munge/munged.pid "$state/munged.pid"
    for _ in $(seq 50); do
        munge -n </dev/null 2>/dev/null | unmunge >/dev/null 2>&1 && return
        sleep 0.1
    done
    die "munged does not answer"
}

write_config() {
    mkdir -p "$state/ctld" "$state/spool"
    local cpus
    cpus=$(nproc)
    # The address is given: a container's hostname need not resolve.
    cat >"$state/slurm.conf.new" <<EOF
# Written by rtow's examples/slurm/e2e.sh: one node, no cgroups, no accounting.
ClusterName=rtow-e2e
SlurmctldHost=$host(127.0.0.1)
SlurmUser=root
SlurmdUser=root
AuthType=auth/munge
CredType=cred/munge
ProctrackType=proctrack/linuxproc
TaskPlugin=task/none
JobAcctGatherType=jobacct_gather/none
AccountingStorageType=accounting_storage/none
SelectType=select/cons_tres
SelectTypeParameters=CR_CPU
SchedulerType=sched/backfill
MpiDefault=none
MailProg=/bin/true
ReturnToService=2
StateSaveLocation=$state/ctld
SlurmdSpoolDir=$state/spool
SlurmctldPidFile=$state/slurmctld.pid
SlurmdPidFile=$state/slurmd.pid
SlurmctldLogFile=$state/slurmctld.log
SlurmdLogFile=$state/slurmd.log
SlurmctldPort=${RTOW_SLURMCTLD_PORT:-6817}
SlurmdPort=${RTOW_SLURMD_PORT:-6818}
NodeName=$host NodeAddr=127.0.0.1 CPUs=$cpus State=UNKNOWN
PartitionName=rtow Nodes=$host Default=YES MaxTime=INFINITE State=UP
EOF
    if ! cmp -s "$state/slurm.conf.new" "$state/slurm.conf"; then
        if alive "$state/slurmctld.pid" || alive "$state/slurmd.pid"; then
            say "the configuration changed: restarting the daemons"
            stop_daemons
        fi
        mv "$state/slurm.conf.new" "$state/slurm.conf"
    else
        rm "$state/slurm.conf.new"
    fi
}

start_slurm() {
    if ! alive "$state/slurmctld.pid"; then
        say "starting slurmctld"
        slurmctld -f "$SLURM_CONF" || die "slurmctld did not start: $(tail -5 "$state/slurmctld.log" 2>/dev/null)"
        echo started >"$state/slurmctld.ours"
    fi
    if ! alive "$state/slurmd.pid"; then
        say "starting slurmd"
        slurmd -f "$SLURM_CONF" || die "slurmd did not start: $(tail -5 "$state/slurmd.log" 2>/dev/null)"
        echo started >"$state/slurmd.ours"
    fi
    local t node
    for t in $(seq 60); do
        node=$(sinfo -h -n "$host" -o %t 2>/dev/null || true)
        case "$node" in
        idle | mix | alloc) return ;;
        down* | drain* | drng* | fail*) scontrol update NodeName="$host" State=RESUME 2>/dev/null || true ;;
        esac
        sleep 0.5
    done
    tail -5 "$state/slurmctld.log" "$state/slurmd.log" >&2 || true
    die "the node is not ready after 30 s (state: ${node:-none})"
}

stop_daemons() {
    local d pid
    for d in slurmd slurmctld; do
        if alive "$state/$d.pid"; then
            pid=$(cat "$state/$d.pid")
            say "stopping $d ($pid)"
            kill "$pid"
            for _ in $(seq 50); do kill -0 "$pid" 2>/dev/null || break; sleep 0.1; done
        fi
        rm -f "$state/$d.ours"
    done
    if alive "$state/munged.pid"; then
        pid=$(cat "$state/munged.pid")
        say "stopping munged ($pid)"
        kill "$pid"
        rm -f "$state/munged.pid"
    fi
}

up() {
    install_packages
    mkdir -p "$state"
    start_munge
    write_config
    start_slurm
    say "Slurm is up: node $host, $(sinfo -h -o '%D node(s), %c CPUs, partition %P')"
}

hash_of() { sed -n 's/.*"image_hash": *"\([0-9a-f]*\)".*/\1/p' "$1"; }

e2e() {
    local started_here=0
    alive "$state/slurmctld.pid" && alive "$state/slurmd.pid" || started_here=1
    up
    if [ "$started_here" = 1 ]; then
        trap stop_daemons EXIT
    fi
    local rtow=${RTOW:-}
    if [ -z "$rtow" ]; then
        # The binary the README's test command builds (same profile and
        # features: nothing to compile again after it, as in .ci/run).
        say "building rtow (cargo test --release --no-run)"
        rtow=$(cd "$repo" && cargo test --release -q --no-run --message-format=json-render-diagnostics |
            grep '"kind":\["bin"\]' | grep '"test":false' | sed -n 's/.*"executable":"\([^"]*\)".*/\1/p' | tail -1)
        [ -x "$rtow" ] || die "cargo did not build rtow"
    fi
    local work
    work=$(mktemp -d "$state/run-XXXXXX")
    cp "$rtow" "$work/rtow"
    cd "$work"
    say "one-process render: final $args"
    # shellcheck disable=SC2086
    ./rtow render final $args --quiet -o one.png --stats-json one.json
    export RTOW=$work/rtow RTOW_SCENE=final RTOW_ARGS=$args RTOW_SPLIT=$split RTOW_PARTS=$work/parts \
        RTOW_OUT=$work/merged.png RTOW_LOGS=$work/logs
    local t0 ids array merge
    t0=$(date +%s%N)
    ids=$("$here/submit.sh" "$shards")
    read -r array merge <<<"$ids"
    say "submitted array job $array ($shards shards by $split) and merge job $merge (afterok:$array)"
    local deadline=$(($(date +%s) + timeout))
    while [ -n "$(squeue -h -j "$array,$merge" -o %i 2>/dev/null)" ]; do
        if [ "$(date +%s)" -ge "$deadline" ]; then
            scancel "$array" "$merge" || true
            tail -n 20 "$work"/logs/* >&2 || true
            die "the jobs did not finish within $timeout s"
        fi
        sleep 0.2
    done
    local ms=$((($(date +%s%N) - t0) / 1000000))
    local st
    st=$(scontrol -o show job "$merge" 2>/dev/null | grep -o 'JobState=[A-Z_]* .*ExitCode=[0-9:]*' |
        sed 's/JobState=\([A-Z_]*\) .*ExitCode=\([0-9:]*\)/\1 \2/' || true)
    if [ "$st" != "COMPLETED 0:0" ]; then
        tail -n 20 "$work"/logs/* >&2 || true
        die "the merge job ended as '${st:-unknown}' (logs above; work folder $work kept)"
    fi
    local one merged
    one=$(hash_of one.json)
    merged=$(hash_of merged.json)
    say "image hash: one process $one, $shards Slurm shards merged $merged"
    if [ -z "$one" ] || [ "$one" != "$merged" ] || ! cmp -s one.png merged.png; then
        die "the merged image differs from the one-process render (work folder $work kept)"
    fi
    # A failed or lost shard is rerun alone and writes the identical part.
    local k=$(((shards + 1) / 2))
    mv "parts/part-$k.rtfilm" "part-$k.first"
    RTOW_SHARDS=$shards timeout "$timeout" sbatch --wait --quiet --array="$k" --output="logs/rerun-%A_%a.out" \
        "$here/render-shard.sbatch" || die "the rerun of shard $k failed (logs in $work/logs)"
    cmp -s "part-$k.first" "parts/part-$k.rtfilm" || die "the rerun of shard $k wrote a different part"
    say "shard $k rerun alone (sbatch --array=$k): the identical part"
    say "ok: $shards shards by $split, from submission to merged image $((ms / 1000)).$(printf %03d $((ms % 1000))) s wall"
    cd /
    rm -rf "$work"
}

case "${1:-}" in
"") e2e ;;
up) up ;;
down) stop_daemons ;;
*) die "usage: $0 [up|down]" ;;
esac
