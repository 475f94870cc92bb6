"""The thesis's run 2 objective per evaluation: usharp against a scipy Radau script at the
same accuracy. Reads usharp's simulations of the run's two tests at its start constants
(usharp simulate decks/thesis-run2.nml, the .sim.txt files given), integrates the same
uniaxial Miller model (Eqs. 2-5 of the technical reference, written here independently) with
scipy's Radau from segment to segment of the strain history, and reports:
- the error of usharp and of Radau at several tolerances against Radau at rtol 1e-11
  (max |stress difference| / peak stress),
- Radau's wall time for the two tests at each tolerance (best of 3), and its evaluations of
  the rates (its finite-difference Jacobians' included) against usharp's,
- the cheapest tolerance at which Radau is at least as accurate as usharp, and the ratio of
  its time to usharp's per-evaluation time (given in ms, from bench_measured),
- Radau's time at exactly usharp's accuracy, interpolated (log-log) between the tolerances
  around it (the decade steps overshoot it).
Usage: python3 scipy_compare.py USHARP_MS LCF.sim.txt RELAX.sim.txt [USHARP_RATE_EVALUATIONS]
"""
import math
import sys
import time

import numpy as np
from scipy.integrate import solve_ivp

K_GAS = 1.9859  # cal/(mol K)


def read_sim(path):
    """Header values (T, Tm, E, D0, constants) and the columns of a usharp .sim.txt"""
    head = {}
    with open(path) as f:
        for line in f:
            if not line.startswith('#'):
                break
            words = line.replace(',', ' ').split()
            for i, w in enumerate(words):
                if i + 2 < len(words) and words[i + 1] == '=':
                    try:
                        head[w] = float(words[i + 2])
                    except ValueError:
                        pass
    return head, np.loadtxt(path)


def corners(name):
    """Strain corners of the thesis's LCF and relaxation tests (reference, Section 2)"""
    if name == 'lcf':
        m = (0.005 / 0.0005) ** (1.0 / 11.0)
        t, v = [0.0], [0.0]
        for k in range(12):
            t += [(2 * k + 1) * 10.0, (2 * k + 2) * 10.0]
            v += [0.0005 * m ** k * (1 if k % 2 == 0 else -1), 0.0]
        return np.array(t), np.array(v)
    return np.array([0.0, 1.0, 601.0, 602.0, 1202.0]), np.array([0.0, 7.5e-4, 7.5e-4, 1e-3, 1e-3])


def simulate(head, tc, vc, tout, rtol, atol):
    c = head
    T, Tm, E = c['T'], c['Tm'], c['E']
    x = 0.6 * Tm
    th = math.exp(-c['Q'] / (K_GAS * T)) if T > x else \
        math.exp(-c['Q'] / (0.6 * K_GAS * Tm) * (math.log(x / T) + 1.0))
    bth, n = c['B'] * th, c['n']

    def rates(t, y, k):
        eps_in, R, D = y
        # Newton iterates of a loose tolerance may leave the model (D <= 0): keep them finite
        D = max(D, 1e-12)
        s = E * (vc[k] + (vc[k + 1] - vc[k]) * (t - tc[k]) / (tc[k + 1] - tc[k]) - eps_in) - R
        f = bth * math.sinh(min((abs(s) / D) ** 1.5, 700.0)) ** n
        de = math.copysign(f, s)
        dR = c['H1'] * de - c['H1'] * bth * math.sinh(min(c['A1'] * abs(R), 700.0)) ** n * np.sign(R)
        dD = c['H2'] * f * (c['C2'] + abs(R) - c['A2'] / c['A1'] * D ** 3) \
            - c['H2'] * c['C2'] * bth * math.sinh(min(c['A2'] * D ** 3, 700.0)) ** n
        return [de, dR, dD]

    y = [0.0, 0.0, c['D0']]
    sig = np.empty(len(tout))
    nfev = 0
    for k in range(len(tc) - 1):
        last = k == len(tc) - 2
        sel = np.where((tout >= tc[k]) & ((tout <= tc[k + 1]) if last else (tout < tc[k + 1])))[0]
        te = np.union1d(tout[sel], [tc[k + 1]])
        sol = solve_ivp(rates, (tc[k], tc[k + 1]), y, method='Radau', t_eval=te, args=(k,),
                        rtol=rtol, atol=[atol, atol * E, atol * E])
        if not sol.success:
            raise RuntimeError(sol.message)
        # scipy's count leaves out the finite-difference Jacobians' columns (one each)
        nfev += sol.nfev + len(y) * sol.njev
        for j, i in enumerate(sel):
            sig[i] = E * (vc[k] + (vc[k + 1] - vc[k]) * (tout[i] - tc[k]) / (tc[k + 1] - tc[k])
                          - sol.y[0, j])
        y = list(sol.y[:, -1])
    return sig, nfev


