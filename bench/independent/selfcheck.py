#!/usr/bin/env python3
"""Self-check of `usharp diagnose` on data it did not make: for each matrix and each injected
effect (miller_ref.py: the thesis's Miller model and effects in forms of their own), draw a
magnitude (the first repetition at the low end of the effect's realistic range), make the data
with 0.5 % noise, write a deck, run the diagnosis and read its verdict. Prints one row per
matrix and effect: repetitions, how often an accepted effect came first, the held-out
structured gap removed (median).

usage: selfcheck.py EXE [--reps N] [--matrices a,b] [--rows a,b] [--noise F] [--keep DIR] [--u U]
       selfcheck.py --make MATRIX ROW U SEED DIR   (one case's data and deck, no diagnosis)
"""
import argparse
import os
import re
import subprocess
import sys
import tempfile

# One BLAS thread: numpy's OpenBLAS sums in an order set by its thread count, and the
# data made here must not change with the caller's OMP_NUM_THREADS
os.environ['OPENBLAS_NUM_THREADS'] = '1'

import numpy as np

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
import miller_ref as ref  # noqa: E402

# Matrices: tests (name, output interval s), the held-out one and the mode: 'holdout' (every
# test carries the effect, one is held out) or 'specimen' (only that test carries it, and the
# per-specimen diagnosis sets it against its replicates)
MATRICES = {
    'thesis-hold-ratchet': ([('lcf', 0.5), ('relax', 1.0), ('ratchet', 1.0)], 'ratchet', 'holdout'),
    'thesis-hold-relax': ([('lcf', 0.5), ('relax', 1.0), ('ratchet', 1.0)], 'relax', 'holdout'),
    'thesis-hold-lcf': ([('lcf', 0.5), ('relax', 1.0), ('ratchet', 1.0)], 'lcf', 'holdout'),
    'creep': ([('lcf', 0.5), ('relax', 1.0), ('creep', 1.0)], 'creep', 'holdout'),
    'specimen': ([('c6', 0.1), ('c8', 0.1), ('c10', 0.1)], 'c8', 'specimen'),
    # The same cycles with a hold of 60 s at each tensile peak (creep-fatigue tests)
    'specimen-hold': ([('h6', 0.2), ('h8', 0.2), ('h10', 0.2)], 'h8', 'specimen'),
}

# Rows: the effect drawn at magnitude u in [0, 1] of its realistic range (0: the low end),
# and the catalogue effects that explain it (the first the exact or nearest form)
def draw(row, u, rng, tests):
    sign = 1.0 if rng.uniform() < 0.5 else -1.0
    lo_hi = lambda lo, hi: lo * (hi / lo) ** u
    if row == 'clean':
        return {t: {} for t in tests}, 'none'
    if row == 'modulus':
        d = lo_hi(0.03, 0.10)
        return {t: {'delta': d} for t in tests}, f'E -{100 * d:.1f} %'
    if row == 'temperature':
        dT = sign * lo_hi(5.0, 25.0)
        return {t: {'dT': dT} for t in tests}, f'dT {dT:+.1f} K'
    if row == 'softening':
        a = lo_hi(0.05, 0.2)
        return {t: {'soft_a': a, 'soft_p0': 0.005} for t in tests}, f'a {a:.3f}'
    if row == 'softening-colder':
        # A softening shared by every test, and the held-out test colder besides (make_case
        # puts '_held' on it): two effects, which a prediction of one at a time cannot confirm
        a = lo_hi(0.05, 0.2)
        dT = -lo_hi(5.0, 25.0)
        out = {t: {'soft_a': a, 'soft_p0': 0.005} for t in tests}
        out['_held'] = {'dT': dT}
        return out, f'a {a:.3f}, held-out dT {dT:+.1f} K'
    if row == 'drift':
        out = {}
        for t in tests:
            _, tc, _ = ref.HISTORIES[t]()
            tot = (1.0 if rng.uniform() < 0.5 else -1.0) * lo_hi(2e-5, 1e-4)
            out[t] = {'drift': tot / tc[-1]}
        return out, 'drift ' + ' '.join(f'{out[t]["drift"]:.1e}' for t in tests) + ' 1/s'
    if row == 'gain':
        # Per test: a load cell's calibration or a cross-section measured wrong
        out = {t: {'gain': (1.0 if rng.uniform() < 0.5 else -1.0) * lo_hi(0.02, 0.06)} for t in tests}
        return out, 'gain ' + ' '.join(f'{out[t]["gain"]:+.3f}' for t in tests)
    if row == 'lag':
        tau = lo_hi(0.1, 0.5)
        return {t: {'tau': tau} for t in tests}, f'tau {tau:.2f} s'
    if row == 'backstress2':
        g3 = 150.0 + 250.0 * rng.uniform()
        sat = lo_hi(1.0, 2.5)  # ksi, 5-12 % of the 20 ksi peak
        return {t: {'H3': sat * g3, 'gamma3': g3} for t in tests}, f'H3/gamma3 {sat:.2f} ksi'
    if row == 'backstress2-fast':
        # A fast-saturating one (fitted per specimen to Alloy 617's cycles 1-2, gamma3 came out
        # at 2100-10300)
        g3 = 1000.0 * 5.0 ** rng.uniform()
        sat = lo_hi(1.0, 2.5)
        return {t: {'H3': sat * g3, 'gamma3': g3} for t in tests}, f'H3/gamma3 {sat:.2f} ksi, gamma3 {g3:.0f}'
    raise ValueError(row)


