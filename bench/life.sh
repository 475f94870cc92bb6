#!/usr/bin/env bash
# Alloy 617 at 950 C over life: the fit of decks/a617-950C-life.nml (the seven LCF tests from
# cycle 1 to mid-life with every cycle's peak stresses, the three creep curves, the tensile
# test), started from the cycles 1-2 fit (decks/a617-950C-best.nml); its wall time, objective
# and per-test errors; the cycles 1-2 fit's prediction of the same data (usharp predict
# decks/a617-950C-predict.nml, the out-of-sample comparison); and, with gnuplot, the figure
# docs/figures/a617-950C-life.png (peak stresses against cycle, mid-life loops, creep and
# tension: measured, predicted from cycles 1-2, fitted over life). Needs ../shared/realdata.
# Usage: bash bench/life.sh [out_dir]   (default: a temporary folder, removed at the end)
set -euo pipefail
cd "$(dirname "$0")/.."
. scripts/release-flags.sh
if [ ! -d ../shared/realdata/a617-950C ]; then
  echo "measured data not found at ../shared/realdata/a617-950C" >&2
  exit 1
fi
fpm build --profile release --flag "$FLAGS" >/dev/null 2>&1
exe=$(fpm run --profile release --flag "$FLAGS" --runner 2>/dev/null | tail -n 1)
if [ $# -ge 1 ]; then out=$1; mkdir -p "$out"; keep=1; else out=$(mktemp -d); keep=0; fi

echo "== the cycles 1-2 fit (decks/a617-950C-best.nml) predicting the data over life"
start=$(date +%s.%N)
"$exe" predict decks/a617-950C-predict.nml -c decks/a617-950C-best.nml -o "$out/predict" \
  | sed -n '2,/errors in/p'
end=$(date +%s.%N)
awk -v s="$start" -v e="$end" 'BEGIN { printf "  wall time %.1f s\n", e - s }'

echo "== the whole-life fit (decks/a617-950C-life.nml)"
start=$(date +%s.%N)
OMP_NUM_THREADS=${OMP_NUM_THREADS:-2} "$exe" run decks/a617-950C-life.nml -q --force \
  -o "$out/fit" > "$out/run.txt"
end=$(date +%s.%N)
sed -n '1,3p' "$out/run.txt"
awk -v s="$start" -v e="$end" 'BEGIN { printf "  wall time %.1f s\n", e - s }'
"$exe" predict decks/a617-950C-life.nml -c "$out/fit/best.nml" -o "$out/life" \
  | sed -n '2,/errors in/p'
sed -n '/^&constants/,/^\//p' "$out/fit/best.nml"

if command -v gnuplot >/dev/null; then
  # The last recorded piece of each LCF test (its mid-life loop): the rows of <test>.fit.txt
  # after the last gap in time (a step longer than 50 median steps)
  python3 - "$out/predict" "$out/life" <<'PY'
import glob, sys
import numpy as np
for d in sys.argv[1:]:
    for f in glob.glob(d + '/*pct*.fit.txt'):
        rows = [l for l in open(f) if not l.startswith('#')]
        t = np.array([float(l.split()[0]) for l in rows])
        dt = np.diff(t)
        gaps = np.nonzero(dt > 50 * np.median(dt[dt > 0]))[0]
        last = gaps[-1] + 1 if len(gaps) else 0
        open(f[:-len('.fit.txt')] + '.mid.txt', 'w').writelines(rows[last:])
PY
  plots=""
  for f in "$out"/life/*pct*.peaks.txt; do
    name=$(basename "$f" .peaks.txt)
    p="$out/predict/$name.peaks.txt"
    plots="$plots set title '$name: peak stresses'; set logscale x; set xlabel 'cycle'; set ylabel 'stress (MPa)';
      plot '$f' u 1:5 w p pt 7 ps 0.2 lc rgb 'gray60' t 'measured', '$p' u 1:6 w p pt 7 ps 0.2 lc rgb '#2060c0' t 'cycles 1-2 fit', '$f' u 1:6 w p pt 7 ps 0.2 lc rgb '#c0392b' t 'life fit'; unset logscale x;"
  done
  for f in "$out"/life/*pct*.mid.txt; do
    name=$(basename "$f" .mid.txt)
    p="$out/predict/$name.mid.txt"
    plots="$plots set title '$name: mid-life loop'; set xlabel 'strain (%)'; set ylabel 'stress (MPa)';
      plot '$f' u (100*\$2):3 w p pt 7 ps 0.2 lc rgb 'gray60' t 'measured', '$p' u (100*\$2):4 w l lw 1.2 lc rgb '#2060c0' t 'cycles 1-2 fit', '$f' u (100*\$2):4 w l lw 1.2 lc rgb '#c0392b' t 'life fit';"
  done
  f="$out/life/D11-tensile-1e-4.fit.txt"
  p="$out/predict/D11-tensile-1e-4.fit.txt"
  plots="$plots set title 'D11: tension 1e-4/s'; set xlabel 'strain (%)'; set ylabel 'stress (MPa)'; set yrange [0:300];
    plot '$f' u (100*\$2):3 w l lw 2 lc rgb 'gray60' t 'measured', '$p' u (100*\$2):(\$1 <= 2610 ? \$4 : 1/0) w l lw 1.2 lc rgb '#2060c0' t 'cycles 1-2 fit', '$f' u (100*\$2):4 w l lw 1.2 lc rgb '#c0392b' t 'life fit'; set autoscale y;"
  for s in 19 24 29; do
    f="$out/life/creep-${s}MPa.fit.txt"
    p="$out/predict/creep-${s}MPa.fit.txt"
    plots="$plots set title 'creep ${s} MPa'; set xlabel 'time (days)'; set ylabel 'strain (%)';
      plot '$p' u (\$1/86400):(100*\$3) w l lw 2 lc rgb 'gray60' t 'measured', '' u (\$1/86400):(100*\$4) w l lw 1.2 lc rgb '#2060c0' t 'cycles 1-2 fit', '$f' u (\$1/86400):(100*\$4) w l lw 1.2 lc rgb '#c0392b' t 'life fit';"
  done
  gnuplot -e "set term pngcairo size 1800,1500 font ',9' noenhanced; set output 'docs/figures/a617-950C-life.png';
    set multiplot layout 5,4 title 'Alloy 617 at 950 C over life: measured (grey), the cycles 1-2 fit (blue), the whole-life fit (red)';
    set key top left; set grid; $plots unset multiplot"
  echo "figure: docs/figures/a617-950C-life.png"
fi
if [ "$keep" = 0 ]; then rm -rf "$out"; fi
