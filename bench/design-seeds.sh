#!/usr/bin/env bash
# Repeats the fit of decks/thesis-design-fit.nml on data with other noise seeds: for each seed
# the three tests are regenerated (Table 4 + 1 % noise) and fitted by Levenberg-Marquardt
# started at Table 4 (the global minimum lies next to it; the multi-start run from the
# standard guess finds the same point for seed 1). Prints each constant's error against
# Table 4 (%) and whether the 95 % interval of the identifiability report contains Table 4.
# Usage: bench/design-seeds.sh [nseeds]   (about 30 s per seed on 2 cores)
set -euo pipefail
cd "$(dirname "$0")/.."
nseeds=${1:-10}
. scripts/release-flags.sh
fpm build --profile release --flag "$FLAGS" >/dev/null 2>&1
exe=$(fpm run --profile release --flag "$FLAGS" --runner 2>/dev/null | tail -n 1)
work=build/design-seeds
mkdir -p "$work"
printf '%-5s %8s %8s %8s %8s %8s %8s %8s  %7s %s\n' seed A1 A2 B C2 H1 H2 n 'max|e|' 'in 95% CI'
for s in $(seq 1 "$nseeds"); do
  d="$work/seed$s"
  mkdir -p "$d"
  sed -e "s/seed = 1\([123]\)/seed = $((s*10))\1/" -e "s|out_dir = '.'|out_dir = '$PWD/$d'|" \
      data/thesis-design/generate.nml > "$d/generate.nml"
  "$exe" simulate -q "$d/generate.nml"
  sed -e "s|'../data/thesis-design/|'$PWD/$d/|" -e 's/  multistart = 8, seed = 1.*//' \
      decks/thesis-design-fit.nml > "$d/fit.nml"
  "$exe" run -q "$d/fit.nml" -c data/thesis-design/generate.nml -o "$d/out" > "$d/summary.txt"
  awk -v seed="$s" '
    BEGIN { t["A1"]=0.8; t["A2"]=7.42e-5; t["B"]=1.0e15; t["C2"]=0.1; t["H1"]=280; t["H2"]=100; t["n"]=5.8 }
    /^  (A1|A2|B |C2|H1|H2|n )  .*\[/ {
      name=$1; v=$2; gsub(/[\[,]/, "", $3); gsub(/\]/, "", $4)
      e[name]=100*(v/t[name]-1); inci += ($3+0 <= t[name] && t[name] <= $4+0); nci++ }
    END { m=0; line=sprintf("%-5s", seed)
      split("A1 A2 B C2 H1 H2 n", k, " ")
      for (i=1;i<=7;i++) { line=line sprintf(" %8.3f", e[k[i]]); if (e[k[i]]>m) m=e[k[i]]; if (-e[k[i]]>m) m=-e[k[i]] }
      printf "%s  %7.3f %d/%d\n", line, m, inci, nci }' "$d/summary.txt"
  rm -f "$d"/*.sim.txt
done
