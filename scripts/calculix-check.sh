#!/usr/bin/env bash
# Proof inside a real FE code: build CalculiX (Debian's own source package) with external
# behaviour support once, cached outside the repository, load the Miller UMAT as
# @ABAQUS_MILLER from libMILLER.so, run a single C3D8 unit cube under the thesis's LCF and
# relaxation histories and compare its stresses with usharp's uniaxial driver.
# Exit 0: compared and within limits; 77: skipped (the reason is printed); other: failed.
# The cache folder: $USHARP_CCX_CACHE (default ~/.cache/usharp-ccx).
set -uo pipefail
here="$(cd "$(dirname "$0")/.." && pwd)"
cache="${USHARP_CCX_CACHE:-$HOME/.cache/usharp-ccx}"
work="${1:-$here/build/calculix-check}"
ccx="$cache/ccx-external"
skip() { echo "calculix-check: SKIP: $*"; exit 77; }
fail() { echo "calculix-check: FAIL: $*"; exit 1; }

build_ccx() {
  command -v apt-get >/dev/null 2>&1 || skip "no apt-get: CalculiX's Debian source cannot be fetched here"
  sudo_cmd=""
  if [ "$(id -u)" -ne 0 ]; then
    command -v sudo >/dev/null 2>&1 && sudo -n true 2>/dev/null || skip "not root and no sudo: cannot install build dependencies"
    sudo_cmd="sudo -n"
  fi
  mkdir -p "$cache" || skip "cannot create the cache folder $cache"
  srclist=/etc/apt/sources.list.d/usharp-deb-src.sources
  if ! grep -rqs "deb-src" /etc/apt/sources.list /etc/apt/sources.list.d/ ; then
    codename=$(. /etc/os-release && echo "${VERSION_CODENAME:-bookworm}")
    printf 'Types: deb-src\nURIs: http://deb.debian.org/debian\nSuites: %s %s-updates\nComponents: main\nSigned-By: /usr/share/keyrings/debian-archive-keyring.gpg\n' \
      "$codename" "$codename" | $sudo_cmd tee "$srclist" >/dev/null || skip "cannot enable deb-src entries"
  fi
  export DEBIAN_FRONTEND=noninteractive
  $sudo_cmd apt-get update -qq >/dev/null 2>&1 || skip "apt-get update failed (no network to Debian?)"
  $sudo_cmd apt-get install -y -qq --no-install-recommends dpkg-dev make gcc gfortran libarpack2-dev \
    libspooles-dev liblapack-dev libblas-dev >/dev/null 2>&1 || skip "build dependencies could not be installed"
  (cd "$cache" && rm -rf calculix-ccx-* && apt-get source -qq calculix-ccx >/dev/null 2>&1) \
    || skip "apt-get source calculix-ccx failed"
  src=$(ls -d "$cache"/calculix-ccx-*/ccx_*/src 2>/dev/null | head -n 1)
  [ -n "$src" ] || skip "CalculiX source tree not found after apt-get source"
  ver=$(basename "$(dirname "$src")")
  echo "calculix-check: building $ver with -DCALCULIX_EXTERNAL_BEHAVIOURS_SUPPORT (about a minute)"
  make -C "$src" -j"$(nproc)" \
    CFLAGS="-O2 -I/usr/include/spooles -DARCH=\"Linux\" -DSPOOLES -DARPACK -DMATRIXSTORAGE -DCALCULIX_EXTERNAL_BEHAVIOURS_SUPPORT" \
    FFLAGS="-O2 -fallow-argument-mismatch" LIBS="-lspooles -lpthread -larpack -llapack -lblas -lm -lc -ldl" \
    > "$cache/build.log" 2>&1 || fail "CalculiX build failed, see $cache/build.log"
  cp "$src/$ver" "$ccx" || fail "built ccx not found"
}

[ -x "$ccx" ] || build_ccx
[ -x "$ccx" ] || skip "no CalculiX binary with external behaviours"

rm -rf "$work"; mkdir -p "$work"
# The library from the single-file CalculiX source, compiled in fixed form as a user would
bash "$here/scripts/build-umat.sh" --check "$work/umat" MILLER >/dev/null || fail "the UMAT library did not build"
mkdir -p "$work/lib" && cp "$work/umat/check-umat_miller_calculix/libMILLER.so" "$work/lib/" \
  || fail "the single-file UMAT library is missing"

# usharp's uniaxial driver on the same histories, output every 0.05 s
(cd "$here" && fpm build --profile release --flag "-I/usr/include/sundials/fortran" >/dev/null 2>&1) \
  || fail "usharp did not build"
exe="$here/$(cd "$here" && fpm run --profile release --flag "-I/usr/include/sundials/fortran" --runner 2>/dev/null | tail -n 1)"

cat > "$work/driver.nml" <<'NML'
&model name='miller', units='ksi', temperature=866.15, tm=1800.0, youngs=22.5e3, poisson=0.3 /
&constants a1=0.8, a2=7.42e-5, b=1.0e15, c2=0.1, h1=280.0, h2=100.0, n=5.8, q=91000.0 /
&output out_dir='driver' /
&test name='lcf', history='thesis_lcf', dt_out=0.05 /
&test name='relax', history='relaxation', dt_out=0.05 /
NML
(cd "$work" && "$exe" simulate driver.nml -q) || fail "usharp simulate failed"

