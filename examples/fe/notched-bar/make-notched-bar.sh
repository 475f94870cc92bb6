#!/usr/bin/env bash
# Writes the notched-bar examples: one mesh of an axisymmetric round bar with a smooth
# circumferential notch (8-node quadrilaterals), as a CalculiX deck, an Abaqus input and an
# ANSYS APDL input, all with the Miller user material at 866.15 K under a cyclic axial
# displacement (0 -> +0.05 -> -0.05 -> +0.05 mm on a 15 mm half-length, 24 s per ramp).
# Lengths mm, stress ksi (the constants' unit), forces ksi*mm^2, time s, temperature K.
# usage: examples/fe/make-notched-bar.sh OUTDIR [DT [tight]]
#   DT: fixed time increment, s (0.75); tight: CalculiX and Abaqus Newton tolerances 1e-9
#   (to follow the global Newton's convergence to the end)
set -euo pipefail
out="${1:?usage: make-notched-bar.sh OUTDIR [DT]}"
dt="${2:-0.75}"
tight="${3:-}"
mkdir -p "$out"
# Mesh: nr x nz elements over r in [0, R(z)], z in [0, L] (half the bar: symmetry at z = 0),
# R(z) = R0 - d exp(-(z/w)^2), axial spacing graded towards the notch
mesh() { # format: ccx | abaqus | ansys
  awk -v fmt="$1" 'BEGIN {
    nr = 4; nz = 8; R0 = 5.0; d = 1.5; w = 1.5; L = 15.0
    NI = 2 * nr; NJ = 2 * nz
    for (j = 0; j <= NJ; j++) {
      z = L * (j / NJ)^1.6; R = R0 - d * exp(-(z / w)^2)
      for (i = 0; i <= NI; i++) {
        if (i % 2 == 1 && j % 2 == 1) continue
        id = j * (NI + 1) + i + 1; r = R * i / NI
        if (fmt == "ansys") printf "N,%d,%.10g,%.10g\n", id, r, z
        else { if (!hdr) { print "*NODE"; hdr = 1 }; printf "%d,%.10g,%.10g\n", id, r, z }
      }
    }
    if (fmt == "ansys") print "! elements: corners counter-clockwise, then mid-side nodes"
    else if (fmt == "ccx") print "*ELEMENT,TYPE=CAX8R,ELSET=BAR"
    else print "*ELEMENT,TYPE=CAX8R,ELSET=BAR"
    e = 0
    for (ej = 0; ej < nz; ej++) for (ei = 0; ei < nr; ei++) {
      e++
      n1 = (2*ej) * (NI+1) + 2*ei + 1; n2 = n1 + 2; n4 = (2*ej+2) * (NI+1) + 2*ei + 1; n3 = n4 + 2
      n5 = n1 + 1; n7 = n4 + 1; n8 = (2*ej+1) * (NI+1) + 2*ei + 1; n6 = n8 + 2
      if (fmt == "ansys") printf "EN,%d,%d,%d,%d,%d,%d,%d,%d,%d\n", e, n1, n2, n3, n4, n5, n6, n7, n8
      else printf "%d,%d,%d,%d,%d,%d,%d,%d,%d\n", e, n1, n2, n3, n4, n5, n6, n7, n8
    }
    # Node sets: axis (r = 0), bottom (z = 0, symmetry plane), top (z = L, loaded)
    if (fmt == "ansys") {
      for (j = 0; j <= NJ; j++) printf "D,%d,UX,0\n", j * (NI + 1) + 1
      for (i = 0; i <= NI; i++) printf "D,%d,UY,0\n", i + 1
      printf "NSEL,NONE\n"; for (i = 0; i <= NI; i++) printf "NSEL,A,NODE,,%d\n", NJ * (NI + 1) + i + 1
      printf "CM,TOP,NODE\nALLSEL\n"
    } else {
      print "*NSET,NSET=AXIS"; for (j = 0; j <= NJ; j++) print j * (NI + 1) + 1
      print "*NSET,NSET=BOTTOM"; for (i = 0; i <= NI; i++) print i + 1
      print "*NSET,NSET=TOP"; for (i = 0; i <= NI; i++) print NJ * (NI + 1) + i + 1
      print "*NSET,NSET=ALLN"
      for (j = 0; j <= NJ; j++) for (i = 0; i <= NI; i++) if (!(i % 2 == 1 && j % 2 == 1)) print j * (NI + 1) + i + 1
    }
  }'
}
# Displacement of the top at the end of each ramp, mm, and the ramp time, s
ramps="0.05 -0.05 0.05"
ramp_t=24.0
controls() {
  [ "$tight" = tight ] || return 0
  echo "*CONTROLS,PARAMETERS=FIELD"; echo "1.E-9,1.E-9,,,1.E-9,,,"
  echo "*CONTROLS,PARAMETERS=TIME INCREMENTATION"; echo "20,30,,,,,,,,,,"
}
props1="22500.,0.3,0.8,7.42E-5,1.E15,0.,0.1,1.9859,"
props2="280.,100.,5.8,91000.,1800."

