#!/bin/bash
# Bake a world as a Slurm job array: one task per shard, every task writing
# into one folder on a file system all nodes mount. Submit with
#   sbatch deploy/slurm/bake-array.sh
# then, once the array is done (or as a dependent job):
#   sbatch --dependency=afterany:JOBID --wrap "$VISTA bake $WORLD --verify $OUT"
# which names any shard to run again (`sbatch --array=I deploy/slurm/bake-array.sh`;
# a rerun keeps the nodes a killed task finished).
#SBATCH --job-name=vista-bake
#SBATCH --array=0-63
#SBATCH --cpus-per-task=16
#SBATCH --mem=8G
#SBATCH --time=06:00:00
#SBATCH --output=vista-bake-%A_%a.log
set -euo pipefail
VISTA=${VISTA:-vista}
WORLD="--extent 292000 --spacing 0.5"
OUT=${OUT:-/shared/vista/bake-292km}
# The shard count is the array's size (--array=0-63: 64); the task id is
# read from SLURM_ARRAY_TASK_ID.
export RAYON_NUM_THREADS=${SLURM_CPUS_PER_TASK:-1}
$VISTA bake $WORLD --yes --no-progress --out "$OUT" --shard auto/64
