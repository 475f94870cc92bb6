#!/usr/bin/env python3
"""Strain histories logged as a test machine logs them, simulated with `history = 'data'`
(the measured strain as smooth forcing, docs/measured-forcing.md) and compared with the
exact command: the forcing's largest distance from the command and the stress against the
stress under the command itself (`history = 'file'`, the command every 0.01 s), both with
the thesis constants (Miller, ksi), every 0.1 s.

usage: python3 bench/forcing_cases.py [path to usharp] [case ...]
(default: the newest build/gfortran_*/app/usharp; every case)"""
import glob
import os
import subprocess
import sys
import tempfile

import numpy as np

DECK = """&model name = 'miller', units = 'ksi', temperature = 866.15, tm = 1800.0, youngs = 22.5e3, poisson = 0.3 /
&constants a1 = 0.8, a2 = 7.42e-5, b = 1.0e15, c2 = 0.1, h1 = 280.0, h2 = 100.0, n = 5.8, q = 91000.0 /
&test name = 'data', history = 'data', dt_out = 0.1, gap_time = 30.0, data_file = 'data.csv' /
&test name = 'exact', history = 'file', file = 'exact.csv', dt_out = 0.1 /
"""


def approach(tau, noise=0.0, quantum=0.0):
    """Ramps of 1e-3/s between +-5e-3 (from 0, back to 0), each held 120 s; a controller
    approaches each level exponentially (time constant tau) over the last 5 % of the ramp's
    travel. Logged every 0.5 s from each ramp's start while it runs straight, then every
    20 s until the next ramp starts"""
    rate, t0, v0 = 1.0e-3, 0.0, 0.0
    pieces, times = [], []
    for level, hold in [(5e-3, 120.0), (-5e-3, 120.0), (5e-3, 120.0), (-5e-3, 120.0), (0.0, 0.0)]:
        travel = abs(level - v0)
        lin = 0.95*travel/rate if hold > 0 else travel/rate
        end = t0 + lin + hold if hold > 0 else t0 + lin
        pieces.append((t0, v0, level, lin, tau, end))
        k = np.arange(0, int(np.floor(lin/0.5 + 1e-9)) + 1)
        times += list(t0 + 0.5*k)
        last = t0 + 0.5*k[-1]
        if hold > 0:
            times += list(np.arange(last + 20.0, end - 1e-9, 20.0))
        t0, v0 = end, level
    times.append(t0)

    def cmd(t):
        for (a, va, level, lin, tau_, end) in pieces:
            if t <= end + 1e-12:
                s = np.sign(level - va)
                if t <= a + lin:
                    return va + s*rate*(t - a)
                d = abs(level - va) - rate*lin
                return level - s*d*np.exp(-(t - a - lin)/tau_)
        return pieces[-1][2]
    return np.unique(np.round(times, 9)), cmd, noise, quantum


def triangle(first):
    """A triangle of 1e-3/s between +-5e-3, two cycles, logged every 0.5 s from first (s):
    its reversals fall between samples"""
    def cmd(t):
        p = (t % 20.0)
        return 1e-3*(p if p <= 5.0 else (10.0 - p if p <= 15.0 else p - 20.0))
    t = np.r_[0.0, np.arange(first, 40.0, 0.5), 40.0]
    return np.unique(np.round(t, 9)), cmd, 0.0, 0.0


def trapezoid(first, hold_step, noise=0.0, start=0.0):
    """Ramps of 1e-3/s between +-5e-3 with 60 s holds (from 0, back to 0), after a hold at 0
    of start (s) if given, logged every 0.5 s from first (s), every hold_step s in the
    holds (from the ramp's last sample, the test's first at its start)"""
    tc = list(start + np.array([0, 5, 65, 75, 135, 145, 205, 215, 275, 280]))
    vc = [0, 5e-3, 5e-3, -5e-3, -5e-3, 5e-3, 5e-3, -5e-3, -5e-3, 0]
    holds = [(start + a, start + b) for a, b in [(5, 65), (75, 135), (145, 205), (215, 275)]]
    if start > 0:
        tc, vc, holds = [0.0] + tc, [0.0] + vc, [(-1.0, start)] + holds
    times, last = [0.0], 0.0
    for t in np.arange(first, tc[-1], 0.5):
        held = any(a < t < b for a, b in holds)
        if not held:
            last = t
            times.append(t)
        elif abs((t - last)/hold_step - round((t - last)/hold_step)) < 1e-9:
            times.append(t)
    times.append(tc[-1])
    return np.unique(np.round(times, 9)), lambda t: np.interp(t, tc, vc), noise, 0.0


