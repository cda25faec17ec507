#!/usr/bin/env bash
# A shelfcross campaign as a Slurm job array, no MPI needed: task I of N runs shard I/N
# (the runs k with k % N == I) into OUT/shard-I, then a merge job, started once every task
# succeeded, combines the shards into OUT/campaign (results.sqlite, summary.json, report.md)
# with the campaign hash a single process would give.
#
#   scripts/slurm_campaign.sh --shards N --runs R --out DIR [--seed S] [--scenario FILE]
#                             [--jobs J] [--time HH:MM:SS] [-- extra sbatch options]
#
# Run it on a login node, from a checkout on a file system every node sees (the program, the
# scenario and DIR must be reachable from the compute nodes). Each task uses J cores (default 4).
# Submitting the same command again resumes: every shard runs only its missing runs.
set -euo pipefail
here="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)"
program="${SHELFCROSS:-$here/build/release/app/shelfcross}"

if [ -n "${SLURM_ARRAY_TASK_ID:-}" ] && [ -n "${SHELFCROSS_SHARDS:-}" ]; then
  # One task of the array (sbatch runs this same script).
  exec "$program" campaign --scenario "$SHELFCROSS_SCENARIO" --runs "$SHELFCROSS_RUNS" --seed "$SHELFCROSS_SEED" \
    --jobs "${SLURM_CPUS_PER_TASK:-1}" --shard "$SLURM_ARRAY_TASK_ID/$SHELFCROSS_SHARDS" \
    --out "$SHELFCROSS_OUT/shard-$SLURM_ARRAY_TASK_ID"
fi

shards="" runs="" out="" seed=1 scenario="$here/scenarios/paper_test_shelf.yaml" jobs=4 time_limit="24:00:00"
while [ $# -gt 0 ]; do
  case "$1" in
    --shards) shards="$2"; shift 2 ;;
    --runs) runs="$2"; shift 2 ;;
    --out) out="$2"; shift 2 ;;
    --seed) seed="$2"; shift 2 ;;
    --scenario) scenario="$2"; shift 2 ;;
    --jobs) jobs="$2"; shift 2 ;;
    --time) time_limit="$2"; shift 2 ;;
    --) shift; break ;;
    *) echo "slurm_campaign.sh: unknown option $1" >&2; exit 2 ;;
  esac
done
if [ -z "$shards" ] || [ -z "$runs" ] || [ -z "$out" ]; then
  sed -n '7,9p' "$0" >&2
  exit 2
fi
out="$(realpath -m "$out")"
scenario="$(realpath "$scenario")"
mkdir -p "$out/logs"

export SHELFCROSS_SHARDS="$shards" SHELFCROSS_RUNS="$runs" SHELFCROSS_SEED="$seed" \
  SHELFCROSS_SCENARIO="$scenario" SHELFCROSS_OUT="$out"
array_job=$(sbatch --parsable --job-name=shelfcross-campaign --array="0-$((shards - 1))" \
  --cpus-per-task="$jobs" --time="$time_limit" --output="$out/logs/shard-%a.log" --export=ALL "$@" "$0")
array_job="${array_job%%;*}"
shard_dirs=""
for ((i = 0; i < shards; i++)); do shard_dirs+=" $out/shard-$i"; done
merge_job=$(sbatch --parsable --job-name=shelfcross-merge --dependency="afterok:$array_job" \
  --time=01:00:00 --output="$out/logs/merge.log" "$@" \
  --wrap="'$program' merge$shard_dirs --out '$out/campaign'")
echo "submitted array job $array_job ($shards shards of $runs runs) and merge job $merge_job"
echo "results: $out/campaign/report.md once the merge job has run; logs in $out/logs"
