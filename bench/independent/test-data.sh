#!/usr/bin/env bash
# The independent data the diagnosis tests read (test/test_diagnose_data.f90), made again:
# bench/independent/selfcheck.py --make for each case, into data/independent-<case>/, with a
# deck that names what was injected. The elementary functions of glibc and numpy pick code
# paths by the processor (FMA, AVX-512), whose last bits differ: data made on two machines
# differed by 3e-10 relative, which moved one case's verdict (relax-softening: its held-out
# prediction is open between end points the fit tests cannot tell apart). So the data are
# kept in the project, made with the paths every x86-64 processor has.
# usage: bash bench/independent/test-data.sh   (python3 with numpy and scipy)
set -euo pipefail
cd "$(dirname "$0")/../.."
export GLIBC_TUNABLES=glibc.cpu.hwcaps=-AVX2,-FMA,-AVX512F,-AVX_Usable
export NPY_DISABLE_CPU_FEATURES="X86_V4 AVX512_ICL AVX512_SPR X86_V3"
export OPENBLAS_NUM_THREADS=1
# case matrix row u seed: what the case injects
cases=(
  "ratchet-clean thesis-hold-ratchet clean 0.5 3"
  "ratchet-modulus thesis-hold-ratchet modulus 0.5 3"
  "ratchet-temperature thesis-hold-ratchet temperature 0.5 3"
  "lcf-softening thesis-hold-lcf softening 0.3 3"
  "relax-softening thesis-hold-relax softening 0.55 5"
  "relax-softening-colder thesis-hold-relax softening-colder 0.63 7"
  "specimen-gain specimen gain 0.0 11"
)
for c in "${cases[@]}"; do
  read -r name matrix row u seed <<< "$c"
  dir=data/independent-$name
  rm -rf "$dir"
  python3 bench/independent/selfcheck.py --make "$matrix" "$row" "$u" "$seed" "$dir" > /dev/null
  {
    echo "! Data made by bench/independent/selfcheck.py --make $matrix $row $u $seed (Python and"
    echo "! scipy's Radau, not usharp; made again by bash bench/independent/test-data.sh): the"
    echo "! tests of its matrix '$matrix', injected effect '$row' at u = $u of its range, 0.5 % noise. Read by"
    echo "! test/test_diagnose_data.f90."
    sed "s#out_dir = 'out'#out_dir = '../../build/test-scratch/independent-$name'#" "$dir/diagnose.nml"
  } > "$dir/diagnose.tmp"
  mv "$dir/diagnose.tmp" "$dir/diagnose.nml"
  echo "$dir"
done
