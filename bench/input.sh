#!/usr/bin/env bash
# Time to read an input file of 1,000 and of 10,000 &test groups, and their ratio (linear
# reading gives about 10). `usharp simulate --test t1` reads and checks every group, builds
# every history, then simulates only the first (tiny) test.
# Usage: bench/input.sh [usharp executable]   (default: the release build)
set -euo pipefail
cd "$(dirname "$0")/.."
. scripts/release-flags.sh
exe=${1:-}
if [ -z "$exe" ]; then
   fpm build --profile release --flag "$FLAGS" >/dev/null 2>&1
   exe=$(fpm run --profile release --flag "$FLAGS" --runner 2>/dev/null | tail -n 1)
fi
work=$(mktemp -d)
trap 'rm -rf "$work"' EXIT
deck() {  # deck with $1 &test groups
   {
      echo "&model temperature = 866.15, tm = 1800.0, youngs = 22.5e3 /"
      echo "&constants a1 = 0.8, a2 = 7.42e-5, b = 1.0e15, c2 = 0.1, h1 = 280.0, h2 = 100.0,"
      echo "  n = 5.8, q = 91000.0 /"
      for ((i = 1; i <= $1; i++)); do
         echo "&test name = 't$i', history = 'tensile', strain_rate = 1.0e-4, final_strain = 0.0002,"
         echo "  dt_out = 0.5 /"
      done
   } >"$work/n$1.nml"
}
seconds() {  # wall time of reading deck n$1.nml
   local t0 t1
   t0=$(date +%s.%N)
   "$exe" simulate "$work/n$1.nml" --test t1 -o "$work/out$1" >/dev/null
   t1=$(date +%s.%N)
   awk -v a="$t0" -v b="$t1" 'BEGIN { printf "%.3f", b - a }'
}
deck 1000
deck 10000
t1k=$(seconds 1000)
t10k=$(seconds 10000)
printf 'groups    read time (s)\n'
printf '%6d    %8.3f\n' 1000 "$t1k" 10000 "$t10k"
awk -v a="$t1k" -v b="$t10k" 'BEGIN { printf "ratio 10000/1000: %.1f (linear: 10, quadratic: 100)\n", b / a }'