# Per specimen, a modulus drop of one test is its scatter (dE/E) or a compliance of its own
ACCEPT = {'clean': ['none'], 'modulus': ['compliance', 'scatter'], 'temperature': ['temperature', 'initial'],
          'softening': ['softening'], 'drift': ['drift'], 'lag': ['lag'], 'backstress2': ['backstress2'],
          'backstress2-fast': ['backstress2'],
          # two effects: the one-effect verdict may name either (the held-out test's own
          # difference is then in its last clause: see own.py)
          'softening-colder': ['softening', 'temperature', 'initial', 'scatter'],
          'gain': ['gain']}
# (softening-colder only where asked for: --rows)
ROWS = [r for r in ACCEPT if r != 'softening-colder']

WEIGHTING = {'lcf': "weighting = 'threshold', sig = 14.0", 'relax': "weighting = 'relaxation'",
             'ratchet': '', 'creep': '', 'c6': '', 'c8': '', 'c10': '', 'h6': '', 'h8': '', 'h10': ''}
HIST = {'lcf': "history = 'thesis_lcf', amp_first = 0.0005, amp_last = 0.005, npeaks = 12, quarter_time = 10.0",
        'relax': "history = 'relaxation', levels = 0.00075, 0.001, ramp_time = 1.0, holds = 600.0, 600.0",
        'ratchet': "history = 'ratchet', up = 0.0005, down = 0.00025, repeats = 15, seg_time = 40.0",
        'creep': "history = 'creep', stress = 15.0, ramp_time = 1.0, duration = 600.0",
        'c6': "history = 'cyclic', strain_range = 0.006, strain_rate = 1.0e-3, cycles = 3",
        'c8': "history = 'cyclic', strain_range = 0.008, strain_rate = 1.0e-3, cycles = 3",
        'c10': "history = 'cyclic', strain_range = 0.010, strain_rate = 1.0e-3, cycles = 3",
        'h6': "history = 'cyclic', strain_range = 0.006, strain_rate = 1.0e-3, cycles = 3, hold_max = 60.0",
        'h8': "history = 'cyclic', strain_range = 0.008, strain_rate = 1.0e-3, cycles = 3, hold_max = 60.0",
        'h10': "history = 'cyclic', strain_range = 0.010, strain_rate = 1.0e-3, cycles = 3, hold_max = 60.0"}


def deck(tests, held, files, out_dir, mode='holdout'):
    lines = ["&model name = 'miller', units = 'ksi', temperature = 866.15, tm = 1800.0, youngs = 22.5e3,",
             "  poisson = 0.3 /",
             "&constants a1 = 0.8, a2 = 7.42e-5, b = 1.0e15, c2 = 0.1, h1 = 280.0, h2 = 100.0, n = 5.8,",
             "  q = 91000.0 /",
             "&fit fitted = 'A1', 'A2', 'B', 'C2', 'H1', 'H2', 'n', method = 'lm', objective = 'eq7' /",
             f"&diagnose holdout = '{held}' /" if mode == 'holdout' else f"&diagnose specimen = '{held}' /",
             f"&output out_dir = '{out_dir}' /"]
    for name, dt in tests:
        lines.append(f"&test name = '{name}', {HIST[name]}, dt_out = {dt},")
        if WEIGHTING[name]:
            lines.append(f"  {WEIGHTING[name]},")
        lines.append(f"  data_file = '{files[name]}' /")
    return '\n'.join(lines) + '\n'


