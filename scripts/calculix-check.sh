#!/usr/bin/env bash
# Proof inside a real FE code: build CalculiX (Debian's own source package) with external
# behaviour support once, cached outside the repository, load the Miller UMAT as
# @ABAQUS_MILLER from libMILLER.so (built from the single-file fixed-form CalculiX source),
# run the shipped examples: a C3D8 unit cube under the thesis's LCF and relaxation histories,
# compared with usharp's uniaxial driver (and the same cubes with the Chaboche model's UMAT),
# and the axisymmetric notched bar under cyclic load,
# compared with a refined-increment reference, with the Newton iterations measured.
# Exit 0: compared and within limits; 77: skipped (the reason is printed); other: failed.
# The cache folder: $USHARP_CCX_CACHE (default ~/.cache/usharp-ccx).
set -uo pipefail
here="$(cd "$(dirname "$0")/.." && pwd)"
. "$here/scripts/release-flags.sh"
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
(cd "$here" && fpm build --profile release --flag "$FLAGS" >/dev/null 2>&1) \
  || fail "usharp did not build"
exe="$here/$(cd "$here" && fpm run --profile release --flag "$FLAGS" --runner 2>/dev/null | tail -n 1)"

cat > "$work/driver.nml" <<'NML'
&model name='miller', units='ksi', temperature=866.15, tm=1800.0, youngs=22.5e3, poisson=0.3 /
&constants a1=0.8, a2=7.42e-5, b=1.0e15, c2=0.1, h1=280.0, h2=100.0, n=5.8, q=91000.0 /
&output out_dir='driver' /
&test name='lcf', history='thesis_lcf', dt_out=0.05 /
&test name='relax', history='relaxation', dt_out=0.05 /
NML
(cd "$work" && "$exe" simulate driver.nml -q) || fail "usharp simulate failed"

# The shipped C3D8 unit-cube decks (examples/fe/cube): uniaxial stress by symmetry planes,
# axial displacement on the top face, one *STEP per segment of the history
for t in lcf relax; do cp "$here/examples/fe/cube/cube-$t.inp" "$work/$t.inp" || fail "examples/fe/cube/cube-$t.inp missing"; done
# Run cube t in folder d with the libraries of d/lib; its axial and lateral stresses per time
# (.dat: per increment a header with the time, then 'elem ip sxx syy szz sxy sxz syz') into
# d/t.ccx.txt
run_cube() { # folder, test
  local d="$1" t="$2"
  (cd "$d" && LD_LIBRARY_PATH="$d/lib:${LD_LIBRARY_PATH:-}" OMP_NUM_THREADS=1 timeout 1200 "$ccx" -i "$t" > "$t.log" 2>&1) \
    || { tail -5 "$d/$t.log"; fail "ccx did not finish the $t cube (see $d/$t.log)"; }
  awk '/stresses \(elem/ { t = $NF; next } NF == 8 && $1 == 1 { n[t]++; sz[t] += $5; sx[t] += $3; sy[t] += $4 }
       END { for (k in n) printf "%.10g %.10g %.10g %.10g\n", k, sz[k]/n[k], sx[k]/n[k], sy[k]/n[k] }' \
       "$d/$t.dat" | sort -g > "$d/$t.ccx.txt"
  [ -s "$d/$t.ccx.txt" ] || fail "no stresses in $d/$t.dat"
}
# Compare d/t.ccx.txt with the driver's curve d/driver/t.sim.txt interpolated at the ccx
# times: within 1 % of peak, lateral stress below 1e-6 of peak
compare_cube() { # folder, test, label, stress unit
  awk -v test="$3: $2" -v unit="$4" 'NR == FNR { if ($1 !~ /^#/) { n++; td[n] = $1; sd[n] = $3 }; next }
       { while (j < n - 1 && td[j + 1] < $1) j++; if (j < 1) j = 1
         w = ($1 - td[j]) / (td[j + 1] - td[j]); s = (1 - w) * sd[j] + w * sd[j + 1]
         d = $2 - s; if (d < 0) d = -d; if (d > dmax) dmax = d
         p = s < 0 ? -s : s; if (p > peak) peak = p
         l = ($3 < 0 ? -$3 : $3); if (($4 < 0 ? -$4 : $4) > l) l = ($4 < 0 ? -$4 : $4); if (l > lat) lat = l; m++ }
       END { printf "calculix-check: %s: %d increments, max |ccx - driver| / peak = %.3e (peak %.3f %s), max |lateral stress| = %.2e %s\n", test, m, dmax / peak, peak, unit, lat, unit
             exit (dmax / peak <= 0.01 && lat <= 1e-6 * peak) ? 0 : 1 }' \
       "$1/driver/$2.sim.txt" "$1/$2.ccx.txt"
}
status=0
for t in lcf relax; do
  run_cube "$work" "$t"
  compare_cube "$work" "$t" "Miller" ksi || status=1
