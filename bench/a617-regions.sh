#!/usr/bin/env bash
# Regions of the Alloy 617 residual (decks/a617-950C-diagnose.nml at its constants) as the
# diagnosis classes them, with the loops coloured by region: docs/figures/a617-regions.png
# (stress against strain, one panel per test; grey elastic, colours the inelastic points by
# history class) and the region tables on stdout. Needs ../shared/realdata and gnuplot.
set -euo pipefail
cd "$(dirname "$0")/.."
. scripts/release-flags.sh
if [ ! -d ../shared/realdata/a617-950C ]; then
  echo "skipped: ../shared/realdata/a617-950C not found"; exit 0
fi
fpm build --profile release --flag "$FLAGS" >/dev/null 2>&1
exe=$(fpm run --profile release --flag "$FLAGS" --example bench_regions --runner 2>/dev/null | tail -n 1)
tmp=$(mktemp -d)
(cd decks && OMP_NUM_THREADS=${OMP_NUM_THREADS:-1} "../$exe" a617-950C-diagnose.nml "$tmp")
mkdir -p docs/figures
tests=$(awk -F, 'NR > 1 { print $1 }' "$tmp/points.csv" | uniq)
n=$(echo "$tests" | wc -l)
{
  echo "set terminal pngcairo size 1500,$((420 * ((n + 2) / 3))) font ',9'"
  echo "set output 'docs/figures/a617-regions.png'"
  echo "set datafile separator ','"
  echo "set multiplot layout $(((n + 2) / 3)),3"
  echo "set xlabel 'strain (%)'; set ylabel 'stress (MPa)'; set key top left font ',8'"
  for t in $tests; do
    echo "set title '$t'"
    echo "plot '$tmp/points.csv' using (strcol(1) eq '$t' && strcol(8) eq 'no' ? 100*\$3 : 1/0):4 w p pt 7 ps 0.35 lc rgb '#b0b0b0' t 'elastic', \\"
    echo "  '' using (strcol(1) eq '$t' && strcol(8) eq 'yes' && strcol(6) eq 'loading' ? 100*\$3 : 1/0):4 w p pt 7 ps 0.35 lc rgb '#d03030' t 'inelastic loading', \\"
    echo "  '' using (strcol(1) eq '$t' && strcol(8) eq 'yes' && strcol(6) eq 'unloading' ? 100*\$3 : 1/0):4 w p pt 7 ps 0.35 lc rgb '#3060d0' t 'inelastic unloading', \\"
    echo "  '' using (strcol(1) eq '$t' && strcol(8) eq 'yes' && strcol(6) eq 'reversal' ? 100*\$3 : 1/0):4 w p pt 7 ps 0.35 lc rgb '#30a040' t 'inelastic reversal', \\"
    echo "  '' using (strcol(1) eq '$t' && strcol(6) eq 'hold' ? 100*\$3 : 1/0):4 w p pt 7 ps 0.5 lc rgb 'black' t 'hold', \\"
    echo "  '' using (strcol(1) eq '$t' ? 100*\$3 : 1/0):5 w l lc rgb '#404040' dt 2 t 'model'"
  done
  echo "unset multiplot"
} > "$tmp/plot.gp"
gnuplot "$tmp/plot.gp"
echo
echo "figure: docs/figures/a617-regions.png; points: $tmp/points.csv"
