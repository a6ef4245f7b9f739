#!/usr/bin/env bash
set -euo pipefail
# The two amortised RL studies (rl-amortised, then rl-tension) on a machine of many cores: LANES processes of
# each study over one run store, each making the runs that no other has made or is making (--lane; docs/
# problems.md, 'Experiments'), then the study once more over the whole store for its tables (it replays every
# run). A run steps two envs (a GA run two workers), so a lane takes two cores: LANES defaults to half the
# cores. These are the runs of experiments/full_rl_next.sh, so either script resumes what the other made; kill
# it and start it again at any time: each lane restores the run archives into OUT/runs.sqlite and resumes
# from there, and a run stopped by SIGTERM writes a last snapshot into its archive first (commit the archives
# as the study goes). Logs: OUT/rl-lane-<study>-<i>.log for the lanes, OUT/rl-amortised.log and
# OUT/rl-tension.log for the tables.
# Usage: experiments/full_rl_lanes.sh [OUT] [LANES]
OUT="${1:-results}"
cores="$(nproc)"
LANES="${2:-$((cores > 3 ? cores / 2 : 1))}"
[[ "$LANES" =~ ^[1-9][0-9]*$ ]] || { echo "LANES must be a whole number >= 1, not $LANES" >&2; exit 2; }
mkdir -p "$OUT"
export OPENBLAS_NUM_THREADS=1 OMP_NUM_THREADS=1  # one core per process (the learners' torch too)

study() {  # study MODULE ARCHIVE LOG ARGS...
    python -m "experiments.$1" --full --envs 2 --workers 2 --store "$OUT/runs.sqlite" --archive "$2" \
        "${@:4}" > "$3" 2>&1
}
lanes() {  # lanes MODULE ARCHIVE NAME: LANES lanes of the study, then its tables
    local pids=() status=0
    for i in $(seq "$LANES"); do
        study "$1" "$2" "$OUT/rl-lane-$3-$i.log" --out "$OUT/lanes/$i" --lane &
        pids+=("$!")
    done
    for pid in "${pids[@]}"; do wait "$pid" || status=1; done
    [ "$status" -eq 0 ] || { echo "a lane of $3 failed: see $OUT/rl-lane-$3-*.log" >&2; exit 1; }
    study "$1" "$2" "$OUT/$3.log" --out "$OUT"
}
lanes rl_amortised "$OUT/rl/amortised/archive" rl-amortised
lanes rl_tension "$OUT/rl/tension/archive" rl-tension
