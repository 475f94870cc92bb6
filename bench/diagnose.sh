#!/usr/bin/env bash
# Cost of a full diagnosis (release build, 2 threads): wall time, processor time (user +
# system, every thread) and simulations of the test set, with the load average before and
# after, for the thesis matrix (LCF and relaxation fitted, ratcheting held out, 1 % noise
# data) and the Alloy 617 matrix at 950 C (five LCF tests fitted, two held out; needs
# ../shared/realdata). The simulations of each step are in the report, their times in
# <out>/diagnose/steps.csv (printed here).
# usage: bash bench/diagnose.sh [--specimen] [--selfcheck]
#   --specimen   also the Alloy 617 per-specimen diagnosis (each of the seven tests)
#   --selfcheck  also the whole self-check (clean data and each effect, 10 repetitions each; long)
# Times on a shared machine depend on its load: compare the processor times, or runs made
# one after another under the same load.
set -euo pipefail
cd "$(dirname "$0")/.."
export PATH="$HOME/.local/bin:$PATH"
. scripts/release-flags.sh
fpm build --profile release --flag "$FLAGS" >/dev/null 2>&1
exe=$(fpm run --profile release --flag "$FLAGS" --runner 2>/dev/null | tail -n 1)
tmp=$(mktemp -d)
threads=${OMP_NUM_THREADS:-2}
specimen=no
selfcheck=no
for a in "$@"; do
  case $a in
    --specimen) specimen=yes ;;
    --selfcheck) selfcheck=yes ;;
    *) echo "usage: bash bench/diagnose.sh [--specimen] [--selfcheck]" >&2; exit 2 ;;
  esac
done
load() { uptime | sed 's/.*load average: \([0-9.]*\).*/\1/'; }
one() {  # name: then the arguments of usharp diagnose (run in decks/)
  local name=$1 l0 l1
  shift
  l0=$(load)
  (cd decks && OMP_NUM_THREADS=$threads /usr/bin/time -f '%e %U %S' -o "$tmp/$name.time" \
     "../$exe" diagnose "$@" -o "$tmp/$name") > "$tmp/$name.txt"
  l1=$(load)
  # (a per-specimen diagnosis counts its replicates' fit and the specimen's simulations apart)
  sims=$(sed -n 's/^\([0-9]*\) simulations of the test set.*/\1/p
    s/^\([0-9]*\) simulations of the replicates (their fit), \([0-9]*\) of the specimen.*/\1+\2/p' \
    "$tmp/$name.txt" | paste -sd+ | bc)
  verdict=$(sed -n 's/^\*\*Verdict:\*\* //p' "$tmp/$name.txt" | head -n 1 | cut -c1-60)
  [ -n "$verdict" ] || verdict=$(sed -n 's/^\*\*Verdict\*\*: //p; s/^Verdict: //p' "$tmp/$name.txt" | head -n 1 | cut -c1-60)
  read -r wall user sys < "$tmp/$name.time"
  awk -v m="$name" -v w="$wall" -v u="$user" -v s="$sys" -v n="${sims:-?}" -v a="$l0" -v b="$l1" -v v="$verdict" \
    'BEGIN { printf "%-10s %8.1f %8.1f %8s  %5s %5s  %s\n", m, w, u + s, n, a, b, v }'
}
printf '%-10s %8s %8s %8s  %5s %5s  %s\n' matrix "wall s" "cpu s" sims load0 load1 verdict
one thesis thesis-diagnose.nml
if [ -d ../shared/realdata/a617-950C ]; then
  one a617 a617-950C-diagnose.nml
  [ $specimen = yes ] && one a617-spec a617-950C-specimen.nml
else
  echo "a617: skipped (../shared/realdata not found)"
fi
for f in "$tmp"/*/diagnose/steps.csv; do
  [ -f "$f" ] || continue
  echo
  echo "$(basename "$(dirname "$(dirname "$f")")"): steps (simulations, wall s, cpu s)"
  python3 -c 'import csv, sys
for r in csv.reader(open(sys.argv[1])): print("%-56s %11s %8s %8s" % tuple(r))' "$f"
done
if [ $selfcheck = yes ]; then
  l0=$(load)
  OMP_NUM_THREADS=$threads /usr/bin/time -f '%e %U %S' -o "$tmp/selfcheck.time" \
    "$exe" diagnose --selfcheck -o "$tmp/selfcheck" | sed -n '/^| injected/,/^correct/p'
  read -r wall user sys < "$tmp/selfcheck.time"
  awk -v w="$wall" -v u="$user" -v s="$sys" -v a="$l0" -v b="$(load)" \
    'BEGIN { printf "self-check: %.1f s wall, %.1f s cpu, load %s to %s\n", w, u + s, a, b }'
fi
echo "reports in $tmp"