def main():
    usharp_ms = float(sys.argv[1])
    usharp_rhs = int(sys.argv[4]) if len(sys.argv) > 4 else 0
    tests = []
    for path, name in zip(sys.argv[2:4], ['lcf', 'relax']):
        head, cols = read_sim(path)
        tests.append((name, head, cols[:, 0], cols[:, 2]))
    refs = [simulate(h, *corners(nm), t, 1e-11, 1e-15)[0] for nm, h, t, _ in tests]
    peak = [np.max(np.abs(r)) for r in refs]
    err_u = max(np.max(np.abs(s - r)) / p for (_, _, _, s), r, p in zip(tests, refs, peak))
    print('usharp (RODAS4, default tolerances): max |stress - reference| / peak %.2e, '
          '%.3f ms per evaluation (bench_measured)' % (err_u, usharp_ms))
    if usharp_rhs:
        print('usharp: %d rate evaluations, %.3f us each' % (usharp_rhs, 1e3 * usharp_ms / usharp_rhs))
    print('%-22s %12s %14s %10s %12s %10s' % ('scipy Radau', 'max err/peak', 'ms (2 tests)', 'ratio',
                                              'rate evals', 'us each'))
    chosen = None
    curve = []
    for rtol in [1e-4, 1e-5, 1e-6, 1e-7, 1e-8]:
        atol = rtol * 1e-3
        best = float('inf')
        for _ in range(3):
            t0 = time.perf_counter()
            runs = [simulate(h, *corners(nm), t, rtol, atol) for nm, h, t, _ in tests]
            best = min(best, time.perf_counter() - t0)
        sims = [r[0] for r in runs]
        nfev = sum(r[1] for r in runs)
        err = max(np.max(np.abs(s - r)) / p for s, r, p in zip(sims, refs, peak))
        ms = best * 1e3
        print('rtol %-8.0e atol %-6.0e %12.2e %14.1f %10.0f %12d %10.1f'
              % (rtol, atol, err, ms, ms / usharp_ms, nfev, 1e3 * ms / nfev))
        if chosen is None and err <= err_u:
            chosen = (rtol, ms)
        curve.append((err, ms))
    if chosen:
        print('same accuracy: Radau at rtol %.0e costs %.0f times usharp per evaluation'
              % (chosen[0], chosen[1] / usharp_ms))
        # The decade steps of rtol overshoot usharp's accuracy; log-log between the two
        # tolerances around it, Radau's cost at exactly that accuracy
        for (e1, m1), (e2, m2) in zip(curve, curve[1:]):
            if e1 > err_u >= e2:
                w = math.log(e1 / err_u) / math.log(e1 / e2)
                ms_at = m1 * (m2 / m1) ** w
                print('at exactly usharp\'s accuracy (log-log between those two tolerances): '
                      '%.0f ms, %.0f times usharp' % (ms_at, ms_at / usharp_ms))
                break
    else:
        print('Radau did not reach usharp\'s accuracy at rtol down to 1e-8')


if __name__ == '__main__':
    main()
