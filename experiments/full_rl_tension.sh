#!/usr/bin/env bash
set -euo pipefail
# The full tension-conditioned RL study (docs/problems.md, 'Experiments', rl-tension): SAC, 3 seeds of 10,000
# steps on B1, speeds and contact-wire tensions drawn outside their held-out bands, and a GA run of 1000
# simulations at each of the table's five tensions at 300 km/h; about 35,000 simulations, some 4-5 h on two
# cores. Run it after experiments/full_rl_amortised.sh (both take both cores). It resumes from OUT/runs.sqlite
# (kill it and start it again at any time), and each run goes into the run archive OUT/rl/tension/archive as it
# finishes, with a snapshot every ten minutes while it runs: commit the archive as the study goes, and a fresh
# checkout resumes from it.
# Usage: experiments/full_rl_tension.sh [OUT]
OUT="${1:-results}"
mkdir -p "$OUT"
export OPENBLAS_NUM_THREADS=1 OMP_NUM_THREADS=1  # one core per process (the learners' torch too)
python -m experiments.rl_tension --full --envs 2 --workers 2 --out "$OUT" --store "$OUT/runs.sqlite" \
    --archive "$OUT/rl/tension/archive" > "$OUT/rl-tension.log" 2>&1
