#!/usr/bin/env bash
# What --resume costs: Levenberg-Marquardt from 8 Latin-hypercube starts (thesis run 2,
# decks/thesis-run2-multistart.nml), release build, one core. The uninterrupted run, then
# the run killed once its journal holds 10 %, 50 % and 90 % of its evaluations (the
# share it holds when the kill lands is printed) and resumed: evaluations replayed and
# simulated, wall time of the resumed run against the whole run, and whether it ends with
# the same journal and constants.
set -euo pipefail
cd "$(dirname "$0")/.."
. scripts/release-flags.sh
fpm build --profile release --flag "$FLAGS" >/dev/null 2>&1
exe=$(fpm run --profile release --flag "$FLAGS" --runner 2>/dev/null | tail -n 1)
deck=decks/thesis-run2-multistart.nml
tmp=$(mktemp -d)
trap 'rm -rf "$tmp"' EXIT
secs() { date +%s.%N; }
start=$(secs)
OMP_NUM_THREADS=1 "$exe" run -q "$deck" -o "$tmp/full" > "$tmp/full.txt"
wall=$(awk -v s="$start" -v e="$(secs)" 'BEGIN { print e - s }')
total=$(sed -n 's/.*evaluations \([0-9]*\) .*/\1/p' "$tmp/full.txt")
# records: the evaluations in a journal (its other lines begin with #)
records() { { grep -v '^#' "$1" 2>/dev/null || true; } | wc -l; }
printf '%-9s %8s %9s %9s %10s %8s %9s\n' stopped evals replayed simulated "wall s" "% time" identical
printf '%-9s %8d %9d %9d %10.2f %8.1f %9s\n' never "$total" 0 "$total" "$wall" 100 -
for p in 10 50 90; do
  # The run killed (-9) once its journal holds p % of the evaluations: its journal and
  # fit.cache as a kill leaves them (the cache holds the start under way)
  k=$(( total * p / 100 ))
  d="$tmp/at$p"
  OMP_NUM_THREADS=1 "$exe" run -q "$deck" -o "$d" > /dev/null 2>&1 & pid=$!
  while [ "$(records "$d/fit.journal")" -lt "$k" ] && kill -0 $pid 2>/dev/null; do sleep 0.002; done
  kill -9 $pid 2>/dev/null || true
  wait $pid 2>/dev/null || true
  kept=$(records "$d/fit.journal")
  start=$(secs)
  OMP_NUM_THREADS=1 "$exe" run -q --resume "$deck" -o "$d" > "$d.txt"
  w=$(awk -v s="$start" -v e="$(secs)" 'BEGIN { print e - s }')
  line=$(sed -n 's/.*evaluations \([0-9]*\) (\([0-9]*\) replayed, \([0-9]*\) simulated).*/\1 \2 \3/p' "$d.txt")
  same=no
  if cmp -s "$d/fit.journal" "$tmp/full/fit.journal" && \
     diff -q <(sed 1,2d "$d/best.nml") <(sed 1,2d "$tmp/full/best.nml") >/dev/null; then same=yes; fi
  read -r ev rep sim <<< "$line"
  printf '%-9s %8d %9d %9d %10.2f %8.1f %9s\n' "$(( 100 * kept / total )) %" "$ev" "$rep" "$sim" "$w" \
    "$(awk -v a="$w" -v b="$wall" 'BEGIN { print 100 * a / b }')" "$same"
done