done
[ $status -eq 0 ] || fail "CalculiX and the uniaxial driver differ by more than 1 % of peak, or lateral stress not zero"
# The expected table shipped with the cube (axial stress at the ends of the history's segments)
[ -s "$here/examples/fe/cube/expected.txt" ] || fail "examples/fe/cube/expected.txt missing"
awk 'FILENAME ~ /expected/ { if ($1 !~ /^#/ && NF >= 3) e[$1 " " sprintf("%.4f", $2)] = $3; next }
     { np = split(FILENAME, p, "/"); t = p[np]; sub(/\.ccx\.txt$/, "", t); k = t " " sprintf("%.4f", $1)
       if (k in e) { n++; d = $2 - e[k]; if (d < 0) d = -d; if (d > dm) dm = d } }
     END { printf "calculix-check: cube: %d segment ends against examples/fe/cube/expected.txt, max diff %.2e ksi\n", n, dm
           exit (n >= 20 && dm <= 1e-3) ? 0 : 1 }' "$here/examples/fe/cube/expected.txt" "$work/lcf.ccx.txt" "$work/relax.ccx.txt" \
  || fail "the cube differs from examples/fe/cube/expected.txt"

# The Chaboche model's drop-in in the same cubes: its library from the single CalculiX file,
# the Miller decks with the Chaboche material card (15 constants, 19 state variables; MPa),
# against usharp's uniaxial driver
ch="$work/chaboche"
bash "$here/scripts/build-umat.sh" --check "$work/umat-chaboche" CHABOCHE chaboche >/dev/null \
  || fail "the Chaboche UMAT library did not build"
mkdir -p "$ch/lib" && cp "$work/umat-chaboche/check-umat_chaboche_calculix/libCHABOCHE.so" "$ch/lib/" \
  || fail "the single-file Chaboche UMAT library is missing"
cat > "$ch/driver.nml" <<'NML'
&model name='chaboche', units='MPa', temperature=866.15, tm=1800.0, youngs=144000.0, poisson=0.3 /
&constants s0=10.0, eta=500.0, n=5.0, q=30.0, b=20.0, c1=8.0e4, g1=1500.0, c2=5.0e3, g2=60.0,
  a1=1.0e-7, m1=2.0, a2=1.0e-6, m2=3.0 /
&output out_dir='driver' /
&test name='lcf', history='thesis_lcf', dt_out=0.05 /
&test name='relax', history='relaxation', dt_out=0.05 /
NML
(cd "$ch" && "$exe" simulate driver.nml -q) || fail "usharp simulate failed (Chaboche)"
for t in lcf relax; do
  awk 'BEGIN { skip = 0 }
       /^\*USER MATERIAL/ { print "*USER MATERIAL,CONSTANTS=15"
                            print "144000.,0.3,10.,500.,5.,30.,20.,80000.,"
                            print "1500.,5000.,60.,1.E-7,2.,1.E-6,3."; skip = 2; next }
       skip > 0 { skip--; next }
       /^\*DEPVAR/ { print; getline; print "19"; next }
       { gsub(/@ABAQUS_MILLER/, "@ABAQUS_CHABOCHE"); print }' "$work/$t.inp" > "$ch/$t.inp"
  grep -q "CONSTANTS=15" "$ch/$t.inp" || fail "the Chaboche cube deck $ch/$t.inp was not written"
  run_cube "$ch" "$t"
  compare_cube "$ch" "$t" "Chaboche" MPa || status=1
done
[ $status -eq 0 ] || fail "Chaboche: CalculiX and the uniaxial driver differ by more than 1 % of peak, or lateral stress not zero"

# An unusable constant (A1 < 0): one line naming it on standard output per element and attempt,
# then CalculiX cuts the increment below its minimum and stops with an error
mkdir -p "$work/bad"
sed 's/^22500.,0.3,0.8,/22500.,0.3,-0.8,/' "$work/relax.inp" > "$work/bad/bad.inp"
(cd "$work/bad" && LD_LIBRARY_PATH="$work/lib:${LD_LIBRARY_PATH:-}" OMP_NUM_THREADS=1 timeout 300 "$ccx" -i bad > ccx.log 2>&1)
rc=$?
nmsg=$(grep -c "usharp Miller material @ABAQUS_MILLER: constant A1 must be > 0" "$work/bad/ccx.log")
echo "calculix-check: A1 < 0: ccx exit $rc, $nmsg message lines: $(grep -m1 'usharp Miller material' "$work/bad/ccx.log")"
[ "$rc" -ne 0 ] && [ "$nmsg" -ge 1 ] && [ "$nmsg" -le 4 ] && grep -q "increment size smaller than minimum" "$work/bad/ccx.log" \
  || fail "a material with A1 < 0 did not stop CalculiX with a message naming A1"

