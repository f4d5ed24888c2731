#!/bin/bash
# Render one image as N independent processes on one big machine with GNU parallel, then merge.
# Each process renders a disjoint share of the samples; a pass that fails can be rerun alone
# (`--pass K/N` is deterministic) and the merge gives the single render's image bit for bit.
#
#   examples/gnu-parallel.sh SCENE [N] [SPP]
set -euo pipefail

SCENE=${1:?usage: gnu-parallel.sh SCENE [N] [SPP]}
N=${2:-8}
SPP=${3:-1024}
JOBS=${JOBS:-4}                                  # processes at once
THREADS=$(( $(nproc) / JOBS > 0 ? $(nproc) / JOBS : 1 ))
PARTS=${PARTS:-parts}
mkdir -p "$PARTS"

# --halt now,fail=1: stop at the first failure; --resume-failed with --joblog reruns only
# the passes that failed (or never ran) when the script is started again.
parallel --jobs "$JOBS" --halt now,fail=1 --joblog "$PARTS/joblog" --resume-failed \
    mcrt render "$SCENE" --spp "$SPP" --threads "$THREADS" --quiet \
        --pass {}/"$N" -o "$PARTS/part-{}-of-$N.exr" \
    ::: $(seq 1 "$N")

mcrt merge "$PARTS"/part-*-of-"$N".exr -o image.exr --keep-sums "$PARTS/sums.exr"
echo "image.exr: $N passes of $SCENE at $SPP spp"
