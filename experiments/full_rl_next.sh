#!/usr/bin/env bash
set -euo pipefail
# The two amortised RL studies one after the other (both take both cores): experiments/full_rl_amortised.sh
# (speed-conditioned PPO and SAC on B1 and SW1), then experiments/full_rl_tension.sh (SAC conditioned on the
# contact-wire tension as well, on B1). Each resumes from OUT/runs.sqlite and its run archive, so this script
# can be killed and started again at any time; the first part's logs are OUT/rl-amortised-*.log, the second's
# OUT/rl-tension.log.
# Usage: experiments/full_rl_next.sh [OUT]
OUT="${1:-results}"
here="$(dirname "$0")"
"$here/full_rl_amortised.sh" "$OUT"
"$here/full_rl_tension.sh" "$OUT"
