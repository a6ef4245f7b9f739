#!/usr/bin/env bash
# The full studies of docs/problems.md, 'Experiments', in the order their results are needed: the design
# studies of B1 and SW1 (the headline), the optimiser comparison (its GA runs with seed 0 reuse the design
# study's simulations through the shared run store), the other four design studies, the RL studies.
# Each command resumes from results/runs.sqlite, so this script can be killed and started again at any time;
# it takes days on two cores (docs/performance.md). Usage: experiments/full_studies.sh [OUT] [WORKERS]
set -euo pipefail
OUT="${1:-results}"
WORKERS="${2:-2}"
export OPENBLAS_NUM_THREADS=1
python -m experiments.design_studies --full --problems B1 SW1 --workers "$WORKERS" --out "$OUT"
python -m experiments.optimizer_comparison --full --workers "$WORKERS" --out "$OUT"
python -m experiments.design_studies --full --problems B2 SW2 B3 SW3 --workers "$WORKERS" --out "$OUT"
python -m experiments.rl_studies --full --workers "$WORKERS" --out "$OUT"
python -m catenary_env.cli report --out "$OUT"
