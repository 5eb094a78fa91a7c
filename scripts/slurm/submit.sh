#!/usr/bin/env bash
# Submits a job array and the job that merges its results, which runs only if every task
# succeeded (--dependency=afterok). Prints the two job ids.
#
#   SCENE=cornell-box SPP=16384 SHARDS=16 OUT=/shared/ref scripts/slurm/submit.sh reference
#   SCENE=cornell-box PASSES=2000 SHARDS=8 OUT=/shared/r scripts/slurm/submit.sh render
#   SCENE=cornell-box SHOTS=/shared/shots OUT=/shared/anim scripts/slurm/submit.sh animation
#   SWEEP=/shared/sweep.txt OUT=/shared/sweep scripts/slurm/submit.sh sweep
#
# Every variable the .sbatch scripts read is passed on (sbatch --export=ALL); PPM names the
# ppm binary on the nodes. Extra arguments go to both sbatch calls (--partition=..., ...).
set -euo pipefail
here=$(cd "$(dirname "$0")" && pwd)
kind=${1:?usage: submit.sh reference|render|animation|sweep [sbatch options]}
shift
: "${OUT:?set OUT, a folder every node sees}"
mkdir -p "$OUT/logs"
case $kind in
  reference | render) tasks=${SHARDS:?set SHARDS}; array=$here/$kind.sbatch; after=$here/merge.sbatch ;;
  animation) tasks=$(ls "${SHOTS:?set SHOTS}"/shot-*.toml | wc -l); array=$here/animate.sbatch; after=$here/join.sbatch; export KIND=animation ;;
  sweep) tasks=$(grep -c . "${SWEEP:?set SWEEP}"); array=$here/sweep.sbatch; after=$here/join.sbatch; export KIND=sweep ;;
  *) echo "submit.sh: $kind: reference, render, animation or sweep" >&2; exit 1 ;;
esac
((tasks > 0)) || { echo "submit.sh: nothing to run" >&2; exit 1; }
array_id=$(sbatch --parsable --export=ALL --output "$OUT/logs/%x-%A_%a.log" \
  --array="0-$((tasks - 1))" "$@" "$array")
merge_id=$(sbatch --parsable --export=ALL --output "$OUT/logs/%x-%j.log" \
  --dependency="afterok:${array_id%%;*}" "$@" "$after")
echo "$array_id $merge_id"