def verdict_of(text):
    """(first effect named by the verdict or 'none' or '?', held-out gap removed % or nan,
    the verdict, the effects named as explaining the gap equally well when a separating test
    is named too)"""
    # the verdict's line and its continuation lines (indented)
    m = re.search(r'\*\*Verdict:\*\*\s*(.*(?:\n  .*)*)', text)
    v = ' '.join(x.strip() for x in m.group(1).split('\n')) if m else ''
    # a specimen fitted by its replicates' constants no worse than they fit themselves: the
    # verdict says so first, then names the effect as before
    v = re.sub(r'^\s*\S+ does not stand out from its replicates \([^)]*\);\s*', '', v)
    # what the held-out tests have of their own beside an effect carried from the fit tests
    # (the verdict's last clause) is a second effect's verdict: the first is scored
    v = re.split(r';\s*\S+ explains the fit tests \(BIC', v)[0]
    if re.match(r'\s*no significant effect', v) or re.match(r'\s*no effect explains', v) or \
            'predicted to its noise level by its replicates' in v or \
            re.match(r'\s*one set of constants fits .* to its noise level', v):
        lead = 'none'
    else:
        m2 = re.match(r'\s*`?([a-z0-9]+)`?', v)
        lead = m2.group(1) if m2 and m2.group(1) in CATALOGUE else '?'
    m3 = re.search(r'([0-9.]+) %\s*on the held-out', v)
    alike = []
    m4 = re.search(r';\s*([a-z0-9, ]+?) explains? it equally well', v)
    # alike only by both leaving noise: 'lag (BIC +164.0) explains it to the noise level too'
    m5 = re.search(r';\s*([a-zA-Z0-9, ()+.-]+?) explains? it to the noise level too', v)
    if re.search(r'would tell \S+ from ', v):
        if m4:
            alike = [x.strip() for x in m4.group(1).split(',')]
        if m5:
            alike += [re.sub(r'\s*\(BIC [^)]*\)', '', x).strip() for x in m5.group(1).split(',')]
    return lead, (float(m3.group(1)) if m3 else float('nan')), v, alike


# Rows whose injected form is the catalogue effect's own (one parameter): a miss counts as
# right when the verdict states that the tests could miss that effect up to a magnitude at
# or above the injected one (the significance rule's power 0.95 there) and names a test that
# would find that much with power 0.95 or more
HIDE = {'drift': 'drift', 'lag': 'lag', 'temperature': 'temperature'}
LOW_END = {'drift': 2e-5, 'lag': 0.1, 'temperature': 5.0}  # the catalogue's low ends (drift: over a test)


def hidden_of(v):
    """The verdict's "could miss" entries: effect -> (times the low end, value or None, the
    test named, its power)"""
    out = {}
    for m in re.finditer(r'([a-z0-9]+) \(power [0-9.]+ there; found with power 0\.95 from ([0-9.]+) times it'
                         r'(?:, [A-Za-z0-9/]+ = ([-+0-9.Ee]+) [^,)]*)?(?:, which an? (.+?) would find with power '
                         r'([0-9.]+))?\)', v):
        out[m.group(1)] = (float(m.group(2)), float(m.group(3)) if m.group(3) else None, m.group(4) or '',
                           float(m.group(5)) if m.group(5) else -1.0)
    return out


def hidden_right(row, mname, label, v):
    """A miss stated as such: the injected effect (its exact form) among those the verdict says
    the tests could miss, up to a magnitude at or above the injected one, with a test named
    that would find that much (power 0.95 or more)"""
    if row not in HIDE:
        return False
    h = hidden_of(v).get(HIDE[row])
    if not h or not h[2] or h[3] < 0.95:
        return False
    tests, held, mode = MATRICES[mname]
    names = [t for t, _ in tests]
    nums = [float(x) for x in re.findall(r'[-+]?[0-9.]+(?:e[-+]?[0-9]+)?', label.split(' on ')[0])]
    if row == 'drift':
        # per test: its rate (1/s) and, as a multiple of the low end, its total over the test
        carriers = [names.index(held)] if mode == 'specimen' else range(len(names))
        for i in carriers:
            tot = abs(nums[i]) * ref.HISTORIES[names[i]]()[1][-1]
            if (h[1] is not None and abs(nums[i]) > abs(h[1])) or (h[1] is None and tot / LOW_END[row] > h[0]):
                return False
        return True
    mag = abs(nums[0])
    return (abs(h[1]) if h[1] is not None else h[0] * LOW_END[row]) >= mag


