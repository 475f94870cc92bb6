#!/usr/bin/env bash
# Wall time of a full diagnosis (release build, 2 threads): the thesis matrix (LCF and
# relaxation fitted, ratcheting held out, 1 % noise data) and the Alloy 617 matrix at 950 C
# (five LCF tests fitted, two held out; needs ../shared/realdata). With --selfcheck also the
# whole self-check (9 rows x 10 repetitions; about 20 minutes).
set -euo pipefail
cd "$(dirname "$0")/.."
FLAGS="-I/usr/include/sundials/fortran"
fpm build --profile release --flag "$FLAGS" >/dev/null 2>&1
exe=$(fpm run --profile release --flag "$FLAGS" --runner 2>/dev/null | tail -n 1)
tmp=$(mktemp -d)
threads=${OMP_NUM_THREADS:-2}
one() {  # name deck
  start=$(date +%s.%N)
  (cd decks && OMP_NUM_THREADS=$threads "../$exe" diagnose "$2" -o "$tmp/$1") > "$tmp/$1.txt"
  end=$(date +%s.%N)
  sims=$(sed -n 's/^\([0-9]*\) simulations of the test set.*/\1/p' "$tmp/$1.txt")
  verdict=$(sed -n 's/^\*\*Verdict:\*\* //p' "$tmp/$1.txt" | cut -c1-70)
  awk -v m="$1" -v s="$start" -v e="$end" -v n="$sims" -v v="$verdict" \
    'BEGIN { printf "%-10s %8.1f %8s  %s\n", m, e - s, n, v }'
}
printf '%-10s %8s %8s  %s\n' matrix "wall s" sims verdict
one thesis thesis-diagnose.nml
if [ -d ../shared/realdata/a617-950C ]; then
  one a617 a617-950C-diagnose.nml
else
  echo "a617: skipped (../shared/realdata not found)"
fi
if [ "${1:-}" = "--selfcheck" ]; then
  start=$(date +%s.%N)
  OMP_NUM_THREADS=$threads "$exe" diagnose --selfcheck -o "$tmp/selfcheck" | sed -n '/^| injected/,/^correct/p'
  end=$(date +%s.%N)
  awk -v s="$start" -v e="$end" 'BEGIN { printf "self-check: %.1f s\n", e - s }'
fi
echo "reports in $tmp"
