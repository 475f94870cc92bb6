#!/usr/bin/env bash
# The fault catalogue of docs/guide/faults.md: tries every bad input and fault listed below on
# the usharp executable and prints, per case, the exit code and the first line usharp wrote to
# stderr (or the line named), as a Markdown table. A case whose stderr holds a backtrace or a
# Fortran runtime error, or that exits 0 where a result is missing, is marked "FAULT".
# Usage: bash scripts/faults.sh [USHARP]   (default: the release build, built if needed)
# Runs in a temporary folder; the 64 KiB tmpfs cases need root (else they say "not run").
set -uo pipefail
root=$(cd "$(dirname "$0")/.." && pwd)
if [ $# -ge 1 ]; then
  exe=$(realpath "$1")
else
  . "$root/scripts/release-flags.sh"
  (cd "$root" && fpm build --profile release --flag "$FLAGS" >/dev/null 2>&1)
  exe=$(cd "$root" && realpath "$(fpm run --profile release --flag "$FLAGS" --runner 2>/dev/null | tail -n 1)")
fi
tmp=$(mktemp -d)
cleanup() { umount "$tmp/tiny" "$tmp/rofs" 2>/dev/null; rm -rf "$tmp"; }
trap cleanup EXIT
cd "$tmp"
cp "$root/data/thesis/lcf.sim.txt" lcf.txt
cp "$root/data/thesis/relax.sim.txt" relax.txt
standin="$root/test/ansys_standin.sh"

model="&model name='miller', units='ksi', temperature=866.15, tm=1800.0, youngs=22.5e3 /"
consts="&constants a1=0.8, a2=7.42e-5, b=1e15, c2=0.1, h1=200, h2=100, n=5.0, q=91000 /"
fitg="&fit fitted='H1','n', rho=0.5, eps=1e-4, max_evals=8, identify=.false. /"
lcf="&test name='lcf', history='thesis_lcf', data_file='lcf.txt', weighting='threshold', sig=14 /"
# A fit input: fit.nml with optional replacements of the &fit and &test lines
mk() { # mk FILE [FIT] [TEST...]
  local f=$1; shift
  local fit=${1:-$fitg}; [ $# -gt 0 ] && shift
  { echo "$model"; echo "$consts"; echo "$fit"
    if [ $# -gt 0 ]; then printf '%s\n' "$@"; else echo "$lcf"; fi; } > "$f"
}
mk fit.nml

n=0
printf '| # | fault | exit | what usharp says |\n|---|---|---|---|\n'
# put DESCRIPTION EXIT MESSAGE: one row
put() {
  n=$((n + 1))
  local msg=${3//$tmp\//}
  msg=${msg//$root\//}
  [ -z "${long:-}" ] || msg=$(printf '%s' "${msg//$long/<the 300-character name>}" | sed -E 's/d{40,}/d...d/g')
  msg=${msg//|/\\|}
  printf '| %d | %s | %s | `%s`%s |\n' "$n" "$1" "$2" "${msg:0:170}" "${4:-}"
}
# row DESCRIPTION RESULT_FILE_OR_- COMMAND...: runs the command line, prints its row
row() {
  local what=$1 result=$2; shift 2
  "$@" > out.txt 2> err.txt
  local rc=$?
  local msg flag=''
  msg=$(grep '^usharp' err.txt | head -1)
  [ -n "$msg" ] || msg=$(grep -v '^ *$' err.txt | grep -v '^usage:' | head -1)
  [ -n "$msg" ] || msg=$(grep -v '^ *$' out.txt | head -1)
  if grep -q -e 'Backtrace' -e 'runtime error' -e 'Segmentation' err.txt; then flag=' **FAULT: backtrace**'; fi
  if grep -q 'runtime warning' err.txt; then flag=" (and: $(grep -m1 'runtime warning' err.txt))"; fi
  if [ "$rc" = 0 ] && [ "$result" != - ] && [ ! -s "$result" ]; then flag=' **FAULT: exit 0, no result**'; fi
  put "$what" "$rc" "$msg" "$flag"
}
# journal_at DIR N: wait (at most 30 s) until DIR/fit.journal has N lines
journal_at() {
  local k=0
  while [ "$({ wc -l < "$1/fit.journal"; } 2>/dev/null || echo 0)" -lt "$2" ] && [ $k -lt 3000 ]; do
    sleep 0.01; k=$((k + 1))
  done
}
u() { "$exe" "$@"; }

# --- command line
row 'no arguments' - u
row 'unknown command' - u frobnicate fit.nml
row 'misspelt option' - u run --resum fit.nml
row 'option of another command' - u simulate --resume fit.nml
row 'option without its value' - u run fit.nml -o
row 'two input files' - u run fit.nml fit.nml
row 'no input file' - u run
row '`--resume` and `--force` together' - u run --resume --force fit.nml -o both

# --- the input file
row 'input file missing' - u simulate none.nml
mkdir adir.nml
row 'input is a folder' - u simulate adir.nml
: > empty.nml
row 'empty input file' - u simulate empty.nml
{ echo "$model"; echo "$consts"; echo "&tset name='lcf', history='thesis_lcf' /"; } > tset.nml
row 'unknown group `&tset`' - u simulate tset.nml
{ echo "&model name='miller', units='ksi', temperature=866.15, tm=1800.0, yungs=22.5e3 /"; echo "$consts"; echo "$lcf"; } > misspelt.nml
row 'misspelt variable in `&model`' - u simulate misspelt.nml
{ echo "&model name='miller', units='ksi', temperature=866.15, tm=1800.0, youngs='abc' /"; echo "$consts"; echo "$lcf"; } > text.nml
row 'text where a number belongs' - u simulate text.nml
{ echo "$model"; echo "$consts"; echo "&test name='lcf', history='thesis_lcf', data_file='lcf.txt', npeaks=99999999999 /"; } > huge.nml
row 'a whole number too large' - u simulate huge.nml
{ echo "&model name='miller, units='ksi', temperature=866.15, tm=1800.0, youngs=22.5e3 ! the thesis's"; echo "/"; echo "$consts"; echo "$lcf"; } > quotes.nml
row 'quotes that do not pair up on a line' - u simulate quotes.nml
{ echo "&model name='miller', units='ksi', temperature=866.15"; echo "  tm 1800.0, youngs=22.5e3 /"; echo "$consts"; echo "$lcf"; } > noeq.nml
row "a name without '=' after a value" - u simulate noeq.nml
{ echo "&model name='miller', units='ksi', temperature=866.15, tm=1800.0, youngs=22.5e3"; echo "  = 0.3 /"; echo "$consts"; echo "$lcf"; } > noname.nml
row "an '=' without a name before it" - u simulate noname.nml
{ echo "&model name='miller', units='ksi', temperature=866.15"; echo "  tm: 1800.0, youngs=22.5e3 /"; echo "$consts"; echo "$lcf"; } > colon.nml
row "'name: value' (YAML, INI) for 'name = value'" - u simulate colon.nml
{ echo "&model name='miller', units='ksi', temperature=866.15, &"; echo "  tm=1800.0, youngs=22.5e3 /"; echo "$consts"; echo "$lcf"; } > amp.nml
row "a '&' continuing a line, as in Fortran source" - u simulate amp.nml
{ echo "&model name='miller', units=ksi, temperature=866.15, tm=1800.0, youngs=22.5e3 /"; echo "$consts"; echo "$lcf"; } > unquoted.nml
row 'a text value without its quotes' - u simulate unquoted.nml
{ echo "&model name='miller, units='ksi', temperature=866.15, tm=1800.0, youngs=22.5e3 /"; echo "$consts"; echo "$lcf"; } > runon.nml
row 'a quote left open before the next group' - u simulate runon.nml
{ echo "&model"; echo "  miller units='ksi', temperature=866.15, tm=1800.0, youngs=22.5e3 /"; echo "$consts"; echo "$lcf"; } > leading.nml
row "a word before a group's first assignment" - u simulate leading.nml
{ echo "$model"; echo "$consts"; echo "&test name='lcf', history='thesis_lcf', data_file=../lcf.txt /"; } > path.nml
row 'a path not in quotes' - u simulate path.nml
{ printf '\xef\xbb\xbf'; echo "$model"; echo "$consts"; echo "$lcf"; } > bom.nml
row 'a UTF-8 byte-order mark (read as blanks)' bom/lcf.sim.txt u simulate -o bom bom.nml
{ echo "&model name='miller', units='ksi', temperature=866.15, tm=1800.0, youngs=22.5e3, tm=1700.0 /"; echo "$consts"; echo "$lcf"; } > twice.nml
row 'a variable given twice' - u simulate twice.nml
{ echo "&model name='miller', units='ksi', temperature=866.15, tm=1800.0, youngs=-22.5e3 /"; echo "$consts"; echo "$lcf"; } > negE.nml
row 'negative Young'"'"'s modulus' - u simulate negE.nml
{ echo "&model name='miller', units='psi', temperature=866.15, tm=1800.0, youngs=22.5e3 /"; echo "$consts"; echo "$lcf"; } > psi.nml
row 'unknown stress unit' - u simulate psi.nml
{ echo "$model"; echo "$consts"; echo "$fitg"; } > notest.nml
row 'no `&test` group' - u run notest.nml -o notest
mk badname.nml "&fit fitted='H1','Z9', max_evals=8 /"
row '`&fit` names an unknown constant' - u run badname.nml -o badname
mk nofit.nml "&fit max_evals=8 /"
row '`&fit` fits no constant' - u run nofit.nml -o nofit
mk dupfit.nml "&fit fitted='H1','n','H1', max_evals=8 /"
row '`&fit` names a constant twice' - u run dupfit.nml -o dupfit
mk orphan.nml "&fit fitted='H1','n', upper(3)=7e4, max_evals=8 /"
row '`&fit` bound for a constant it does not name' - u run orphan.nml -o orphan
awk '/^#/ { print; next } { $3 = "0.0"; print }' lcf.txt > zero.txt
mk zero.nml "$fitg" "&test name='lcf', history='thesis_lcf', data_file='zero.txt' /"
row 'data: stress 0 at every row' - u run zero.nml -o zero
awk -F, -v OFS=, '/^#/ || /^time/ { print; next } { $2 = 100 * $2; print }' \
  "$root/data/tutorial/cyclic-fast.csv" > pct.csv
mk pct.nml "$fitg" "&test name='fast', history='data', data_file='pct.csv' /"
row 'data: measured strain in percent' - u run pct.nml -o pct
cp "$root/data/tutorial/cyclic-fast.csv" fast.csv
mk amp.nml "$fitg" "&test name='fast', history='cyclic', strain_range=0.015, strain_rate=1e-3, cycles=5, hold_max=600.0, hold_min=600.0, data_file='fast.csv', data_unit='MPa' /"
row 'data: the history is not the recorded test (an amplitude given as strain_range)' - u run amp.nml -o amp
mk amp-pct.nml "$fitg" "&test name='fast', history='cyclic', strain_range=0.03, strain_rate=1e-3, cycles=5, hold_max=600.0, hold_min=600.0, data_file='pct.csv', data_unit='MPa' /"
row 'data: measured strain in percent beside a programmed history' - u run amp-pct.nml -o amp-pct
mk range.nml "$fitg" "&test name='c', history='cyclic', strain_range=3.0, strain_rate=1e-3, cycles=1 /"
row 'strain range in percent (3 for 3 %)' - u run range.nml -o range
mk range-half.nml "$fitg" "&test name='c', history='cyclic', strain_range=0.5, strain_rate=1e-3, cycles=1 /"
row 'strain range in percent (0.5 for 0.5 %)' - u run range-half.nml -o range-half
awk '/^#/ { print; next } { $3 = $3 * 0.006894757; print }' lcf.txt > gpa.txt
mk gpa.nml "$fitg" "&test name='lcf', history='thesis_lcf', data_file='gpa.txt' /"
row 'data: stress in GPa on a deck in ksi' - u run gpa.nml -o gpa
awk '/^#/ { print; next } { $3 = $3 * 6.894757; print }' lcf.txt > mpa.txt
mk mpa.nml "$fitg" "&test name='lcf', history='thesis_lcf', data_file='mpa.txt' /"
row 'data: stress in MPa on a deck in ksi' - u run mpa.nml -o mpa
awk '/^#/ { print; next } { $1 = 1000 * $1; print }' lcf.txt > ms.txt
mk ms.nml "$fitg" "&test name='lcf', history='thesis_lcf', data_file='ms.txt' /"
row 'data: time in ms' - u run ms.nml -o ms
tr ',' ';' < "$root/data/tutorial/cyclic-fast.csv" > semi.csv
mk semi.nml "$fitg" "&test name='fast', history='data', data_file='semi.csv' /"
row 'data: columns separated by semicolons' - u run semi.nml -o semi
mk method.nml "&fit fitted='H1','n', method='newton' /"
row 'unknown method' - u run method.nml -o method
mk jac.nml "&fit fitted='H1','n', method='lm', jacobian='exact' /"
row 'unknown Jacobian' - u run jac.nml -o jac
mk between.nml "$fitg" "this line is no group" "$lcf"
row 'text between groups' - u run between.nml -o between
mk noamp.nml "$fitg" "$lcf" "test name='relax', history='relaxation', data_file='relax.txt' /"
row '`&test` group without its `&`' - u run noamp.nml -o noamp
{ echo "$model"; echo "$model"; echo "$consts"; echo "$fitg"; echo "$lcf"; } > twomodel.nml
row 'second `&model` group' - u run twomodel.nml -o twomodel
mk dup.nml "$fitg" "$lcf" "$lcf"
row 'two tests of the same name' - u run dup.nml -o dup
long=$(printf 'd%.0s' $(seq 1 300))
{ echo "$model"; echo "$consts"; echo "$fitg"; echo "&output out_dir='$long' /"; echo "$lcf"; } > longpath.nml
row 'output path of 300 characters' "$long/best.nml" u run longpath.nml
mk nodata.nml "$fitg" "&test name='lcf', history='thesis_lcf', data_file='none.txt' /"
row 'data file missing' - u run nodata.nml -o nodata
: > empty.txt
mk emptydata.nml "$fitg" "&test name='lcf', history='thesis_lcf', data_file='empty.txt' /"
row 'data file empty' - u run emptydata.nml -o emptydata
printf 'time stress\n0 0\n1 abc\n2 3\n' > nan.txt
mk nandata.nml "$fitg" "&test name='lcf', history='thesis_lcf', data_file='nan.txt' /"
row 'data file: text in a number column' - u run nandata.nml -o nandata
mk col.nml "$fitg" "&test name='lcf', history='thesis_lcf', data_file='lcf.txt', stress_column='sigma' /"
row 'data file: no column of that name' - u run col.nml -o col
printf 'time stress\n0 0\n2 1\n1 2\n3 0\n' > back.txt
mk back.nml "$fitg" "&test name='lcf', history='thesis_lcf', data_file='back.txt' /"
row 'data file: time going backwards' - u run back.nml -o back
sed '4,$s/\./,/g' "$root/data/tutorial/cyclic-fast.csv" > comma.csv
mk comma.nml "$fitg" "&test name='fast', history='data', data_file='comma.csv' /"
row 'data file: decimal commas (rows longer than the header)' - u run comma.nml -o comma
mk short.nml "$fitg" "&test name='r', history='relaxation', data_file='lcf.txt' /"
row 'data shorter than the simulation' - u run short.nml -o short
mk hist.nml "$fitg" "&test name='lcf', history='thesis_lfc', data_file='lcf.txt' /"
row 'unknown history' - u run hist.nml -o hist
mk histfile.nml "$fitg" "&test name='lcf', history='file', file='none.csv', data_file='lcf.txt' /"
row 'history file missing' - u run histfile.nml -o histfile
mk weight.nml "$fitg" "&test name='lcf', history='thesis_lcf', data_file='lcf.txt', weighting='heavy' /"
row 'unknown weighting' - u run weight.nml -o weight
mk backend.nml "$fitg" "&test name='lcf', history='thesis_lcf', data_file='lcf.txt', backend='ansys' /"
row 'unknown backend' - u run backend.nml -o backend
mk extstress.nml "$fitg" "&test name='c', history='creep', stress=30, duration=200, data_file='lcf.txt', backend='external', command='true' /"
row 'external backend on a stress-controlled test' - u run extstress.nml -o extstress
row '`--constants` file missing' - u simulate fit.nml -c none.nml -o c1
echo "&model youngs=1 /" > noconst.nml
row '`--constants` file without `&constants`' - u simulate fit.nml -c noconst.nml -o c2
row '`simulate -t` names no test' - u simulate fit.nml -t nosuch -o t1
row '`deck` names no test' - u deck nosuch fit.nml -o d1
row '`deck` with the input before the test'"'"'s name' - u deck fit.nml lcf -o d2
{ echo "$model"; echo "$consts"; echo "$fitg"; echo "$lcf"; } > noheld.nml
row '`diagnose` with no held-out test' - u diagnose noheld.nml -o noheld
put '... what it left' 0 "$([ -e noheld ] && echo "the folder noheld: $(find noheld | tr '\n' ' ')" || echo 'nothing: no folder noheld')"

# --- output
echo x > afile
row 'output folder is a file' - u run fit.nml -o afile
row 'output folder under /proc' - u simulate fit.nml -o /proc/usharp-out
if mkdir -p tiny && mount -t tmpfs -o size=64k tmpfs tiny 2>/dev/null; then
  mk full.nml "&fit fitted='H1','n', max_evals=40 /"
  row 'disk full during `run` (64 KiB tmpfs)' - u run -q full.nml -o tiny/run
  put '... what the run left' 0 "$(cd tiny/run && ls | tr '\n' ' ')"
  rm -rf tiny/run
  row 'disk full during `simulate` (64 KiB tmpfs)' - u simulate -q "$root/decks/thesis-data.nml" -o tiny/sim
  put '... temporary or half-written files left' 0 "$(ls tiny/sim | grep -c '\.part$') *.part files"

  umount tiny
  if mkdir -p rofs && mount -t tmpfs -o ro,size=64k tmpfs rofs 2>/dev/null; then
    row 'output folder on a read-only file system' - u simulate fit.nml -o rofs/out
    umount rofs
  fi
else
  row 'disk full (64 KiB tmpfs): not run, cannot mount here' - true
fi

# --- runs, journals, locks, signals
u run -q fit.nml -o r1 > /dev/null 2>&1
row 'second run into a folder with a journal' - u run -q fit.nml -o r1
row '... with `--force`' r1/best.nml u run -q --force fit.nml -o r1
row '`--resume` of a finished run' r1/best.nml u run -q --resume fit.nml -o r1
row '`simulate` into a fit'"'"'s folder' - u simulate fit.nml -o r1
row '`predict` into a fit'"'"'s folder' - u predict fit.nml -c r1/best.nml -o r1
mkdir -p mine; echo 'my notes' > mine/summary.txt
row '`predict` over a file of the user'"'"'s' - u predict fit.nml -c r1/best.nml -o mine
row '... with `--force`' mine/lcf.fit.txt u predict --force fit.nml -c r1/best.nml -o mine
echo 'my notes' > mine/identify.txt
row '`identify` over a file of the user'"'"'s' - u identify fit.nml -o mine
echo '1.0' > mine/Constants.txt
row '`deck` over a file of the user'"'"'s' - u deck fit.nml -o mine
echo 'my notes' > mine/design.txt
row '`design` over a file of the user'"'"'s' - u design fit.nml -o mine
mkdir -p mine/diagnose; echo 'my notes' > mine/diagnose/report.md
mk held.nml "$fitg" "$lcf" "&test name='relax', history='relaxation', data_file='relax.txt' /" \
  "&diagnose holdout='relax' /"
row '`diagnose` over a file of the user'"'"'s' - u diagnose held.nml -o mine
echo 'my notes' > mine/lcf.sim.txt
row '`simulate` over a file of the user'"'"'s' - u simulate fit.nml -o mine
row '`--resume` without a journal' - u run -q --resume fit.nml -o r-none
cp lcf.txt lcf.orig; echo '# changed' >> lcf.txt
row '`--resume` after a data file changed' - u run -q --resume fit.nml -o r1
cp lcf.orig lcf.txt; cp fit.nml fit.orig; echo '! edited' >> fit.nml
row '`--resume` after the input changed' - u run -q --resume fit.nml -o r1
cp fit.orig fit.nml
row '`--resume` with another `--constants` file' - u run -q --resume fit.nml -o r1 -c fit.nml
head -c 300 r1/fit.journal > torn; cp torn r1/fit.journal
row '`--resume` of a journal torn by a kill' r1/best.nml u run -q --resume fit.nml -o r1
sed -i '1s/ build=[0-9A-Za-z]* / build=0123456789ABCDEF /' r1/fit.journal
row '`--resume` of a journal another build of usharp wrote' - u run -q --resume fit.nml -o r1
truncate -s 100 r1/fit.journal
row '`--resume` of a journal whose fingerprint line is cut short' - u run -q --resume fit.nml -o r1
echo 'not a journal' > r1/fit.journal
row '`--resume` of a file that is no journal' - u run -q --resume fit.nml -o r1
mk sens.nml "&fit fitted='H1','n', method='lm', jacobian='sensitivity', identify=.false. /"
u run -q sens.nml -o sens > /dev/null 2>&1
# bytes of the first Jacobian's values damaged (after the header and the first residual vector)
m=$(od -An -t d4 -j 8 -N 4 sens/fit.cache | tr -d ' ')
printf 'garbage!' | dd of=sens/fit.cache bs=1 seek=$((16 + 8 + 8 * (2 + m) + 8 + 16 + 320)) conv=notrunc 2>/dev/null
head -n 8 sens/fit.journal > torn; cp torn sens/fit.journal
row '`--resume` with damaged bytes in `fit.cache`' - u run -q --resume sens.nml -o sens
mkdir -p locked
flock locked/.usharp.lock sleep 5 &
sleep 0.3
row 'another run holds the output folder' - u run -q --force fit.nml -o locked
wait
mk long.nml "&fit fitted='H1','n', eps=1e-300, max_evals=400 /"
"$exe" run -q long.nml -o killed > /dev/null 2>&1 & pid=$!
journal_at killed 20
kill -9 $pid; wait $pid 2>/dev/null
row 'kill -9, then `--resume` (no stale lock)' killed/best.nml u run -q --resume long.nml -o killed
for sig in TERM INT; do
  "$exe" run -q long.nml -o sig$sig > out.txt 2> err.txt & pid=$!
  journal_at sig$sig 20
  kill -$sig $pid; wait $pid; rc=$?
  put "SIG$sig during a run" "$rc" "$(head -1 err.txt); fit.log: $(tail -1 sig$sig/fit.log)"
done

# --- external commands
ext() { # ext FILE COMMAND [EXTRA]
  mk "$1" "&fit fitted='H1','n', max_evals=2, identify=.false. /" \
    "&test name='lcf', history='thesis_lcf', data_file='lcf.txt', backend='external', command='$2' ${3:-} /"
}
ext e127.nml 'no-such-fe-program {constants}'
row 'external command not found' - u run -q e127.nml -o e127
echo 'exit 0' > noexec.sh; chmod -x noexec.sh
ext e126.nml "$tmp/noexec.sh"
row 'external command not executable' - u run -q e126.nml -o e126
ext e3.nml 'echo license server not reachable >&2; exit 3'
row 'external command fails' - u run -q e3.nml -o e3
ext eout.nml 'true'
row 'external command writes no output' - u run -q eout.nml -o eout
ext egarb.nml 'echo garbage > {output}'
row 'external command writes garbage' - u run -q egarb.nml -o egarb
ext eterm.nml 'sleep 60 & trap "" TERM; sleep 60' ', time_limit=0.5'
row 'external command ignores TERM past its time limit' - u run -q eterm.nml -o eterm
put '... its background child' 0 "$(pgrep -x -f 'sleep 60' > /dev/null && echo 'still running' || echo 'stopped with its group')"

ext eid.nml "case {work} in *identify*) exit 9;; esac; sh $standin $exe {input_dir}/fit.nml {test}" ', constants_format="(ES24.16)"'
sed -i 's/identify=.false./identify=.true./' eid.nml
row 'fit done, identifiability report fails' eid/best.nml u run -q eid.nml -o eid

# --- fits and simulations that fail
mk abort.nml "&fit fitted='H1','n', max_failures=1, rho=0.99 /"
row 'fit aborted: failures in a row' - u run -q abort.nml -o abort
{ echo "$model"; echo "&constants a1=0.8, a2=7.42e-5, b=1e15, c2=0.1, h1=200, h2=100, n=-5.0, q=91000 /"; echo "$lcf"; } > badc.nml
row 'simulate with invalid constants' - u simulate badc.nml -o badc

# --- the plot script
mkdir -p 'p";system("touch pwned");print "'
cp r1/lcf.fit.txt 'p";system("touch pwned");print "/'
row 'plot-fit.sh: a folder name that is gnuplot code' - bash "$root/scripts/plot-fit.sh" 'p";system("touch pwned");print "'
put '... the command in the name' 0 "$([ -e pwned ] && echo 'RAN: pwned exists' || echo 'did not run: no file pwned')"

row 'plot-fit.sh: folder without fits' - bash "$root/scripts/plot-fit.sh" r-none

# --- standard output, temporary names, load histories
row 'standard output on a full device' - sh -c "'$exe' simulate --force -o so fit.nml > /dev/full"
mkdir -p pt && echo 'my notes' > pt/lcf.fit.txt.part
row "a user's file under a result's temporary name (lcf.fit.txt.part)" - u run -q fit.nml -o pt
mkdir -p hf && cp lcf.txt hf/lcf.sim.txt
{ echo "$model"; echo "$consts"; echo "&test name='lcf', history='file', file='lcf.sim.txt' /"; } > hf/h.nml
row 'simulate --force into the folder of its load history (lcf.sim.txt)' - u simulate --force hf/h.nml -o hf
{ echo "$model"; echo "$consts"; echo "&test name='lcf', history='file' /"; } > nofile.nml
row "history 'file' without file" - u simulate nofile.nml -o nofile
awk '/^#/ { print; next } { $2 = 100 * $2; print }' lcf.txt > pct-small.txt
mk pct-small.nml "$fitg" "&test name='lcf', history='data', data_file='pct-small.txt' /"
row 'data: measured strain in percent below 1 (a 0.5 % test)' - u run pct-small.nml -o pct-small
