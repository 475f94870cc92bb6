#!/bin/sh
# Runs one usharp APDL deck with ANSYS in batch mode, in the current folder (the folder that
# holds the constants file the deck reads; the PRVAR listing is written there too).
#
# usage: run-ansys.sh DECK.inp
#
# Settings (edit here or set in the environment):
#   ANSYS_EXE      the ANSYS Mechanical APDL executable
#   ANS_USER_PATH  the folder of the user-programmable-features library built with the usharp
#                  USERMAT (see docs/user-guide.md, "Step by step: a fit with ANSYS")
#   ANSYS_OPTS     further options, e.g. a licence: -p ansys
ANSYS_EXE=${ANSYS_EXE:-/ansys_inc/v242/ansys/bin/mapdl}
ANS_USER_PATH=${ANS_USER_PATH:-$HOME/usharp-upf}
ANSYS_OPTS=${ANSYS_OPTS:-}
export ANS_USER_PATH

deck=$1
[ -n "$deck" ] || { echo "usage: run-ansys.sh DECK.inp" >&2; exit 2; }
[ -r "$deck" ] || { echo "run-ansys.sh: cannot read $deck" >&2; exit 2; }
[ -x "$ANSYS_EXE" ] || { echo "run-ansys.sh: ANSYS_EXE=$ANSYS_EXE is not an executable" >&2; exit 2; }
# -b batch, -np 1 one core (a single element), -i input, -o the solver's own listing
# shellcheck disable=SC2086
exec "$ANSYS_EXE" -b -np 1 $ANSYS_OPTS -i "$deck" -o ansys.out
