#!/usr/bin/env bash
# Cost and accuracy of the residual Jacobian by forward differences and by CVODES forward
# sensitivities (thesis LCF + relaxation, seven constants; release build, one thread)
set -euo pipefail
cd "$(dirname "$0")/.."
. scripts/release-flags.sh
OMP_NUM_THREADS=1 fpm run --profile release --flag "$FLAGS" --example bench_jacobian 2>/dev/null
