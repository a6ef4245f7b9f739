#!/usr/bin/env bash
set -euo pipefail
# The full studies of docs/problems.md, 'Experiments': the six design studies (B1 and SW1 first, the
# headline), then the optimiser comparison (six problems) and the RL studies of B1 and SW1 in two lanes, each a single
# process on one core (PPO steps its environment in one process), then both studies once more over both
# problems, which takes every run from the store (nothing is simulated again) and writes their combined
# results, and the report. A simulation of SW1 costs about 1.5 times one of B1 (and B1's comparison meets
# more designs that fail the static check, which cost no dynamics), so the lanes split SW1's comparison by
# optimiser: each lane finishes its share of the comparison, the headline, at about the same time, then
# runs the RL studies of one problem. Last, the two-pantograph and the tolerance studies (they read the design
# studies' optima). The amortised RL study has a script of its own (experiments/full_rl_amortised.sh, 20 h).
# Each command resumes from OUT/runs.sqlite, so this script can be killed and started again at any time;
# it takes about 35 hours on two cores (docs/performance.md, 'The full studies' and 'The full protocol of the
# optimiser benchmark'). The lanes write their partial tables into OUT/lanes (scratch, not committed): only the
# combined runs at the end write OUT/full-protocol and OUT/rl. Every run of the comparison that finishes is
# kept at once in the run archive OUT/full-protocol/archive (one file a run, docs/problems.md, 'Experiments'),
# which a fresh checkout restores into its store before it goes on: commit the archive as the lanes go.
# While the lanes run, `python -m experiments.optimizer_comparison --full --from-store --store
# "$OUT/runs.sqlite" --out "$OUT/full-protocol"` writes the comparison's results so far from the store (the
# finished runs; the others "not run yet"), simulating nothing.
# Usage: experiments/full_studies.sh [OUT] [WORKERS]
OUT="${1:-results}"
WORKERS="${2:-2}"
STORE="$OUT/runs.sqlite"
ARCHIVE="$OUT/full-protocol/archive"
mkdir -p "$OUT"
export OPENBLAS_NUM_THREADS=1 OMP_NUM_THREADS=1  # one core per process (PPO's torch too)
python -m experiments.design_studies --full --problems B1 SW1 --workers "$WORKERS" --out "$OUT"
python -m experiments.design_studies --full --problems B2 SW2 B3 SW3 --workers "$WORKERS" --out "$OUT"

study() {  # study LANE NAME ARGS...: one study in full on one core, its partial tables in the lane's scratch
    python -m "experiments.$2" --full "${@:3}" --workers 1 --store "$STORE" --out "$OUT/lanes/$1"
}
{  # the comparison's full protocol (docs/performance.md, 'The full protocol of the optimiser benchmark')
    study 1 optimizer_comparison --problems B1 B2 B3 --archive "$ARCHIVE"
    study 1 optimizer_comparison --problems SW1 SW2 SW3 --optimizers gp ppo --archive "$ARCHIVE"
    study 1 rl_studies --problems B1
} > "$OUT/lane-1.log" 2>&1 &
one=$!
{
    study 2 optimizer_comparison --problems SW1 SW2 SW3 --optimizers ga cma de pso random ngopt tpe --archive "$ARCHIVE"
    study 2 rl_studies --problems SW1
} > "$OUT/lane-2.log" 2>&1 &
two=$!
status=0
wait "$one" || status=1
wait "$two" || status=1
[ "$status" -eq 0 ] || { echo "a lane failed: see $OUT/lane-1.log and $OUT/lane-2.log" >&2; exit 1; }

# the six problems, every run replayed from the store
python -m experiments.optimizer_comparison --full --workers "$WORKERS" --store "$STORE" --archive "$ARCHIVE" \
    --out "$OUT/full-protocol"
python -m experiments.rl_studies --full --workers "$WORKERS" --out "$OUT"
# Two pantographs: the design studies' optima behind a leader, and the GA for the worse pantograph.
python -m experiments.pantographs --full --designs "$OUT" --workers "$WORKERS" --out "$OUT"
# Installation tolerances, the design studies under buildability limits and the robust GA (docs/acceptance.md).
python -m experiments.tolerance --full --workers "$WORKERS" --out "$OUT"
python -m catenary_env.cli report --out "$OUT"
