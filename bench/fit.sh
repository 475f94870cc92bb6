#!/usr/bin/env bash
# Wall time of the thesis fits (runs 1-3) and objective evaluations per second, release build,
# one core; then the Alloy 617 fit (if its data are present). Each run writes to a temporary
# folder.
set -euo pipefail
cd "$(dirname "$0")/.."
. scripts/release-flags.sh
fpm build --profile release --flag "$FLAGS" >/dev/null 2>&1
exe=$(fpm run --profile release --flag "$FLAGS" --runner 2>/dev/null | tail -n 1)
tmp=$(mktemp -d)
printf '%-6s %12s %10s %12s %10s\n' run objective evals "wall s" "evals/s"
for r in 1 2 3; do
  start=$(date +%s.%N)
  OMP_NUM_THREADS=1 "$exe" run "decks/thesis-run$r.nml" -q -o "$tmp/run$r" > "$tmp/run$r.txt"
  end=$(date +%s.%N)
  evals=$(sed -n 's/.*evaluations \([0-9]*\) .*/\1/p' "$tmp/run$r.txt")
  best=$(sed -n 's/.*best \([0-9.E+-]*\).*/\1/p' "$tmp/run$r.txt")
  awk -v r="$r" -v b="$best" -v n="$evals" -v s="$start" -v e="$end" \
    'BEGIN { printf "%-6s %12s %10d %12.2f %10.0f\n", "run" r, b, n, e - s, n / (e - s) }'
done
# The Alloy 617 fit (decks/a617-950C-fit.nml: 7 measured-strain tests, LM from 8 starts, the
# default threads), when the measured data lie beside the project: wall and CPU time, with
# the load average (the machine may be shared)
if [ -d ../shared/realdata/a617-950C ]; then
  load0=$(cut -d' ' -f1 /proc/loadavg)
  start=$(date +%s.%N)
  TIMEFORMAT='%U %S'
  # (the program's own messages apart from the times)
  { time "$exe" run decks/a617-950C-fit.nml -q -o "$tmp/a617" > "$tmp/a617.txt" 2> "$tmp/a617.err" ; } \
    2> "$tmp/a617.time"
  end=$(date +%s.%N)
  evals=$(sed -n 's/.*evaluations \([0-9]*\) .*/\1/p' "$tmp/a617.txt" | tail -n 1)
  best=$(sed -n 's/.*best \([0-9.E+-]*\).*/\1/p' "$tmp/a617.txt" | tail -n 1)
  awk -v b="$best" -v n="$evals" -v s="$start" -v e="$end" -v c="$(tail -n 1 "$tmp/a617.time")" \
    -v l0="$load0" -v l1="$(cut -d' ' -f1 /proc/loadavg)" 'BEGIN { split(c, t, " ");
    printf "%-6s %12s %10d %12.2f %10.0f   CPU %.1f s, load average %s to %s\n", "a617", b, n, e - s,
    n / (e - s), t[1] + t[2], l0, l1 }'
fi
rm -rf "$tmp"
