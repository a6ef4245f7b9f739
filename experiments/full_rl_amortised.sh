#!/usr/bin/env bash
set -euo pipefail
# The full amortised-RL study (docs/problems.md, 'Experiments', rl-amortised): PPO and SAC, 3 seeds of 10,000
# steps each, on B1 and SW1, trained outside the held-out speed bands, and a GA run of 1000 simulations at each
# of the table's five speeds; about 130,000 simulations, 20-22 h on two cores (docs/performance.md, 'The full
# studies').
# MODE "vector" (default): one problem after the other, each run stepping two envs in worker processes (both
# cores), the GA on two workers. MODE "lanes": one lane per core, B1 in one and SW1 in the other, each a single
# process stepping one env (another run than with two envs: a PPO rollout is n_steps x envs steps).
# Either way, every command resumes from OUT/runs.sqlite: the script can be killed and started again at any
# time, with the same MODE. Each run goes into the run archive OUT/rl/amortised/archive as it finishes, with a
# snapshot every ten minutes while it runs (docs/problems.md, 'Experiments'): commit the archive as the study
# goes, and a fresh checkout resumes from it. The per-problem commands write their partial tables into
# OUT/lanes (scratch, not committed); the last command replays every run from the store and writes the
# combined results under OUT/rl/amortised.
# Usage: experiments/full_rl_amortised.sh [OUT] [vector|lanes]
OUT="${1:-results}"
MODE="${2:-vector}"
mkdir -p "$OUT"
export OPENBLAS_NUM_THREADS=1 OMP_NUM_THREADS=1  # one core per process (the learners' torch too)

study() {  # study RESULTS ENVS WORKERS ARGS...
    python -m experiments.rl_amortised --full --envs "$2" --workers "$3" --out "$1" --store "$OUT/runs.sqlite" \
        --archive "$OUT/rl/amortised/archive" "${@:4}"
}
case "$MODE" in
vector)
    study "$OUT/lanes/1" 2 2 --problems B1 > "$OUT/rl-amortised-B1.log" 2>&1
    study "$OUT/lanes/2" 2 2 --problems SW1 > "$OUT/rl-amortised-SW1.log" 2>&1
    study "$OUT" 2 2
    ;;
lanes)
    study "$OUT/lanes/1" 1 1 --problems B1 > "$OUT/rl-amortised-B1.log" 2>&1 &
    one=$!
    study "$OUT/lanes/2" 1 1 --problems SW1 > "$OUT/rl-amortised-SW1.log" 2>&1 &
    two=$!
    status=0
    wait "$one" || status=1
    wait "$two" || status=1
    [ "$status" -eq 0 ] || { echo "a lane failed: see $OUT/rl-amortised-*.log" >&2; exit 1; }
    study "$OUT" 1 2
    ;;
*)
    echo "MODE must be vector or lanes, not $MODE" >&2
    exit 2
    ;;
esac
