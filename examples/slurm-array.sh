#!/usr/bin/env bash
# A fragility sweep as a Slurm job array: one array task per manifest line, no server.
#
#   sbatch --array=0-$(( $(grep -c . examples/sweep-manifest.jsonl) - 1 ))%64 examples/slurm-array.sh
#   # when the array has finished (or as a dependent job: sbatch --dependency=afterok:JOBID …):
#   ashlar sweep --collect results --with-manifest examples/sweep-manifest.jsonl
#
# Each task runs line $SLURM_ARRAY_TASK_ID (read by `ashlar sweep` itself) into
# results/NNNNNN/ (summary.json, histories.csv, line.json). A line's directory appears only
# when the line is complete, so a failed or preempted task can simply be resubmitted
# (sbatch --array=17,42 …); `--collect` names any line still missing.
#SBATCH --job-name=ashlar-sweep
#SBATCH --cpus-per-task=1
#SBATCH --mem=1G
#SBATCH --time=00:30:00
#SBATCH --output=logs/ashlar-%A_%a.out
set -euo pipefail
MANIFEST="${MANIFEST:-examples/sweep-manifest.jsonl}"
OUT="${OUT:-results}"
# One DDA run is single-threaded: keep BLAS/rayon from oversubscribing the allocated core.
export RAYON_NUM_THREADS="${SLURM_CPUS_PER_TASK:-1}"
srun ashlar sweep "$MANIFEST" --out "$OUT" --no-trajectory
