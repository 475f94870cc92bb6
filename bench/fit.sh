#!/usr/bin/env bash
# Wall time of the thesis fits (runs 1-3) and objective evaluations per second, release build,
# one core. Each run writes to a temporary folder.
set -euo pipefail
cd "$(dirname "$0")/.."
FLAGS="-I/usr/include/sundials/fortran"
fpm build --profile release --flag "$FLAGS" >/dev/null 2>&1
exe=$(fpm run --profile release --flag "$FLAGS" --runner 2>/dev/null | tail -n 1)
tmp=$(mktemp -d)
printf '%-6s %12s %10s %12s %10s\n' run objective evals "wall s" "evals/s"
for r in 1 2 3; do
  start=$(date +%s.%N)
  OMP_NUM_THREADS=1 "$exe" run "decks/thesis-run$r.nml" -q -o "$tmp/run$r" > "$tmp/run$r.txt"
  end=$(date +%s.%N)
  evals=$(sed -n 's/.*evaluations \([0-9]*\) .*/\1/p' "$tmp/run$r.txt")
  best=$(sed -n 's/.*best \([0-9.E+-]*\).*/\1/p' "$tmp/run$r.txt")
  awk -v r="$r" -v b="$best" -v n="$evals" -v s="$start" -v e="$end" \
    'BEGIN { printf "%-6s %12s %10d %12.2f %10.0f\n", "run" r, b, n, e - s, n / (e - s) }'
done
rm -rf "$tmp"
