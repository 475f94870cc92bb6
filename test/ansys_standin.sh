#!/bin/sh
# A stand-in for an ANSYS batch run, for testing the external backend without a licence.
# Like the decks of `usharp deck`, it runs in a work folder that holds the constants file
# (E, Poisson, A1, A2, B, C1, C2, k, H1, H2, n, Q, Tm, D0, one per line), simulates one test
# and writes a POST26 PRVAR-style listing: page headers, title lines repeated after every
# page break, columns TIME, STRESS, STRAIN, and (as ANSYS) no row at time 0.
#
# usage: ansys_standin.sh USHARP INPUT.nml TEST [LISTING [CONSTANTS]]
#   USHARP     the usharp executable
#   INPUT.nml  the input file whose &test TEST is simulated (its &constants are replaced)
#   LISTING    the listing to write (default TEST_prvar.txt)
#   CONSTANTS  the constants file to read (default Constants.txt)
set -e
usharp=$1
input=$2
test=$3
listing=${4:-${test}_prvar.txt}
constants=${5:-Constants.txt}
[ -r "$constants" ] || { echo "ansys_standin: cannot read $constants" >&2; exit 8; }

# The properties that usharp's &constants names; Q is props(12) in cal/mol
awk 'NF { v[++n] = $1 }
     END {
       if (n < 13) { print "ansys_standin: " n " values in the constants file, 13 needed" > "/dev/stderr"; exit 8 }
       printf "&constants\n a1 = %.17g, a2 = %.17g, b = %.17g, c2 = %.17g,\n", v[3], v[4], v[5], v[7]
       printf " h1 = %.17g, h2 = %.17g, n = %.17g, q = %.17g\n/\n", v[9], v[10], v[11], v[12]
     }' "$constants" > standin-constants.nml

"$usharp" simulate "$input" --constants standin-constants.nml --test "$test" --out-dir . -q

# time strain stress ... -> a PRVAR listing, 40 rows a page
awk -v title="$test" '
  function page(n) {
    printf "\f\n ANSYS Mechanical Enterprise (stand-in for tests: usharp test/ansys_standin.sh, %s)   PAGE %d\n\n", title, n
    printf " /INPUT FILE= %s.inp\n\n", title
    printf " ***** POST26 VARIABLE LISTING *****\n\n"
    printf "    TIME           2 S                 3 U\n"
    printf "                   STRESS              STRAIN\n"
  }
  /^#/ { next }
  NF >= 3 && $1 + 0 > 0 {
    if (rows % 40 == 0) page(rows / 40 + 1)
    printf " %.16E  %.16E  %.16E\n", $1, $3, $2
    rows++
  }' "$test.sim.txt" > "$listing"
