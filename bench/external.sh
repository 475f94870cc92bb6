#!/usr/bin/env bash
# Thesis run 2 (decks/thesis-run2.nml) fitted twice, release build, one core: with the internal
# integrator, and through the external backend with test/ansys_standin.sh standing in for an
# ANSYS batch run (constants file at full precision). Prints objective, evaluations, wall time
# and the largest relative difference of the objective over all evaluations.
set -euo pipefail
cd "$(dirname "$0")/.."
. scripts/release-flags.sh
fpm build --profile release --flag "$FLAGS" >/dev/null 2>&1
exe=$(cd "$PWD" && realpath "$(fpm run --profile release --flag "$FLAGS" --runner 2>/dev/null | tail -n 1)")
tmp=$(mktemp -d)
root=$PWD
# The internal run's input, with absolute data paths; the external one adds the backend
sed -e "s|'../data/|'$root/data/|" decks/thesis-run2.nml > "$tmp/internal.nml"
sed -e "s|^  weighting = \(.*\)$|  weighting = \1\n  backend = 'external', constants_format = '(ES24.16)'\n  command = 'sh $root/test/ansys_standin.sh $exe $tmp/internal.nml {test}'|" \
  "$tmp/internal.nml" > "$tmp/external.nml"
printf '%-9s %14s %8s %10s %12s\n' backend objective evals "wall s" "ms/eval"
for b in internal external; do
  start=$(date +%s.%N)
  OMP_NUM_THREADS=1 "$exe" run "$tmp/$b.nml" -q -o "$tmp/$b" > "$tmp/$b.txt"
  end=$(date +%s.%N)
  evals=$(sed -n 's/.*evaluations \([0-9]*\) .*/\1/p' "$tmp/$b.txt")
  best=$(sed -n 's/.*best \([0-9.E+-]*\).*/\1/p' "$tmp/$b.txt")
  awk -v b="$b" -v f="$best" -v n="$evals" -v s="$start" -v e="$end" \
    'BEGIN { printf "%-9s %14s %8d %10.2f %12.2f\n", b, f, n, e - s, 1000 * (e - s) / n }'
done
paste "$tmp/internal/fit.journal" "$tmp/external/fit.journal" | awk -v n=5 '
  { nf = NF / 2; a = $3; b = $(nf + 3); d = (a > 0 ? (a > b ? a - b : b - a) / a : 0)
    if (d > m) { m = d; k = $1 } }
  END { printf "largest relative difference of the objective: %.2e (evaluation %d)\n", m, k }'
rm -rf "$tmp"
