#!/usr/bin/env python3
"""Follow a diagnosis's advice where the fit tests leave its held-out prediction open: for every
case kept by selfcheck.py whose verdict names a test that "would tell those end points apart",
make that test's data with the case's own injected effect (its seed's stream replayed to the
case, checked against the label kept in truth.txt; miller_ref.py simulates, with a noise
stream of its own), add it to the fit tests, diagnose again and compare: the leader, the
held-out gap removed, and the range of it over the end points the fit tests cannot tell
apart. The added test carries the effect of the case's first test (the same in every test
but a drift's rate, drawn per test). The cases are copied to OUT/<case> and diagnosed there,
JOBS at a time, one thread each; a case already diagnosed in OUT is not run again.

usage: follow_advice.py EXE OUT DIR:SEED [DIR:SEED ...] [--jobs N]
  DIR: a folder of kept cases (or of rediagnose.py's copies), SEED: the --seed it was made with
"""
import argparse
import os
import re
import shutil
import subprocess
import sys
from concurrent.futures import ThreadPoolExecutor

os.environ['OPENBLAS_NUM_THREADS'] = '1'
import numpy as np  # noqa: E402

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
import miller_ref as ref  # noqa: E402
import selfcheck as sc  # noqa: E402

ADVICE = re.compile(r'; a ([^;]+?) would tell those end points apart')
OPEN = re.compile(r'\(([0-9.]+) to ([0-9.]+) % at (\d+) end points of its refit')


def candidate(name):
    """(control, corner times, values, deck history, output interval) of a named candidate"""
    m = re.fullmatch(r'tension at ([0-9.e+-]+) /s to ([0-9.]+) % strain', name)
    if m:
        rate, final = float(m.group(1)), float(m.group(2)) / 100.0
        # (its end time rounded as the output grid's: 0.01/1e-5 is 1000.0000000000001)
        return ('strain', np.array([0.0, round(final / rate, 9)]), np.array([0.0, final]),
                f"history = 'tensile', strain_rate = {rate}, final_strain = {final}",
                max(final / rate / 1000.0, 0.1))
    m = re.fullmatch(r'relaxation holds of ([0-9.]+) s at ([0-9.]+) and ([0-9.]+) % strain', name)
    if m:
        hold, a, b = float(m.group(1)), float(m.group(2)) / 100.0, float(m.group(3)) / 100.0
        tc = np.array([0.0, 1.0, 1.0 + hold, 2.0 + hold, 2.0 + 2.0 * hold])
        return ('strain', tc, np.array([0.0, a, a, b, b]),
                f"history = 'relaxation', levels = {a}, {b}, ramp_time = 1.0, holds = {hold}, {hold}", 1.0)
    m = re.fullmatch(r'cycling at ([0-9.e+-]+) /s, range ([0-9.]+) %, ([0-9.]+) s holds, (\d+) cycles', name)
    if m:
        rate, rng_, hold, n = float(m.group(1)), float(m.group(2)) / 100.0, float(m.group(3)), int(m.group(4))
        a, q = 0.5 * rng_, 0.5 * rng_ / rate
        t, v = [0.0], [0.0]
        for _ in range(n):
            for dt, val in ((q, a), (hold, a), (2.0 * q, -a), (hold, -a), (q, 0.0)):
                t.append(t[-1] + dt)
                v.append(val)
        return ('strain', np.array(t), np.array(v),
                f"history = 'cyclic', strain_range = {rng_}, strain_rate = {rate}, cycles = {n}, "
                f"hold_max = {hold}, hold_min = {hold}", 1.0)
    raise ValueError(f'no such candidate: {name}')


def replay(seed, mname, row, rep, noise=0.005):
    """The effects (per test) and label of repetition rep of a row, as selfcheck.py drew them:
    its stream replayed, each test's noise drawn as make_data draws it (without simulating)"""
    tests, held, mode = sc.MATRICES[mname]
    rng = np.random.default_rng([seed, sc.ROWS.index(row), list(sc.MATRICES).index(mname)])
    for r in range(rep + 1):
        u = 0.0 if r == 0 else rng.uniform()
        eff, label = sc.draw(row, u, rng, [t for t, _ in tests])
        if mode == 'specimen':
            eff = {t: (e if t == held else {}) for t, e in eff.items()}
            label += f' on {held} alone'
        for name, dt in tests:
            _, tc, _ = ref.HISTORIES[name]()
            rng.standard_normal(ref.output_grid(tc, dt).size)
    return eff, label


def verdict(path):
    with open(path) as f:
        return sc.verdict_of(f.read())