# One C3D8 unit cube: uniaxial stress by symmetry planes, axial displacement on the top face
write_deck() { # name, corner points (time,strain per line)
  {
    echo "*NODE"
    echo "1,0,0,0"; echo "2,1,0,0"; echo "3,1,1,0"; echo "4,0,1,0"
    echo "5,0,0,1"; echo "6,1,0,1"; echo "7,1,1,1"; echo "8,0,1,1"
    echo "*ELEMENT,TYPE=C3D8,ELSET=CUBE"
    echo "1,1,2,3,4,5,6,7,8"
    echo "*NSET,NSET=TOP"; echo "5,6,7,8"
    echo "*NSET,NSET=ALL"; echo "1,2,3,4,5,6,7,8"
    echo "*BOUNDARY"
    echo "1,1,3"; echo "2,2,3"; echo "3,3,3"; echo "4,1,1"; echo "4,3,3"; echo "5,1,2"; echo "6,2,2"; echo "8,1,1"
    echo "*MATERIAL,NAME=@ABAQUS_MILLER"
    echo "*USER MATERIAL,CONSTANTS=13"
    echo "22500.,0.3,0.8,7.42E-5,1.E15,0.,0.1,1.9859,"
    echo "280.,100.,5.8,91000.,1800."
    echo "*DEPVAR"; echo "13"
    echo "*SOLID SECTION,ELSET=CUBE,MATERIAL=@ABAQUS_MILLER"
    echo "*INITIAL CONDITIONS,TYPE=TEMPERATURE"; echo "ALL,866.15"
    # One *STEP per segment of the history, as the thesis's APDL deck had one load step per
    # segment: the displacement ramps linearly within a step, so no increment straddles a corner
    printf '%s\n' "$2" | awk -F, 'NR > 1 { printf "*STEP,INC=1000000\n*STATIC\n%.10g,%.10g,1.E-8,0.15\n*BOUNDARY\nTOP,3,3,%.12g\n*TEMPERATURE\nALL,866.15\n*EL PRINT,ELSET=CUBE\nS\n*END STEP\n", ($1 - t0 < 0.1 ? $1 - t0 : 0.1), $1 - t0, $2 } { t0 = $1 }'
  } > "$work/$1.inp"
}
lcf_amp=$(awk 'BEGIN { m = 10^(1/11); printf "0.,0.\n"; for (k = 0; k < 12; k++) { a = 0.0005*m^k*(k%2==0?1:-1); printf "%g,%.12g\n%g,0.\n", (2*k+1)*10, a, (2*k+2)*10 } }')
write_deck lcf "$lcf_amp"
write_deck relax "$(printf '0.,0.\n1.,0.00075\n601.,0.00075\n602.,0.001\n1202.,0.001')"

status=0
for t in lcf relax; do
  (cd "$work" && LD_LIBRARY_PATH="$work/lib:${LD_LIBRARY_PATH:-}" OMP_NUM_THREADS=1 timeout 1200 "$ccx" -i "$t" > "$t.log" 2>&1) \
    || { tail -5 "$work/$t.log"; fail "ccx did not finish the $t cube (see $work/$t.log)"; }
  # .dat: per increment a header with the time, then 'elem ip sxx syy szz sxy sxz syz'
  awk '/stresses \(elem/ { t = $NF; next } NF == 8 && $1 == 1 { n[t]++; sz[t] += $5; sx[t] += $3; sy[t] += $4 }
       END { for (k in n) printf "%.10g %.10g %.10g %.10g\n", k, sz[k]/n[k], sx[k]/n[k], sy[k]/n[k] }' \
       "$work/$t.dat" | sort -g > "$work/$t.ccx.txt"
  [ -s "$work/$t.ccx.txt" ] || fail "no stresses in $work/$t.dat"
  # Compare with the driver's curve interpolated at the ccx times
  awk -v test="$t" 'NR == FNR { if ($1 !~ /^#/) { n++; td[n] = $1; sd[n] = $3 }; next }
       { while (j < n - 1 && td[j + 1] < $1) j++; if (j < 1) j = 1
         w = ($1 - td[j]) / (td[j + 1] - td[j]); s = (1 - w) * sd[j] + w * sd[j + 1]
         d = $2 - s; if (d < 0) d = -d; if (d > dmax) dmax = d
         p = s < 0 ? -s : s; if (p > peak) peak = p
         l = ($3 < 0 ? -$3 : $3); if (($4 < 0 ? -$4 : $4) > l) l = ($4 < 0 ? -$4 : $4); if (l > lat) lat = l; m++ }
       END { printf "calculix-check: %s: %d increments, max |ccx - driver| / peak = %.3e (peak %.3f ksi), max |lateral stress| = %.2e ksi\n", test, m, dmax / peak, peak, lat
             exit (dmax / peak <= 0.01 && lat <= 1e-6 * peak) ? 0 : 1 }' \
       "$work/driver/$t.sim.txt" "$work/$t.ccx.txt" || status=1
done
[ $status -eq 0 ] || fail "CalculiX and the uniaxial driver differ by more than 1 % of peak, or lateral stress not zero"
echo "calculix-check: PASS"
