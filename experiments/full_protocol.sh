#!/usr/bin/env bash
set -euo pipefail
# The optimiser benchmark's full protocol (docs/problems.md, 'Reading the comparison'; its cost in
# docs/performance.md, 'The full protocol of the optimiser benchmark') in two lanes, each a single process on
# one core, then the combined results of the six problems in OUT/full-protocol.
# Every run goes into the run store OUT/runs.sqlite and, as it finishes, into the run archive
# OUT/full-protocol/archive (with a snapshot every ten minutes while it runs): commit the archive as the lanes
# go. Started again, here or on a fresh checkout, each lane restores the archive into the store, reads back the
# runs that finished and resumes the others, so the script can be killed and started again at any time.
# The lanes split the work by the hour (docs/performance.md): lane 1 the runs of B1-B3 (a Gaussian-process run
# some 8 min, most of it its model fits), then the Gaussian-process runs of SW1-SW3; lane 2 the other seven
# optimisers on SW1-SW3 (some 3.5 min a run), then SW1's PPO runs. Each lane then goes over the whole
# protocol (lane 2 from its other end) and makes the runs nobody has started: a lane makes only the runs it
# holds (a lock beside the store, RunStore.claim), so none is made twice and neither core idles while the
# other lane has runs left. The lanes' own tables go to OUT/lanes (scratch, not committed).
# While the lanes run, `python -m experiments.optimizer_comparison --full --from-store --store
# OUT/runs.sqlite --archive OUT/full-protocol/archive --out OUT/full-protocol` writes the results so far and
# a snapshot of each run in flight, simulating nothing.
# Usage: experiments/full_protocol.sh [OUT]
OUT="${1:-results}"
mkdir -p "$OUT"
export OPENBLAS_NUM_THREADS=1 OMP_NUM_THREADS=1  # one core per process (PPO's torch too)

comparison() {  # comparison RESULTS ARGS...
    python -m experiments.optimizer_comparison --full --workers 1 --store "$OUT/runs.sqlite" \
        --archive "$OUT/full-protocol/archive" --out "$1" "${@:2}"
}
{
    comparison "$OUT/lanes/1" --problems B1 B2 B3
    comparison "$OUT/lanes/1" --problems SW1 SW2 SW3 --optimizers gp
    comparison "$OUT/lanes/1"  # what nobody has started yet
} > "$OUT/lane-1.log" 2>&1 &
one=$!
{
    comparison "$OUT/lanes/2" --problems SW1 SW2 SW3 --optimizers ga cma de pso random ngopt tpe
    comparison "$OUT/lanes/2" --problems SW1 --optimizers ppo
    comparison "$OUT/lanes/2" --problems SW3 SW2 SW1 B3 B2 B1  # the same, from the other end
} > "$OUT/lane-2.log" 2>&1 &
two=$!
status=0
wait "$one" || status=1
wait "$two" || status=1
[ "$status" -eq 0 ] || { echo "a lane failed: see $OUT/lane-1.log and $OUT/lane-2.log" >&2; exit 1; }
comparison "$OUT/full-protocol"  # the six problems, every run read back from the store
