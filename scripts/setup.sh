#!/usr/bin/env bash
# Install what usharp needs to build and test, without prompts; a no-op when all is present.
# Debian packages: gfortran, LAPACK/BLAS, SUNDIALS 6 Fortran 2003 interface, Open MPI, gnuplot,
# GNU time. PyPI: fpm, numpy and scipy (the independent references of bench/).
set -euo pipefail

command -v python3 >/dev/null 2>&1 || need_py=1
need_apt=()
[ -n "${need_py:-}" ] && need_apt+=(python3 python3-pip)
command -v gfortran >/dev/null 2>&1 || need_apt+=(gfortran)
# CVODE(S) and ARKODE (ARKStep) with their Fortran 2003 modules
{ [ -e /usr/include/sundials/fortran/fcvode_mod.mod ] && [ -e /usr/include/sundials/fortran/farkode_arkstep_mod.mod ]; } ||
  need_apt+=(libsundials-fortran-dev libsundials-dev)
ls /usr/lib/x86_64-linux-gnu/liblapack.so* >/dev/null 2>&1 || ls /usr/lib/*/liblapack.so >/dev/null 2>&1 || need_apt+=(liblapack-dev)
ls /usr/lib/*/libblas.so >/dev/null 2>&1 || need_apt+=(libblas-dev)
# Open MPI: the compiler wrapper, mpirun and the mpi_f08 module (spreads work over ranks)
{ command -v mpirun >/dev/null 2>&1 && command -v mpif90 >/dev/null 2>&1; } ||
  need_apt+=(libopenmpi-dev openmpi-bin)
# gnuplot draws the fit plots (scripts/plot-fit.sh); usharp itself runs without it
command -v gnuplot >/dev/null 2>&1 || need_apt+=(gnuplot-nox)
# GNU time: bench/diagnose.sh measures processor time and memory with it
[ -x /usr/bin/time ] || need_apt+=(time)

if [ ${#need_apt[@]} -gt 0 ]; then
  echo "setup: installing Debian packages: ${need_apt[*]}" >&2
  sudo_cmd=""
  [ "$(id -u)" -eq 0 ] || sudo_cmd="sudo"
  export DEBIAN_FRONTEND=noninteractive
  $sudo_cmd apt-get update -qq
  $sudo_cmd apt-get install -y -qq --no-install-recommends "${need_apt[@]}" >/dev/null
fi

# include/openmpi points fpm at the folder of mpi_f08.mod (Debian's on x86_64); elsewhere the
# link is pointed at the folder the MPI wrapper names
here="$(cd "$(dirname "$0")/.." && pwd)"
if [ ! -e "$here/include/openmpi/mpi_f08.mod" ] && command -v mpif90 >/dev/null 2>&1; then
  for d in $(mpif90 --showme:incdirs 2>/dev/null); do
    if [ -e "$d/mpi_f08.mod" ]; then
      ln -sfn "$d" "$here/include/openmpi"
      echo "setup: include/openmpi -> $d" >&2
      break
    fi
  done
fi

if ! command -v fpm >/dev/null 2>&1; then
  echo "setup: installing fpm from PyPI" >&2
  python3 -m pip install --quiet --disable-pip-version-check 'fpm>=0.12,<0.13' 2>/dev/null \
    || python3 -m pip install --quiet --disable-pip-version-check --break-system-packages 'fpm>=0.12,<0.13'
  hash -r
fi
# numpy and scipy make the independent references of bench/ (bench/independent: the
# diagnosis's self-check on data usharp did not make; the tests read such data kept in data/).
# Installed at the versions the benches were checked with: another scipy's solve_ivp may move
# a case that lies near a verdict's threshold (an installed numpy and scipy are used as they are)
py_pins=(numpy==2.4.6 scipy==1.17.1)
if ! python3 -c 'import numpy, scipy' >/dev/null 2>&1; then
  echo "setup: installing ${py_pins[*]} from PyPI" >&2
  python3 -m pip install --quiet --disable-pip-version-check "${py_pins[@]}" 2>/dev/null \
    || python3 -m pip install --quiet --disable-pip-version-check --break-system-packages "${py_pins[@]}" \
    || echo "setup: numpy/scipy not installed: bench/independent and bench/scipy_compare.sh need them" >&2
fi
command -v pyenv >/dev/null 2>&1 && pyenv rehash 2>/dev/null || true
command -v fpm >/dev/null 2>&1 || { echo "setup: fpm not on PATH after install" >&2; exit 1; }
