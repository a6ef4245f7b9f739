#!/usr/bin/env bash
set -euo pipefail
# The full studies of docs/problems.md, 'Experiments': the six design studies (B1 and SW1 first, the
# headline), then the optimiser benchmark's full protocol in two lanes (experiments/full_protocol.sh, which
# keeps its runs in the committed run archive OUT/full-protocol/archive), then the RL studies of B1 and SW1 in
# two lanes, each a single process on one core (PPO steps its environment in one process), and once more
# over both problems, which takes every run from the store (nothing is simulated again) and writes their
# combined results; last, the two-pantograph and the tolerance studies (they read the design studies'
# optima), and the report. The lanes write their partial tables into OUT/lanes (scratch, not committed).
# The amortised RL studies have scripts of their own (experiments/full_rl_amortised.sh, some 23 h, then
# experiments/full_rl_tension.sh, some 5 h).
# Each command resumes from OUT/runs.sqlite, so this script can be killed and started again at any time;
# it takes about 35 hours on two cores (docs/performance.md, 'The full studies' and 'The full protocol of the
# optimiser benchmark').
# Usage: experiments/full_studies.sh [OUT] [WORKERS]
OUT="${1:-results}"
WORKERS="${2:-2}"
STORE="$OUT/runs.sqlite"
mkdir -p "$OUT"
export OPENBLAS_NUM_THREADS=1 OMP_NUM_THREADS=1  # one core per process (PPO's torch too)
python -m experiments.design_studies --full --problems B1 SW1 --workers "$WORKERS" --out "$OUT"
python -m experiments.design_studies --full --problems B2 SW2 B3 SW3 --workers "$WORKERS" --out "$OUT"

# The optimiser benchmark's full protocol, two lanes, and its combined results in OUT/full-protocol.
"$(dirname "$0")/full_protocol.sh" "$OUT"

study() {  # study LANE NAME ARGS...: one study in full on one core, its partial tables in the lane's scratch
    python -m "experiments.$2" --full "${@:3}" --workers 1 --store "$STORE" --out "$OUT/lanes/$1"
}
study 1 rl_studies --problems B1 > "$OUT/rl-lane-1.log" 2>&1 &
one=$!
study 2 rl_studies --problems SW1 > "$OUT/rl-lane-2.log" 2>&1 &
two=$!
status=0
wait "$one" || status=1
wait "$two" || status=1
[ "$status" -eq 0 ] || { echo "a lane failed: see $OUT/rl-lane-1.log and $OUT/rl-lane-2.log" >&2; exit 1; }
python -m experiments.rl_studies --full --workers "$WORKERS" --out "$OUT"
# Two pantographs: the design studies' optima behind a leader, and the GA for the worse pantograph.
python -m experiments.pantographs --full --designs "$OUT" --workers "$WORKERS" --out "$OUT"
# Installation tolerances, the design studies under buildability limits and the robust GA (docs/acceptance.md).
python -m experiments.tolerance --full --workers "$WORKERS" --out "$OUT"
python -m catenary_env.cli report --out "$OUT"
