#!/usr/bin/env bash
# Thesis run 2 (LCF + relaxation from the standard guess) with each optimiser, release build:
# evaluations, simulations (2 per evaluation), wall time, best objective, and the evaluation at
# which the objective first reaches Hooke-Jeeves's end value (from the first row). Then the OpenMP
# speed-up of the Levenberg-Marquardt fit on 2 threads, and multi-start from the box.
set -euo pipefail
cd "$(dirname "$0")/.."
. scripts/release-flags.sh
fpm build --profile release --flag "$FLAGS" >/dev/null 2>&1
exe=$(fpm run --profile release --flag "$FLAGS" --runner 2>/dev/null | tail -n 1)
tmp=$(mktemp -d)
hj=1e300   # set from the Hooke-Jeeves row
run() {  # name threads extra-&fit-settings
  # A folder per row: the same method on 2 threads is a run of its own
  local out="$tmp/$1-$2"
  sed -e "s/method = 'hooke-jeeves'/$3/" decks/thesis-run2.nml > "decks/.bench-$1.nml"
  start=$(date +%s.%N)
  OMP_NUM_THREADS=$2 "$exe" run "decks/.bench-$1.nml" -q -o "$out" > "$out.txt"
  end=$(date +%s.%N)
  rm -f "decks/.bench-$1.nml"
  evals=$(sed -n 's/.*evaluations \([0-9]*\) .*/\1/p' "$out.txt")
  best=$(sed -n 's/.*, best \([0-9.E+-]*\).*/\1/p' "$out.txt")
  if [ "$1" = hooke-jeeves ]; then hj=$best; fi
  first=$(awk -v t="$hj" '$1 + 0 <= t + 0 { print NR; exit }' "$out/FOM.TXT")
  awk -v m="$1" -v p="$2" -v b="$best" -v n="$evals" -v s="$start" -v e="$end" -v f="${first:--}" \
    'BEGIN { printf "%-22s %3d %12s %7d %7d %9.2f %10s\n", m, p, b, n, 2 * n, e - s, f }'
}
printf '%-22s %3s %12s %7s %7s %9s %10s\n' method thr objective evals sims "wall s" "first<=HJ"
run hooke-jeeves 1 "method = 'hooke-jeeves'"
run lm 1 "method = 'lm'"
run lm 2 "method = 'lm'"
run nelder-mead 1 "method = 'nelder-mead', max_evals = 5000"
run anneal 1 "method = 'anneal', max_evals = 20000"
run lm-multistart-8 1 "method = 'lm', multistart = 8"
run lm-multistart-8 2 "method = 'lm', multistart = 8"
rm -rf "$tmp"