# The axisymmetric notched bar (examples/fe/notched-bar): the shipped deck (fixed 0.75 s
# increments, CalculiX's default Newton tolerances) against a reference with 0.25 s
# increments and tolerances of 1e-9, whose residuals show the Newton's order near the solution
nb="$here/examples/fe/notched-bar"
mkdir -p "$work/nb" "$work/nb-gen" "$work/nb-ref"
bash "$nb/make-notched-bar.sh" "$work/nb-gen" >/dev/null || fail "make-notched-bar.sh failed"
for f in notched-bar.inp notched-bar-abaqus.inp notched-bar-ansys.mac; do
  cmp -s "$nb/$f" "$work/nb-gen/$f" || fail "examples/fe/notched-bar/$f is not what make-notched-bar.sh writes"
done
cp "$nb/notched-bar.inp" "$work/nb/"
bash "$nb/make-notched-bar.sh" "$work/nb-ref" 0.25 tight >/dev/null || fail "make-notched-bar.sh failed"
for d in nb nb-ref; do
  (cd "$work/$d" && LD_LIBRARY_PATH="$work/lib:${LD_LIBRARY_PATH:-}" OMP_NUM_THREADS=1 timeout 1200 "$ccx" -i notched-bar > ccx.log 2>&1) \
    || { tail -5 "$work/$d/ccx.log"; fail "ccx did not finish the notched bar in $work/$d"; }
done
# Axial reaction force of the top per time: 'total force (fx,fy,fz) for set TOP and time T', a
# blank line, then the three components
rf() { awk '/total force .* for set TOP/ { t = $NF; getline; getline; printf "%.10g %.10g\n", t, $2 }' "$1"; }
rf "$work/nb/notched-bar.dat" > "$work/nb/rf.txt"
rf "$work/nb-ref/notched-bar.dat" > "$work/nb-ref/rf.txt"
[ -s "$work/nb/rf.txt" ] && [ -s "$work/nb-ref/rf.txt" ] || fail "no reaction forces in the notched-bar .dat files"
awk 'NR == FNR { ref[sprintf("%.4f", $1)] = $2; if (($2 < 0 ? -$2 : $2) > peak) peak = ($2 < 0 ? -$2 : $2); next }
     { k = sprintf("%.4f", $1); if (!(k in ref)) next; d = $2 - ref[k]; if (d < 0) d = -d; if (d > dmax) dmax = d; n++ }
     END { printf "calculix-check: notched bar: %d increments compared, max |RF(0.75 s) - RF(0.25 s)| / peak = %.3e (peak %.4f ksi mm^2 on the 2-degree segment)\n", n, dmax / peak, peak
           exit (n >= 90 && dmax / peak <= 0.01) ? 0 : 1 }' "$work/nb-ref/rf.txt" "$work/nb/rf.txt" || status=1
# Newton iterations per increment (.sta: STEP INC ATT ITRS ...)
for d in nb nb-ref; do
  awk -v d="$d" 'NR > 2 && NF >= 7 { n++; s += $4; if ($4 > m) m = $4; h[$4]++ }
       END { printf "calculix-check: notched bar %s: %d increments, Newton iterations per increment mean %.2f, max %d (", d, n, s / n, m
             for (k = 1; k <= m; k++) if (h[k]) printf " %dx%d", h[k], k; print " )" }' "$work/$d/notched-bar.sta"
done
# Order near the solution from the reference's residual forces (.cvg, % of the mean force):
# p = log(r[k+1]) / log(r[k]) for consecutive iterations once r[k] < 1 %
awk 'NR > 4 && NF >= 9 { key = $1 " " $2 " " $3; r = $6 / 100
       if (key == last && prev > 0 && prev < 0.01 && r > 0) { p[++n] = log(r) / log(prev) }
       last = key; prev = r }
     END { if (n == 0) { print "calculix-check: notched bar: no residual pairs to measure the order"; exit 1 }
           for (i = 1; i <= n; i++) for (j = i + 1; j <= n; j++) if (p[j] < p[i]) { t = p[i]; p[i] = p[j]; p[j] = t }
           printf "calculix-check: notched bar reference: order of the global Newton near the solution, median %.2f (quartiles %.2f, %.2f; %d pairs)\n", p[int((n + 1) / 2)], p[int((n + 3) / 4)], p[int((3 * n + 1) / 4)], n
           exit (p[int((n + 1) / 2)] >= 1.6) ? 0 : 1 }' "$work/nb-ref/notched-bar.cvg" || status=1
# The expected table shipped with the example (reaction force at the ramp ends)
awk 'NR == FNR { if ($1 !~ /^#/ && NF >= 2) e[sprintf("%.4f", $1)] = $2; next }
     { k = sprintf("%.4f", $1); if (k in e) { n++; d = ($2 - e[k]) / e[k]; if (d < 0) d = -d; if (d > dm) dm = d } }
     END { printf "calculix-check: notched bar: %d ramp ends against examples/fe/notched-bar/expected.txt, max rel. diff %.2e\n", n, dm
           exit (n == 3 && dm <= 1e-3) ? 0 : 1 }' "$nb/expected.txt" "$work/nb/rf.txt" || status=1
[ $status -eq 0 ] || fail "notched bar: increments not converged to 1 %, Newton not quadratic, or results differ from expected.txt"
echo "calculix-check: PASS"
