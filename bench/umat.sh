#!/usr/bin/env bash
# Stress-update calls per second and time per thesis test on the umat path (release, one core).
set -euo pipefail
cd "$(dirname "$0")/.."
. scripts/release-flags.sh
OMP_NUM_THREADS=1 fpm run --profile release --flag "$FLAGS" --example bench_umat 2>/dev/null