# The CalculiX and Abaqus inputs share the keyword syntax: code, material name, run line
abaqus_style() {
  local code="$1" mat="$2" run="$3" k=0
  echo "** Miller user material: axisymmetric notched bar, cyclic axial displacement ($code)"
  echo "** written by examples/fe/notched-bar/make-notched-bar.sh; $run"
  [ "$code" = CalculiX ] || { echo "*HEADING"; echo "Notched bar, Miller viscoplastic UMAT"; }
  mesh "$([ "$code" = CalculiX ] && echo ccx || echo abaqus)"
  echo "*BOUNDARY"; echo "AXIS,1,1"; echo "BOTTOM,2,2"
  echo "*MATERIAL,NAME=$mat"; echo "*USER MATERIAL,CONSTANTS=13"; echo "$props1"; echo "$props2"
  echo "*DEPVAR"; echo "13"
  echo "*SOLID SECTION,ELSET=BAR,MATERIAL=$mat"
  echo "*INITIAL CONDITIONS,TYPE=TEMPERATURE"; echo "ALLN,866.15"
  for u in $ramps; do
    k=$((k + 1))
    echo "*STEP,INC=100000"; echo "*STATIC,DIRECT"; echo "$dt,$ramp_t"; controls
    echo "*BOUNDARY"; echo "TOP,2,2,$u"; echo "*TEMPERATURE"; echo "ALLN,866.15"
    echo "*NODE PRINT,NSET=TOP,TOTALS=ONLY"; echo "RF"
    [ "$code" = CalculiX ] || { echo "*OUTPUT,FIELD"; echo "*ELEMENT OUTPUT"; echo "S,SDV,ENER"; }
    echo "*END STEP"
  done
}
abaqus_style CalculiX @ABAQUS_MILLER "run: ccx -i notched-bar (libMILLER.so on LD_LIBRARY_PATH)" > "$out/notched-bar.inp"
abaqus_style Abaqus/Standard MILLER "run: abaqus job=notched-bar-abaqus user=umat_miller_abaqus.f" \
  > "$out/notched-bar-abaqus.inp"

{ echo "! Miller user material: axisymmetric notched bar, cyclic axial displacement (ANSYS APDL)"
  echo "! written by examples/fe/make-notched-bar.sh; needs an ANSYS built with usermat_miller_ansys.F"
  echo "/PREP7"
  echo "ET,1,PLANE183"; echo "KEYOPT,1,1,0        ! 8-node quadrilateral (2 x 2 Gauss points)"; echo "KEYOPT,1,3,1        ! axisymmetric"
  echo "TB,USER,1,1,13"
  echo "TBTEMP,866.15"
  echo "TBDATA,1,22500.,0.3,0.8,7.42E-5,1.E15,0."
  echo "TBDATA,7,0.1,1.9859,280.,100.,5.8,91000."
  echo "TBDATA,13,1800."
  echo "TB,STATE,1,,13"
  mesh ansys
  echo "TUNIF,866.15"; echo "FINISH"
  echo "/SOLU"; echo "ANTYPE,STATIC"; echo "NLGEOM,OFF"; echo "OUTRES,ALL,ALL"
  t=0; k=0
  for u in $ramps; do
    k=$((k + 1)); t=$(awk -v a="$t" -v b="$ramp_t" 'BEGIN { print a + b }')
    echo "TIME,$t"; echo "DELTIM,$dt,$dt,$dt"; echo "D,TOP,UY,$u"; echo "SOLVE"
  done
  echo "FINISH"
  echo "/POST1                ! axial reaction of the loaded end at the end of each ramp (360 degrees)"
  echo "*DO,LS,1,3"; echo "SET,LS,LAST"; echo "CMSEL,S,TOP"; echo "PRRSOL,FY"; echo "*ENDDO"
  echo "ALLSEL"; echo "FINISH"
} > "$out/notched-bar-ansys.mac"
