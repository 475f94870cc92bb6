#!/usr/bin/env bash
# The drop-in user material of a model (MODEL: miller, the default, or chaboche), in two forms:
# - OUTDIR/lib<NAME>.so (default MILLER, for a CalculiX material named @ABAQUS_MILLER), built
#   with every gfortran warning that applies to a user subroutine turned into an error;
# - single-file sources, one per FE code, in fixed form (72 columns, continuation mark in
#   column 6), the form in which the vendors' build scripts compile .f and .F files:
#     OUTDIR/umat_<MODEL>_abaqus.f     abaqus job=... user=umat_<MODEL>_abaqus.f
#     OUTDIR/umat_<MODEL>_calculix.f   linked into CalculiX (or built into lib<NAME>.so)
#     OUTDIR/usermat_<MODEL>_ansys.F   the ANSYS user-programmable-feature build
#   The modules come in dependency order; only the message routine differs between codes.
#   The adapters are src/upf/umat_miller.f90 and usermat_miller.f90; for another model the
#   model's module and type take the Miller model's place in them (OUTDIR/src).
# Unused-dummy-argument warnings are off: the FE codes' fixed argument lists hold arguments
# the model does not need.
# usage: scripts/build-umat.sh [--check] OUTDIR [NAME [MODEL]]
#   --check: also compile each single-file source as the vendor's build would treat it
#            (gfortran -c -ffixed-form, warnings as errors) and build lib<NAME>.so from the
#            CalculiX single file as well.
set -euo pipefail
here="$(cd "$(dirname "$0")/.." && pwd)"
check=0
if [ "${1:-}" = "--check" ]; then check=1; shift; fi
out="${1:?usage: build-umat.sh [--check] OUTDIR [NAME [MODEL]]}"
name="${2:-MILLER}"
model="${3:-miller}"
Model="$(echo "${model:0:1}" | tr a-z A-Z)${model:1}"
case "$model" in miller | chaboche) ;; *) echo "build-umat: model '$model' is not known (miller, chaboche)" >&2; exit 2 ;; esac
mkdir -p "$out"
out="$(cd "$out" && pwd)"
cd "$here"
# The drop-in sources, in dependency order; the message module and the adapter per code
core=(src/util/usharp_kinds.f90 src/util/usharp_math.f90 src/util/usharp_error.f90 src/util/usharp_strings.f90
      src/util/usharp_units.f90 src/model/usharp_effect_values.f90 src/model/usharp_model.f90
      src/model/usharp_model_j2.f90
      "src/model/usharp_model_${model}.f90" src/upf/usharp_upf.f90)
umat=src/upf/umat_miller.f90
usermat=src/upf/usermat_miller.f90
rdir=src/upf
if [ "$model" != miller ]; then
  # The same adapters with the model's module and type; their header says which model
  mkdir -p "$out/src"
  for a in umat usermat; do
    sed -e "s/usharp_model_miller/usharp_model_${model}/g; s/miller_model/${model}_model/g" \
        -e "1,/^subroutine/{/^!>/d}" "src/upf/${a}_miller.f90" > "$out/src/${a}_${model}.f90.tmp"
    { echo "!> The ${a} adapter of src/upf/${a}_miller.f90 for the ${Model} model (written by"
      echo "!> scripts/build-umat.sh); its properties and state variables: docs/guide/fe-users.md"
      cat "$out/src/${a}_${model}.f90.tmp"; } > "$out/src/${a}_${model}.f90"
    rm -f "$out/src/${a}_${model}.f90.tmp"
  done
  umat="$out/src/umat_${model}.f90"
  usermat="$out/src/usermat_${model}.f90"
  # The message routines name the model
  for r in usharp_upf_report.f90 usharp_upf_report_abaqus.inc usharp_upf_report_ansys.inc; do
    sed -e "s/usharp Miller material/usharp ${Model} material/g; s/usermat_miller/usermat_${model}/g" \
      "src/upf/$r" > "$out/src/$r"
  done
  rdir="$out/src"
fi
warn=(-Wall -Wextra -Wimplicit-interface -Wno-unused-dummy-argument -Werror)
flags=(-O2 -fPIC -std=f2018 "${warn[@]}")