CASES = {
    'approach-3s': lambda: approach(3.0),
    'approach-5s-noise-1e-6': lambda: approach(5.0, 1.0e-6),
    'approach-1s': lambda: approach(1.0),
    'approach-3s-rounded-1e-6': lambda: approach(3.0, quantum=1.0e-6),
    'triangle-reversals-between-samples': lambda: triangle(0.2),
    'trapezoid-logged-throughout': lambda: trapezoid(0.25, 0.5),
    'trapezoid-holds-logged-slowly': lambda: trapezoid(0.25, 20.0),
    'trapezoid-holds-logged-slowly-noise-3e-6': lambda: trapezoid(0.25, 20.0, 3.0e-6),
    'trapezoid-corners-at-samples-noise-3e-6': lambda: trapezoid(0.0, 20.0, 3.0e-6),
    'hold-at-start-logged-slowly': lambda: trapezoid(0.0, 20.0, start=60.2),
    'hold-at-start-logged-throughout': lambda: trapezoid(0.0, 0.5, start=60.2),
}


def run(exe, name):
    t, cmd, noise, quantum = CASES[name]()
    v = np.array([cmd(x) for x in t])
    if noise > 0:
        v = v + noise*np.random.default_rng(1).standard_normal(len(v))
    if quantum > 0:
        v = quantum*np.round(v/quantum)
    te = np.round(np.arange(0.0, t[-1] + 1e-9, 0.01), 9)
    ve = np.array([cmd(x) for x in te])
    with tempfile.TemporaryDirectory() as d:
        np.savetxt(os.path.join(d, 'data.csv'), np.c_[t, v, 0*v], delimiter=',', header='time,strain,stress',
                   comments='', fmt='%.6f,%.16e,%.1f')
        np.savetxt(os.path.join(d, 'exact.csv'), np.c_[te, ve], delimiter=',', header='time,strain',
                   comments='', fmt='%.6f,%.16e')
        with open(os.path.join(d, 'case.nml'), 'w') as f:
            f.write(DECK)
        subprocess.run([exe, 'simulate', 'case.nml', '-q', '--force', '-o', 'out'], cwd=d, check=True)
        s = np.loadtxt(os.path.join(d, 'out', 'data.sim.txt'), comments='#')
        x = np.loadtxt(os.path.join(d, 'out', 'exact.sim.txt'), comments='#')
    de = s[:, 1] - np.interp(s[:, 0], te, ve)
    ds = s[:, 2] - np.interp(s[:, 0], x[:, 0], x[:, 2])
    i, j = np.argmax(np.abs(de)), np.argmax(np.abs(ds))
    print(f'{name:36s} strain max {abs(de[i]):.2e} at t = {s[i, 0]:.1f} s; stress RMS {np.sqrt(np.mean(ds**2)):.3f}'
          f' ksi, max {abs(ds[j]):.3f} ksi at t = {s[j, 0]:.1f} s')


def main():
    args = sys.argv[1:]
    exe = None
    if args and os.path.isfile(args[0]):
        exe = os.path.abspath(args.pop(0))
    if exe is None:
        here = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
        found = glob.glob(os.path.join(here, 'build', 'gfortran_*', 'app', 'usharp'))
        if not found:
            sys.exit('usharp not built: fpm build --profile release (README)')
        exe = max(found, key=os.path.getmtime)
    for name in args or CASES:
        run(exe, name)


if __name__ == '__main__':
    main()
