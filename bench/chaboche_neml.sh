#!/usr/bin/env bash
# Uniaxial Chaboche response against NEML (an independent implementation) on the same
# constants and strain histories; prints the largest difference per history / peak stress.
# Needs: pip install neml. Optional: 13 constants (order of the model's names) as arguments.
set -euo pipefail
cd "$(dirname "$0")/.."
. scripts/release-flags.sh
out=$(mktemp)
trap 'rm -f "$out"' EXIT
fpm run --profile release --flag "$FLAGS" --example bench_chaboche \
  -- "$@" 2>/dev/null | grep -E "^(# (constants|values|history)| *-?[0-9])" >"$out"
python3 bench/chaboche_neml.py "$out"