CATALOGUE = ['compliance', 'lag', 'temperature', 'scatter', 'initial', 'shift', 'softening', 'backstress2',
             'drift', 'gain']


def make_case(mname, row, u, rng, case, noise):
    """Data (CSV) and deck (diagnose.nml) of one case in folder case; returns the truth's label"""
    tests, held, mode = MATRICES[mname]
    eff, label = draw(row, u, rng, [t for t, _ in tests])
    eff[held].update(eff.pop('_held', {}))
    if mode == 'specimen':
        eff = {t: (e if t == held else {}) for t, e in eff.items()}
        label += f' on {held} alone'
    os.makedirs(case, exist_ok=True)
    files = {}
    for name, dt in tests:
        t, e, s = ref.make_data(name, dt, eff[name], noise, rng)
        files[name] = f'{name}.csv'
        ref.write_csv(os.path.join(case, files[name]), t, e, s)
    with open(os.path.join(case, 'diagnose.nml'), 'w') as f:
        f.write(deck(tests, held, files, 'out', mode))
    return label


def main():
    if len(sys.argv) > 1 and sys.argv[1] == '--make':
        mname, row, u, seed, case = sys.argv[2:7]
        label = make_case(mname, row, float(u), np.random.default_rng(int(seed)), case, 0.005)
        print(label)
        return
    ap = argparse.ArgumentParser()
    ap.add_argument('exe')
    ap.add_argument('--reps', type=int, default=3)
    ap.add_argument('--matrices', default=','.join(MATRICES))
    ap.add_argument('--rows', default=','.join(ROWS))
    ap.add_argument('--noise', type=float, default=0.005)
    ap.add_argument('--seed', type=int, default=1)
    ap.add_argument('--keep', default='')
    ap.add_argument('--u', type=float, default=None,
                    help='every repetition at this point of the range (0: the low end), not drawn')
    a = ap.parse_args()
    work = a.keep or tempfile.mkdtemp(prefix='usharp-indep-')
    os.makedirs(work, exist_ok=True)
    print(f'{"matrix":22s} {"injected":12s} {"reps":>4s} {"first":>6s} {"%":>5s} {"held gap removed %":>18s}  answers')
    total_ok = total = 0
    for mname in a.matrices.split(','):
        for row in a.rows.split(','):
            rng = np.random.default_rng([a.seed, list(ACCEPT).index(row), list(MATRICES).index(mname)])
            answers, removed = [], []
            for rep in range(a.reps):
                u = 0.0 if rep == 0 else rng.uniform()
                if a.u is not None:
                    u = a.u
                case = os.path.join(work, f'{mname}-{row}-{rep}')
                label = make_case(mname, row, u, rng, case, a.noise)
                p = subprocess.run([a.exe, 'diagnose', 'diagnose.nml', '--force', '-o', 'out'], cwd=case,
                                   capture_output=True, text=True)
                with open(os.path.join(case, 'report.md'), 'w') as f:
                    f.write(p.stdout + p.stderr)
                out = p.stdout
                spec = os.path.join(case, 'out', 'diagnose', f'specimen-{MATRICES[mname][1]}.md')
                if MATRICES[mname][2] == 'specimen' and os.path.exists(spec):
                    with open(spec) as f:
                        out = f.read()
                lead, rem, v, alike = verdict_of(out)
                # Right: an accepted effect first, or named as explaining the gap equally well
                # with a separating test proposed
                if lead not in ACCEPT[row] and any(x in ACCEPT[row] for x in alike):
                    lead = lead + '~' + next(x for x in alike if x in ACCEPT[row])
                elif lead not in ACCEPT[row] and hidden_right(row, mname, label, v):
                    lead = lead + '~' + HIDE[row] + '(could miss)'
                answers.append(lead)
                removed.append(rem)
                with open(os.path.join(case, 'truth.txt'), 'w') as f:
                    f.write(f'{row}: {label}\nverdict: {v}\n')
            ok = sum(x.split('~')[-1].split('(')[0] in ACCEPT[row] for x in answers)
            total_ok += ok
            total += len(answers)
            med = np.nanmedian(removed) if np.any(np.isfinite(removed)) else float('nan')
            print(f'{mname:22s} {row:12s} {len(answers):4d} {ok:6d} {100.0 * ok / len(answers):5.0f} '
                  f'{med:18.0f}  {" ".join(answers)}', flush=True)
    print(f'correct: {total_ok} of {total}; cases in {work}')


if __name__ == '__main__':
    main()
