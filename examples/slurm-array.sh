#!/bin/bash
# Render one image on N nodes with a Slurm job array, then merge the parts.
#
#   sbatch examples/slurm-array.sh scenes/cornell-box.toml
#
# Task i (0-based) renders pass i+1 of N; the merge job runs once every task has succeeded
# (submit it with the dependency shown at the bottom, or run the merge line by hand).
#SBATCH --job-name=mcrt-pass
#SBATCH --array=0-15
#SBATCH --cpus-per-task=32
#SBATCH --time=04:00:00
#SBATCH --output=mcrt-pass-%A_%a.log
set -euo pipefail

SCENE=${1:?usage: sbatch slurm-array.sh SCENE}
SPP=${SPP:-4096}
SEED=${SEED:-0}
N=${SLURM_ARRAY_TASK_COUNT:-16}      # keep equal to the size of --array
PARTS=${PARTS:-parts}                  # a directory every node can write (shared file system)
K=$((SLURM_ARRAY_TASK_ID + 1))

mkdir -p "$PARTS"
mcrt render "$SCENE" --spp "$SPP" --seed "$SEED" --threads "${SLURM_CPUS_PER_TASK:-1}" \
    --pass "$K/$N" -o "$PARTS/part-$K-of-$N.exr" --quiet

# The merge step, once all tasks are done:
#   sbatch --dependency=afterok:$SLURM_ARRAY_JOB_ID --wrap \
#       "mcrt merge $PARTS/part-*-of-$N.exr -o image.exr --keep-sums sums.exr"
# or, from the submitting shell:
#   jid=$(sbatch --parsable examples/slurm-array.sh scene.toml)
#   sbatch --dependency=afterok:$jid --wrap "mcrt merge parts/part-*-of-16.exr -o image.exr"
