#!/usr/bin/env bash
# Simulating under a measured strain: one objective evaluation of the seven Alloy 617 tests
# (decks/a617-950C-fit.nml, cycles 1-2, at the constants of decks/a617-950C-best.nml) with the
# measured strain as smooth forcing and through every sample, against one of the thesis's
# three tests (decks/thesis-run3.nml), in the same run; each test's stress against a
# tight-tolerance reference under the same forcing, at those constants and at the deck's own
# (start) constants; and, with gnuplot, the loops of both into
# docs/figures/a617-950C-forcing.png. Needs ../shared/realdata beside the project.
set -euo pipefail
cd "$(dirname "$0")/.."
. scripts/release-flags.sh
if [ ! -d ../shared/realdata/a617-950C ]; then
  echo "measured data not found at ../shared/realdata/a617-950C" >&2
  exit 1
fi
out=$(mktemp -d)
OMP_NUM_THREADS=1 fpm run --profile release --flag "$FLAGS" --example bench_measured -- \
  decks/thesis-run3.nml decks/a617-950C-fit.nml decks/a617-950C-best.nml "$out" 2>/dev/null
if command -v gnuplot >/dev/null; then
  plots=""
  for f in "$out"/*.forcing.txt; do
    name=$(basename "$f" .forcing.txt)
    plots="$plots set title '$name'; plot '$f' u (100*\$2):4 w p pt 7 ps 0.25 lc rgb 'gray60' t 'measured', '' u (100*\$2):5 w l lw 1.2 lc rgb '#c0392b' t 'every sample', '' u (100*\$3):6 w l lw 1.2 lc rgb '#2060c0' t 'smooth forcing';"
  done
  gnuplot -e "set term pngcairo size 1260,990 font ',9'; set output 'docs/figures/a617-950C-forcing.png';
    set multiplot layout 3,3 title 'Alloy 617 at 950 C: simulated under the measured strain'; set key top left;
    set xlabel 'strain (%)'; set ylabel 'stress (MPa)'; set grid; $plots unset multiplot"
  echo "figure: docs/figures/a617-950C-forcing.png"
fi
rm -rf "$out"
