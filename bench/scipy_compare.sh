#!/usr/bin/env bash
# The thesis's run 2 objective per evaluation (decks/thesis-run2.nml at its start constants):
# usharp (release, one core) against a scipy Radau script of the same model at the same
# accuracy, measured side by side (bench/scipy_compare.py; numpy and scipy needed): at the
# cheapest of its decade tolerances as accurate, and interpolated to exactly the same accuracy.
set -euo pipefail
cd "$(dirname "$0")/.."
. scripts/release-flags.sh
fpm build --profile release --flag "$FLAGS" >/dev/null 2>&1
exe=$(fpm run --profile release --flag "$FLAGS" --runner 2>/dev/null | tail -n 1)
tmp=$(mktemp -d)
"$exe" simulate decks/thesis-run2.nml -q -o "$tmp"
OMP_NUM_THREADS=1 fpm run --profile release --flag "$FLAGS" --example bench_measured -- \
  decks/thesis-run2.nml > "$tmp/usharp.txt" 2>/dev/null
ms=$(sed -n 's/.*ms per evaluation *//p' "$tmp/usharp.txt")
rhs=$(sed -n 's/.*rate evaluations *//p' "$tmp/usharp.txt")
python3 -W ignore bench/scipy_compare.py "$ms" "$tmp/lcf.sim.txt" "$tmp/relax.sim.txt" "$rhs"
rm -rf "$tmp"
