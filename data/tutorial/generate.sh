#!/usr/bin/env bash
# Regenerates the tutorial's CSV files: simulates data/tutorial/generate.nml (release build)
# and keeps time, strain and stress of each test as a CSV file with a header row.
# Usage: bash data/tutorial/generate.sh
set -euo pipefail
cd "$(dirname "$0")/../.."
. scripts/release-flags.sh
fpm build --profile release --flag "$FLAGS" >/dev/null 2>&1
exe=$(fpm run --profile release --flag "$FLAGS" --runner 2>/dev/null | tail -n 1)
tmp=$(mktemp -d)
trap 'rm -rf "$tmp"' EXIT
"$exe" simulate -q -o "$tmp" data/tutorial/generate.nml
for t in cyclic-fast cyclic-slow; do
  awk -v t="$t" 'BEGIN { print "# synthetic test " t ": Table 4 constants (MPa), 1 % stress noise; made by data/tutorial/generate.sh"
                         print "time,strain,stress" }
       !/^#/ { printf "%.3f,%.6e,%.3f\n", $1, $2, $3 }' "$tmp/$t.sim.txt" > "data/tutorial/$t.csv.tmp"
  mv "data/tutorial/$t.csv.tmp" "data/tutorial/$t.csv"
  echo "wrote data/tutorial/$t.csv"
done
