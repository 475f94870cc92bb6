#!/usr/bin/env bash
# Thermomechanical cycles of the Miller model (Table 4 constants, 1 % strain range at 1e-4 /s,
# two cycles, 811.15-922.15 K in and out of phase) simulated by usharp at its default
# tolerances and by an independent reference (bench/independent/tmf_ref.py: scipy's Radau at
# rtol 1e-11, no code shared); prints the largest stress difference / peak stress per phase.
# Needs: python3 with numpy and scipy.
# usage: bash bench/tmf.sh
set -euo pipefail
cd "$(dirname "$0")/.."
. scripts/release-flags.sh
export PATH="$HOME/.local/bin:$PATH"
fpm build --profile release --flag "$FLAGS" > /dev/null
exe=$(fpm run --profile release --flag "$FLAGS" --runner echo 2>/dev/null | tail -n 1)
out=$(mktemp -d)
trap 'rm -rf "$out"' EXIT
printf '%-14s %12s %14s %12s\n' "phase" "peak (ksi)" "max |diff|" "/ peak"
for phase in in out; do
  cat > "$out/tmf.nml" <<NML
&model temperature = 866.15, tm = 1800.0, youngs = 22.5e3 /
&constants a1 = 0.8, a2 = 7.42e-5, b = 1.0e15, c2 = 0.1, h1 = 280.0, h2 = 100.0, n = 5.8, q = 91000.0 /
&test name = 'tmf', history = 'cyclic', strain_range = 0.01, strain_rate = 1.0e-4, cycles = 2,
  dt_out = 1.0, tmf_temperatures = 811.15, 922.15, tmf_phase = '$phase' /
NML
  "$exe" simulate -q -o "$out" "$out/tmf.nml"
  (cd bench/independent && python3 tmf_ref.py "$out/ref.csv" --phase "$phase" --tmin 811.15 \
    --tmax 922.15 --range 0.01 --rate 1e-4 --cycles 2 --dt 1.0)
  python3 - "$out/tmf.sim.txt" "$out/ref.csv" "$phase" <<'PY'
import sys
import numpy as np
u = np.loadtxt(sys.argv[1], comments='#')
r = np.genfromtxt(sys.argv[2], delimiter=',', names=True)
i = np.searchsorted(u[:, 0], r['time'])
assert np.allclose(u[i, 0], r['time'])
peak = np.abs(r['stress']).max()
d = np.abs(u[i, 2] - r['stress']).max()
print('%-14s %12.4f %14.3e %12.2e' % (sys.argv[3] + ' of phase', peak, d, d / peak))
PY
done
