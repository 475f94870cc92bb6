"""Independent reference for a thermomechanical test of the Miller model: a strain-controlled
triangle wave whose temperature follows the strain command linearly (in phase: the highest
temperature at the largest strain; out of phase: at the smallest), integrated with scipy's
Radau at tight tolerances. It shares no code with usharp: theta(T) and D0 come from
miller_ref.py (taken from the technical reference, Eq. 5 and the D0 formula); the temperature
enters the rates only through B*theta(T(t)), and D0 is that of the temperature at t = 0.

Units: ksi, s, K. Writes CSV: time, strain, stress, temperature.
usage: python3 tmf_ref.py OUT.csv [--tmin K] [--tmax K] [--phase in|out] [--range strain]
                          [--rate 1/s] [--cycles N] [--dt s] [--q cal/mol]
"""
import argparse
import math
import os
# One BLAS thread: numpy's OpenBLAS sums in an order set by its thread count, and the
# data made here must not change with the caller's OMP_NUM_THREADS
os.environ['OPENBLAS_NUM_THREADS'] = '1'

import numpy as np
from scipy.integrate import solve_ivp

from miller_ref import TABLE4, E_NOM, theta, drag0, cyclic


def simulate(tc, vc, tout, tmin, tmax, phase, c):
    vmin, vmax = vc.min(), vc.max()

    def temperature(eps):
        u = (eps - vmin) / (vmax - vmin)
        if phase == 'out':
            u = 1.0 - u
        return tmin + (tmax - tmin) * u

    def command(t, k):
        s = (vc[k + 1] - vc[k]) / (tc[k + 1] - tc[k])
        return vc[k] + s * (t - tc[k])

    def rates(t, y, k):
        eps = command(t, k)
        bth = c['B'] * theta(temperature(eps), c['Q'])
        eps_in, R, D = y
        s = E_NOM * (eps - eps_in) - R
        x = min((abs(s) / max(D, 1e-6)) ** 1.5, 50.0)
        f = bth * math.sinh(x) ** c['n']
        de = math.copysign(f, s)
        dR = c['H1'] * de - c['H1'] * bth * math.sinh(min(c['A1'] * abs(R), 50.0)) ** c['n'] * np.sign(R)
        dD = c['H2'] * f * (c['C2'] + abs(R) - c['A2'] / c['A1'] * D ** 3) \
            - c['H2'] * c['C2'] * bth * math.sinh(min(c['A2'] * abs(D) ** 3, 50.0)) ** c['n']
        return [de, dR, dD]

    y = [0.0, 0.0, drag0(c, theta(temperature(vc[0]), c['Q']))]
    sig = np.empty(len(tout))
    for k in range(len(tc) - 1):
        last = k == len(tc) - 2
        sel = np.where((tout >= tc[k]) & ((tout <= tc[k + 1]) if last else (tout < tc[k + 1])))[0]
        teval = np.union1d(tout[sel], [tc[k + 1]])
        sol = solve_ivp(rates, (tc[k], tc[k + 1]), y, method='Radau', t_eval=teval, args=(k,),
                        rtol=1e-11, atol=[1e-15, 1e-11, 1e-11])
        if not sol.success:
            raise RuntimeError('integration failed: ' + sol.message)
        for i in sel:
            j = np.searchsorted(sol.t, tout[i])
            eps_in, R, _ = sol.y[:, j]
            sig[i] = E_NOM * (command(tout[i], k) - eps_in)
        y = list(sol.y[:, -1])
    eps = np.interp(tout, tc, vc)
    return eps, sig, np.array([temperature(e) for e in eps])


def main():
    p = argparse.ArgumentParser()
    p.add_argument('out')
    p.add_argument('--tmin', type=float, default=811.15)
    p.add_argument('--tmax', type=float, default=922.15)
    p.add_argument('--phase', choices=['in', 'out'], default='in')
    p.add_argument('--range', type=float, default=0.01)
    p.add_argument('--rate', type=float, default=1.0e-4)
    p.add_argument('--cycles', type=int, default=2)
    p.add_argument('--dt', type=float, default=1.0)
    p.add_argument('--q', type=float, default=TABLE4['Q'])
    a = p.parse_args()
    c = dict(TABLE4, Q=a.q)
    _, tc, vc = cyclic(a.range, a.rate, a.cycles)
    t = np.union1d(np.round(np.arange(0.0, tc[-1] + 1e-9, a.dt), 9), tc)
    eps, sig, temp = simulate(tc, vc, t, a.tmin, a.tmax, a.phase, c)
    with open(a.out, 'w') as f:
        f.write('time,strain,stress,temperature\n')
        for row in zip(t, eps, sig, temp):
            f.write('{:.6f},{:.12e},{:.12e},{:.6f}\n'.format(*row))


if __name__ == '__main__':
    main()
