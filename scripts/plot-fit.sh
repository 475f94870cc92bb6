#!/usr/bin/env bash
# Plots of a fit against its data with gnuplot: for every <test>.fit.txt in the output folder
# of `usharp run`, the response against strain (measured and fitted), and one overview of all
# tests, and each test's peak stresses against cycle where it has them (<test>.peaks.txt).
# Writes <out_dir>/plots/<test>.png, <test>.peaks.png and all.png.
# Usage: scripts/plot-fit.sh <out_dir> [title]
#
# No name reaches gnuplot as code: every path and the title enter the gnuplot script as
# single-quoted gnuplot strings (in which only '' is special, for a quote), paths begin with
# / or ./ (a gnuplot file name beginning with < or | would run a command), and names with a
# line break are refused.
set -euo pipefail
dir=${1:?usage: scripts/plot-fit.sh <out_dir> [title]}
title=${2:-$(basename -- "$dir")}
command -v gnuplot >/dev/null 2>&1 || { echo "plot-fit: gnuplot is not installed (bash scripts/setup.sh installs it)" >&2; exit 1; }
nl='
'
case "$dir$title" in *"$nl"*) echo "plot-fit: a folder name or title with a line break is not supported" >&2; exit 1 ;; esac
case "$dir" in /*) ;; *) dir="./$dir" ;; esac

# A text as a gnuplot single-quoted string
gq() { printf "'%s'" "$(printf '%s' "$1" | sed "s/'/''/g")"; }

shopt -s nullglob
files=("$dir"/*.fit.txt)
[ ${#files[@]} -gt 0 ] || { echo "plot-fit: no *.fit.txt in $dir" >&2; exit 1; }
# A run started again in its folder (--force) with fewer tests leaves the files of the tests it
# no longer has: where the run's summary.txt names its tests ("  test <name>: ..."), only those
# are plotted (test names hold only letters, digits, _ - .)
if [ -f "$dir/summary.txt" ]; then
  tests=$(sed -n 's/^  test \([A-Za-z0-9_.-]*\): .*/\1/p' "$dir/summary.txt")
  if [ -n "$tests" ]; then
    kept=()
    for f in "${files[@]}"; do
      name=$(basename -- "$f" .fit.txt)
      if printf '%s\n' "$tests" | grep -qxF -- "$name"; then
        kept+=("$f")
      else
        echo "plot-fit: $f left out: not a test of the run in $dir/summary.txt" >&2
      fi
    done
    files=("${kept[@]}")
    [ ${#files[@]} -gt 0 ] || { echo "plot-fit: none of the *.fit.txt in $dir is a test of its summary.txt" >&2; exit 1; }
  fi
fi
mkdir -p -- "$dir/plots"
tmp=$(mktemp -d)
trap 'rm -rf -- "$tmp"' EXIT
# The loops of a test as gnuplot draws them: its data points only (a test with a peak file
# also has a row at each compared turning point, which a line through the loops would join
# across them), with a blank line where the time jumps by more than 50 median steps (the
# unrecorded cycles between recorded ones: no line across them)
loops() { # loops FIT_FILE OUT_FILE
  local peaks=${1%.fit.txt}.peaks.txt med
  awk -v pf="$peaks" '
    BEGIN { while ((getline line < pf) > 0) if (line !~ /^#/) { split(line, c, " "); skip[c[3] + 0] = 1 } }
    /^#/ { next }
    !(($1 + 0) in skip) { print }' "$1" > "$2.rows"
  med=$(awk 'NR > 1 { print $1 - t } { t = $1 }' "$2.rows" | sort -g | awk '{ d[NR] = $1 } END { if (NR) print d[int((NR + 1) / 2)]; else print 0 }')
  { grep '^#' "$1" || true
    awk -v med="$med" 'NR > 1 && med > 0 && $1 - t > 50 * med { print "" } { print; t = $1 }' "$2.rows"; } > "$2"
}
# The columns' line says whether the test is fitted on stress (stress against strain) or on
# strain (a creep test: strain against time)
axes() { # axes FILE UNIT: the gnuplot labels and the using of the measured and fitted columns
  if grep -q '^# time strain strain_exp strain_sim' -- "$1"; then
    echo "set xlabel 'time (h)'; set ylabel 'strain (%)'"
    echo 'm = "($1/3600):(100*$3)"; s = "($1/3600):(100*$4)"'
  else
    echo "set xlabel 'strain (%)'; set ylabel 'stress ($2)'"
    echo 'm = "(100*$2):3"; s = "(100*$2):4"'
  fi
}
for f in "${files[@]}"; do
  name=$(basename -- "$f" .fit.txt)
  unit=$(sed -n 's/.*stress (\([A-Za-z]*\)) of the simulation.*/\1/p' "$f" | head -1)
  loops "$f" "$tmp/$name.txt"
  {
    echo 'set terminal pngcairo size 800,600 font ",11" noenhanced'
    echo "set output $(gq "$dir/plots/$name.png")"
    echo "set title $(gq "$title: $name")"
    axes "$f" "${unit:-model unit}"
    echo 'set key top left'
    echo 'set grid'
    echo "f = $(gq "$tmp/$name.txt")"
    echo 'plot f using @m with points pt 7 ps 0.3 lc rgb "#888888" title "measured", \'
    echo '     f using @s with lines lw 2 lc rgb "#c0392b" title "fit"'
  } | gnuplot
  # Every cycle's peak stresses (target peaks or both): measured and simulated against cycle
  p=${f%.fit.txt}.peaks.txt
  if [ -f "$p" ]; then
    # maxima and minima apart, each a line through its cycles
    awk '!/^#/ && $2 > 0' "$p" > "$tmp/$name.max.txt"
    awk '!/^#/ && $2 < 0' "$p" > "$tmp/$name.min.txt"
    {
      echo 'set terminal pngcairo size 800,600 font ",11" noenhanced'
      echo "set output $(gq "$dir/plots/$name.peaks.png")"
      echo "set title $(gq "$title: $name, peak stresses")"
      echo "set xlabel 'cycle'; set ylabel 'stress (${unit:-model unit})'"
      echo 'set logscale x; set key bottom left; set grid'
      echo "a = $(gq "$tmp/$name.max.txt"); b = $(gq "$tmp/$name.min.txt")"
      echo 'plot a using 1:5 with points pt 7 ps 0.3 lc rgb "#888888" title "measured", \'
      echo '     b using 1:5 with points pt 7 ps 0.3 lc rgb "#888888" notitle, \'
      echo '     a using 1:6 with lines lw 2 lc rgb "#c0392b" title "fit", \'
      echo '     b using 1:6 with lines lw 2 lc rgb "#c0392b" notitle'
    } | gnuplot
  fi
done
n=${#files[@]}
cols=$(( n < 3 ? n : 3 ))
rows=$(( (n + cols - 1) / cols ))
{
  echo "set terminal pngcairo size $((420*cols)),$((330*rows)) font \",9\" noenhanced"
  echo "set output $(gq "$dir/plots/all.png")"
  echo "set multiplot layout $rows,$cols title $(gq "$title")"
  echo "set grid; set key top left"
  for f in "${files[@]}"; do
    name=$(basename -- "$f" .fit.txt)
    unit=$(sed -n 's/.*stress (\([A-Za-z]*\)) of the simulation.*/\1/p' "$f" | head -1)
    echo "set title $(gq "$name")"
    axes "$f" "${unit:-model unit}"
    echo "f = $(gq "$tmp/$name.txt")"
    echo "plot f using @m with points pt 7 ps 0.2 lc rgb '#888888' title 'measured', f using @s with lines lw 2 lc rgb '#c0392b' title 'fit'"
  done
  echo "unset multiplot"
} | gnuplot
echo "wrote $dir/plots/*.png"
