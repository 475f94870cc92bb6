#!/usr/bin/env bash
# Build the drop-in Miller user material as a shared library lib<NAME>.so (default MILLER,
# for a CalculiX material named @ABAQUS_MILLER) with every gfortran warning that applies to
# a user subroutine turned into an error. Unused-dummy-argument warnings are off: the FE
# codes' fixed argument lists hold arguments the model does not need.
# usage: scripts/build-umat.sh OUTDIR [NAME]
set -euo pipefail
here="$(cd "$(dirname "$0")/.." && pwd)"
out="${1:?usage: build-umat.sh OUTDIR [NAME]}"
name="${2:-MILLER}"
mkdir -p "$out"
# The drop-in sources, in dependency order
srcs=(src/util/usharp_kinds.f90 src/util/usharp_error.f90 src/util/usharp_strings.f90
      src/util/usharp_lapack.f90 src/model/usharp_miller.f90 src/model/usharp_miller_update.f90
      src/upf/usharp_upf.f90 src/upf/usermat_miller.f90 src/upf/umat_miller.f90)
cd "$here"
flags=(-O2 -fPIC -std=f2018 -Wall -Wextra -Wimplicit-interface -Wno-unused-dummy-argument -Werror)
objs=()
for f in "${srcs[@]}"; do
  o="$out/$(basename "${f%.f90}").o"
  gfortran "${flags[@]}" -J "$out" -c "$f" -o "$o"
  objs+=("$o")
done
gfortran -shared -o "$out/lib${name}.so" "${objs[@]}" -llapack -lblas
echo "$out/lib${name}.so"
