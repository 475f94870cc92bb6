#!/usr/bin/env bash
# Wall time per thesis-test simulation (release build, one core) and the solver's work counts.
set -euo pipefail
cd "$(dirname "$0")/.."
. scripts/release-flags.sh
OMP_NUM_THREADS=1 fpm run --profile release --flag "$FLAGS" --example bench_simulate 2>/dev/null
