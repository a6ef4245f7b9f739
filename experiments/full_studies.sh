#!/usr/bin/env bash
# The full studies of docs/problems.md, 'Experiments': the six design studies (B1 and SW1 first, the
# headline), then the optimiser comparison and the RL studies in two lanes, one per problem, each on one
# core (PPO steps its environment in one process, so a lane per problem keeps both cores busy), then
# both studies once more over both problems, which replays every run from the store (nothing is simulated
# again) and writes their combined results, and the report.
# Each command resumes from OUT/runs.sqlite, so this script can be killed and started again at any time;
# it takes days on two cores (docs/performance.md). Usage: experiments/full_studies.sh [OUT] [WORKERS]
set -euo pipefail
OUT="${1:-results}"
WORKERS="${2:-2}"
export OPENBLAS_NUM_THREADS=1
python -m experiments.design_studies --full --problems B1 SW1 --workers "$WORKERS" --out "$OUT"
python -m experiments.design_studies --full --problems B2 SW2 B3 SW3 --workers "$WORKERS" --out "$OUT"

lane() {
    python -m experiments.optimizer_comparison --full --problems "$1" --workers 1 --out "$OUT"
    python -m experiments.rl_studies --full --problems "$1" --workers 1 --out "$OUT"
}
lane B1 > "$OUT/lane-B1.log" 2>&1 &
b1=$!
lane SW1 > "$OUT/lane-SW1.log" 2>&1 &
sw1=$!
status=0
wait "$b1" || status=1
wait "$sw1" || status=1
[ "$status" -eq 0 ] || { echo "a lane failed: see $OUT/lane-B1.log and $OUT/lane-SW1.log" >&2; exit 1; }

python -m experiments.optimizer_comparison --full --workers "$WORKERS" --out "$OUT"
python -m experiments.rl_studies --full --workers "$WORKERS" --out "$OUT"
python -m catenary_env.cli report --out "$OUT"
