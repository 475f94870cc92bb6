#!/usr/bin/env bash
# OpenMP threads and wait policy: wall time of a fit (default the thesis run-2 multi-start fit, LM, 8 starts,
# Jacobian columns in parallel) with 1 and 2 threads, spinning (active) and passive waiting,
# measured one after another in one run, alone and beside a busy process on every core.
# usage: bash bench/threads.sh [deck]   (release build; default decks/thesis-run2-multistart.nml)
set -euo pipefail
cd "$(dirname "$0")/.."
. scripts/release-flags.sh
export PATH="$HOME/.local/bin:$PATH"
fpm build --profile release --flag "$FLAGS" > /dev/null
exe=$(fpm run --profile release --flag "$FLAGS" --runner echo 2>/dev/null | tail -n 1)
deck=${1:-decks/thesis-run2-multistart.nml}
out=$(mktemp -d)
trap 'rm -rf "$out"; [ -n "${load_pids:-}" ] && kill $load_pids 2>/dev/null; true' EXIT
run() { # threads policy
  local s e d
  d=$(mktemp -d "$out/run.XXXX")  # run is called in a subshell: a counter would not advance
  s=$(date +%s.%N)
  OMP_NUM_THREADS=$1 OMP_WAIT_POLICY=$2 "$exe" run -q --force -o "$d" "$deck" > /dev/null
  e=$(date +%s.%N)
  echo "$e - $s" | bc
}
table() {
  local t11 t1p t2a t2p
  t1p=$(run 1 passive); t11=$(run 1 active); t2a=$(run 2 active); t2p=$(run 2 passive)
  printf '%-22s %8.2f %8.2f %8.2f %8.2f   %s\n' "$1" "$t1p" "$t11" "$t2a" "$t2p" \
    "2 active / 2 passive = $(echo "scale=2; $t2a / $t2p" | bc)"
}
printf '%-22s %8s %8s %8s %8s\n' "wall s ($deck)" "1 pass" "1 act" "2 act" "2 pass"
table "alone"
load_pids=""
for _ in $(seq "$(nproc)"); do (while :; do :; done) & load_pids="$load_pids $!"; done
table "beside $(nproc) busy"