# Free-form source -> fixed form: statements joined across '&' continuations, trailing
# comments dropped, code from column 7, continuation lines marked in column 6, nothing past
# column 72. A line broken inside a character literal is filled to column 72 exactly and
# the literal resumes in column 7, as fixed form reads it (with or without padding).
to_fixed() {
  awk -v sq="'" -v dq='"' '
  function emit_comment(text,   w) {
    while (length(text) > 71) {
      w = 71
      while (w > 40 && substr(text, w, 1) != " ") w--
      if (w <= 40) w = 71
      print "!" substr(text, 1, w); text = "  " substr(text, w + 1)
    }
    print "!" text
  }
  # Split statement s (indentation ind) into lines of at most 72 columns
  function emit_stmt(s, ind,   pre, room, cut, i, c, q, lastgood, qat, line, instr) {
    if (ind > 24) ind = 24
    pre = sprintf("%" (6 + ind) "s", "")
    q = ""
    while (1) {
      room = 72 - length(pre)
      if (length(s) <= room) { print pre s; return }
      # Scan the first room characters: quote state and the last break outside a literal
      lastgood = 0
      for (i = 1; i <= room; i++) {
        c = substr(s, i, 1)
        if (q == "") { if (c == sq || c == dq) q = c; else if (c == " " || c == ",") lastgood = i }
        else if (c == q) q = ""
        qat[i] = q
      }
      if (lastgood >= room / 2) {
        cut = lastgood; instr = 0
      } else {
        cut = room; instr = (qat[room] != "")
      }
      line = substr(s, 1, cut)
      # Quote state at the cut decides how the next line starts
      q = (cut == room) ? qat[room] : qat[cut]
      if (instr || q != "") {
        # inside a literal: fill to column 72 exactly, resume in column 7
        while (length(pre line) < 72) { line = line substr(s, cut + 1, 1); cut++ }
        print pre line
        s = substr(s, cut + 1)
        pre = "     &"
      } else {
        print pre line
        s = substr(s, cut + 1)
        sub(/^ +/, "", s)
        pre = "     &" sprintf("%" (ind + 3) "s", "")
      }
      delete qat
    }
  }
  BEGIN { cont = 0; q = ""; stmt = "" }
  {
    sub(/\r$/, "")
    line = $0
    if (!cont) {
      if (line ~ /^[ ]*$/) { print ""; next }
      if (line ~ /^[ ]*!/) { sub(/^[ ]*!/, "", line); emit_comment(line); next }
      match(line, /^ */); ind = RLENGTH; line = substr(line, ind + 1)
    } else {
      if (q == "" && line ~ /^[ ]*!/) next          # comment between continuation lines
      if (line ~ /^[ ]*&/) { sub(/^[ ]*&/, "", line) }
      else if (q == "") { sub(/^ +/, "", line); line = " " line }
    }
    # Drop a trailing comment (outside literals) and find a continuation mark
    code = ""
    n = length(line)
    for (i = 1; i <= n; i++) {
      c = substr(line, i, 1)
      if (q == "") {
        if (c == "!") break
        if (c == sq || c == dq) q = c
      } else if (c == q) q = ""
      code = code c
    }
    if (q == "") sub(/[ ]+$/, "", code)
    else { t = code; sub(/[ ]+$/, "", t); if (t ~ /&$/) code = t }
    if (code ~ /&$/) { cont = 1; code = substr(code, 1, length(code) - 1) } else cont = 0
    stmt = stmt code
    if (!cont) { sub(/[ ]+$/, "", stmt); emit_stmt(stmt, ind); stmt = "" }
  }' "$@"
}

single() { # output file, report module, adapter
  local dst="$1" rep="$2" adapter="$3"
  { echo "! ${Model} viscoplastic model: single-file user material (fixed form),"
    echo "! written by usharp's scripts/build-umat.sh; see docs/guide/fe-users.md"
    to_fixed "${core[@]}" "$rep" "$adapter"; } > "$dst.tmp"
  mv "$dst.tmp" "$dst"
}
report="$rdir/usharp_upf_report.f90"
single "$out/umat_${model}_abaqus.f" "$rdir/usharp_upf_report_abaqus.inc" "$umat"
single "$out/umat_${model}_calculix.f" "$report" "$umat"
single "$out/usermat_${model}_ansys.F" "$rdir/usharp_upf_report_ansys.inc" "$usermat"

# The library from the free-form sources (CalculiX's umat and the ANSYS usermat together)
objs=()
mkdir -p "$out/mod"
for f in "${core[@]}" "$report" "$usermat" "$umat"; do
  o="$out/mod/$(basename "${f%.f90}").o"
  gfortran "${flags[@]}" -J "$out/mod" -c "$f" -o "$o"
  objs+=("$o")
done
gfortran -shared -o "$out/lib${name}.so" "${objs[@]}"

if [ $check -eq 1 ]; then
  # Each single file as the vendor compiles it: fixed form, no extra options
  for f in "umat_${model}_abaqus.f" "umat_${model}_calculix.f" "usermat_${model}_ansys.F"; do
    d="$out/check-${f%.*}"; mkdir -p "$d"
    over=$(awk 'length($0) > 72' "$out/$f" | wc -l)
    [ "$over" -eq 0 ] || { echo "build-umat: $f has $over lines longer than 72 columns"; exit 1; }
    ! grep -q "$(printf '\t')" "$out/$f" || { echo "build-umat: $f has tabs"; exit 1; }
    (cd "$d" && gfortran -c -ffixed-form -fPIC "${warn[@]}" "$out/$f" -o "${f%.*}.o") \
      || { echo "build-umat: $f does not compile as fixed form"; exit 1; }
    echo "build-umat: $f compiles as fixed form with -Wall -Wextra -Werror"
  done
  # The CalculiX single file alone makes the whole library
  (cd "$out/check-umat_${model}_calculix" && gfortran -shared -o "lib${name}.so" "umat_${model}_calculix.o")
fi
echo "$out/lib${name}.so"