def one(exe, src, seed, out):
    """Diagnose case src again with its advised test added; returns a row of the table"""
    name = os.path.basename(src.rstrip('/'))
    m = re.fullmatch(r'(.+?)-(' + '|'.join(sorted(sc.ROWS, key=len, reverse=True)) + r')-(\d+)', name)
    mname, row, rep = m.group(1), m.group(2), int(m.group(3))
    lead0, share0, v0, _ = verdict(os.path.join(src, 'report.md'))
    adv = ADVICE.search(v0)
    if not adv:
        return None
    eff, label = replay(seed, mname, row, rep)
    with open(os.path.join(src, 'truth.txt')) as f:
        kept = f.readline().split(': ', 1)[1].strip()
    if kept != label:
        raise RuntimeError(f'{name}: replayed {label!r}, kept {kept!r}')
    case = os.path.join(out, f'{name}@{seed}')
    report = os.path.join(case, 'report.md')
    if not os.path.exists(report):
        shutil.rmtree(case, ignore_errors=True)
        shutil.copytree(src, case, ignore=shutil.ignore_patterns('out', 'report.md'))
        control, tc, vc, deck_hist, dt = candidate(adv.group(1))
        t = ref.output_grid(tc, dt)
        if np.any(np.diff(t) < 1e-6) or t[-1] > tc[-1]:
            raise RuntimeError(f'{name}: output times past the end or a hair apart')
        eps, sig = ref.simulate(control, tc, vc, t, eff=next(iter(eff.values())))
        rng = np.random.default_rng([seed, 7919, sc.ROWS.index(row), list(sc.MATRICES).index(mname), rep])
        sig = sig + 0.005 * np.max(np.abs(sig)) * rng.standard_normal(sig.size)
        ref.write_csv(os.path.join(case, 'advice.csv'), t, eps, sig)
        with open(os.path.join(case, 'diagnose.nml'), 'a') as f:
            f.write(f"&test name = 'advice', {deck_hist}, dt_out = {dt},\n  data_file = 'advice.csv' /\n")
        env = dict(os.environ, OMP_NUM_THREADS='1', OMP_WAIT_POLICY='passive')
        p = subprocess.run([exe, 'diagnose', 'diagnose.nml', '--force', '-o', 'out'], cwd=case,
                           capture_output=True, text=True, env=env)
        with open(report + '.tmp', 'w') as f:
            f.write(p.stdout + p.stderr)
        os.replace(report + '.tmp', report)
    lead1, share1, v1, _ = verdict(report)
    o0, o1 = OPEN.search(v0), OPEN.search(v1)
    rng0 = f'{o0.group(1)}-{o0.group(2)}' if o0 else '-'
    rng1 = f'{o1.group(1)}-{o1.group(2)}' if o1 else '-'
    right = lead1 in sc.ACCEPT[row]
    return (f'{name}@{seed}', label, adv.group(1), lead0, share0, rng0, lead1, share1, rng1, right)


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument('exe')
    ap.add_argument('out')
    ap.add_argument('dirs', nargs='+', help='DIR:SEED')
    ap.add_argument('--jobs', type=int, default=2)
    a = ap.parse_args()
    exe = os.path.abspath(a.exe)
    os.makedirs(a.out, exist_ok=True)
    jobs = []
    for ds in a.dirs:
        d, seed = ds.rsplit(':', 1)
        for c in sorted(os.listdir(d)):
            if os.path.exists(os.path.join(d, c, 'report.md')):
                jobs.append((os.path.join(d, c), int(seed)))
    with ThreadPoolExecutor(a.jobs) as pool:
        rows = [r for r in pool.map(lambda j: one(exe, j[0], j[1], a.out), jobs) if r]
    print(f'{"case@seed":39s} {"injected":10s} {"before: leader":>16s} {"held %":>7s} {"open %":>11s}'
          f' {"after: leader":>15s} {"held %":>7s} {"open %":>11s}  test added')
    for r in rows:
        print(f'{r[0]:39s} {r[1]:10s} {r[3]:>16s} {r[4]:7.1f} {r[5]:>11s} {r[6]:>15s} {r[7]:7.1f} {r[8]:>11s}  {r[2]}')
    n = len(rows)
    print(f'{n} cases: right after {sum(r[9] for r in rows)} of {n}; held-out gap removed >= 80 % before '
          f'{sum(r[4] >= 80.0 for r in rows)}, after {sum(r[7] >= 80.0 for r in rows)}; prediction open '
          f'before {sum(r[5] != "-" for r in rows)}, after {sum(r[8] != "-" for r in rows)}')


if __name__ == '__main__':
    main()
