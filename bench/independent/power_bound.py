"""What any test could find: the power of the best test for a one-parameter effect on one
specimen, against its replicates, with the data of miller_ref.py (not usharp's).

The effect acts on the specimen only (as in selfcheck.py's per-specimen matrices); the seven
fitted constants are shared by the three tests and refitted. Linearised about Table 4's
constants, with the noise known exactly (Gaussian, sd 0.5 % of each test's peak stress, as
selfcheck.py makes it), the likelihood-ratio statistic of the effect is chi-square with one
degree of freedom and non-centrality

    lambda = (magnitude * |(I - P) j|)**2

where j is the effect's sensitivity column in units of the noise and P the projection on
the constants' columns. No test can do better than this one (it knows the form, the noise and
that no other effect acts), so its power bounds that of any rule at the same false-alarm rate.
Printed for the effect's low end, the magnitudes between, and the share of a row whose
magnitudes are drawn log-uniform over the range (selfcheck.py's draw) that it finds on
average: at a 5 % and a 0.1 % false-alarm rate, and for usharp's rule (BIC falls by more
than 10: the statistic above 10 + ln m, m the points of the three tests).

usage: python3 bench/independent/power_bound.py [specimen|specimen-hold] [drift,lag,...]
(about 1-2 minutes per matrix: finite differences of scipy's Radau at rtol 1e-9)
"""
import math
import os
import sys

import numpy as np
from scipy.stats import chi2, ncx2

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
import miller_ref as ref  # noqa: E402

# The per-specimen matrices of selfcheck.py: replicates, the specimen, output interval (s)
MATRICES = {'specimen': (['c6', 'c8', 'c10'], 'c8', 0.1), 'specimen-hold': (['h6', 'h8', 'h10'], 'h8', 0.2)}
CONSTANTS = ['A1', 'A2', 'B', 'C2', 'H1', 'H2', 'n']
NOISE = 0.005


def effect_of(row, mag, t_end):
    """miller_ref's effect at magnitude mag of the row's own unit (drift: strain over the
    test; lag: s; temperature: K; modulus: share of E)"""
    return {'drift': {'drift': mag / t_end}, 'lag': {'tau': mag}, 'temperature': {'dT': mag},
            'modulus': {'delta': mag}}[row]


# Each row's range as selfcheck.py draws it (the low end first) and its unit
RANGES = {'drift': (2e-5, 1e-4, 'strain over the test'), 'lag': (0.1, 0.5, 's'),
          'temperature': (5.0, 25.0, 'K'), 'modulus': (0.03, 0.10, 'of E')}


def main():
    mname = sys.argv[1] if len(sys.argv) > 1 else 'specimen'
    rows = sys.argv[2].split(',') if len(sys.argv) > 2 else ['drift']
    tests, spec, dt = MATRICES[mname]

    def stress(name, c=ref.TABLE4, eff=None):
        control, tc, vc = ref.HISTORIES[name]()
        return ref.simulate(control, tc, vc, ref.output_grid(tc, dt), c=c, eff=eff)[1]

    base = {n: stress(n) for n in tests}
    sd = {n: NOISE * np.max(np.abs(base[n])) for n in tests}
    m = sum(base[n].size for n in tests)
    cols = []
    for p in CONSTANTS:
        h = 1e-4
        hi, lo = dict(ref.TABLE4), dict(ref.TABLE4)
        hi[p] *= 1.0 + h
        lo[p] *= 1.0 - h
        cols.append(np.concatenate([(stress(n, hi) - stress(n, lo)) / (2.0 * h * ref.TABLE4[p]) / sd[n]
                                    for n in tests]))
    q, _ = np.linalg.qr(np.array(cols).T)
    t_end = ref.HISTORIES[spec]()[1][-1]
    rules = [('LR at 5 %', chi2.ppf(0.95, 1)), ('LR at 0.1 %', chi2.ppf(0.999, 1)),
             ('usharp (BIC -10)', 10.0 + math.log(m))]
    print(f'{mname}: effect on {spec} ({t_end:.0f} s) alone, {m} points of {", ".join(tests)}')
    for row in rows:
        lo_end, hi_end, unit = RANGES[row]
        # A central difference of a small magnitude, a tenth of the low end (the lag from
        # zero: its sensitivity at zero is one-sided)
        d = 0.1 * lo_end
        if row == 'lag':
            col = (stress(spec, eff=effect_of(row, d, t_end)) - base[spec]) / d
        else:
            col = (stress(spec, eff=effect_of(row, d, t_end)) - stress(spec, eff=effect_of(row, -d, t_end))) / (2 * d)
        j = np.concatenate([col / sd[n] if n == spec else np.zeros(base[n].size) for n in tests])
        k = np.linalg.norm(j - q @ (q.T @ j))
        print(f'  {row}: range {lo_end:g}-{hi_end:g} {unit}; the constants take up '
              f'{100 * (1 - (k / np.linalg.norm(j)) ** 2):.1f} % of its signal')
        for f in [f for f in (1.0, 2.0, 3.0, 4.5) if f < hi_end / lo_end] + [hi_end / lo_end]:
            lam = (f * lo_end * k) ** 2
            power = ', '.join(f'{name} {ncx2.sf(thr, 1, lam):.2f}' for name, thr in rules)
            print(f'    {f:4.1f} x low end: lambda {lam:9.2f}; power {power}')
        u = np.linspace(0.0, 1.0, 2001)
        lam = (lo_end * (hi_end / lo_end) ** u * k) ** 2
        print('    share of the row found on average: ' +
              ', '.join(f'{name} {np.mean(ncx2.sf(thr, 1, lam)):.2f}' for name, thr in rules))


if __name__ == '__main__':
    main()
