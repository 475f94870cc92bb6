#!/usr/bin/env python3
"""Accuracy and cost of the smooth forcing against RODAS4's relative tolerance.

The seven Alloy 617 tests of decks/a617-950C-fit.nml (cycles 1-2, measured strain as smooth
forcing) are simulated at constants taken along a fit's own path (evaluations spread evenly
over the journal of `usharp run decks/a617-950C-fit.nml`, 8 Levenberg-Marquardt starts), at
the fitted constants of decks/a617-950C-best.nml and at the deck's own start (Table 4 in
MPa), each against RODAS4 at rtol 1e-10 under the same forcing (bench_measured). For each
tolerance: the cost of one evaluation against the thesis's three tests (same run, at the
fitted constants), the steps there, and the largest error over the path as a share of each
test's peak stress. Needs ../shared/realdata beside the project.

Usage: python3 bench/measured_tolerance.py [--sets 40] [--rtols 2e-5,2.5e-5,3e-5,4e-5]
"""
import argparse
import os
import re
import subprocess
import sys
import tempfile

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
NAMES = ['a1', 'a2', 'b', 'c2', 'h1', 'h2', 'n']   # the deck's fitted constants, in order


def release(*args):
    flags = subprocess.run(['bash', '-c', '. scripts/release-flags.sh; echo "$FLAGS"'], cwd=ROOT,
                           capture_output=True, text=True, check=True).stdout.strip()
    out = subprocess.run(['fpm', *args, '--profile', 'release', '--flag', flags, '--runner'],
                         cwd=ROOT, capture_output=True, text=True, check=True).stdout
    return out.strip().splitlines()[-1]


def deck_copy(tmp, rtol):
    """decks/a617-950C-fit.nml with absolute data paths and &solver rtol"""
    deck = os.path.join(ROOT, 'decks', 'a617-950C-fit.nml')
    text = open(deck).read()
    text = re.sub(r"data_file = '([^']*)'",
                  lambda m: "data_file = '%s'" % os.path.normpath(os.path.join(ROOT, 'decks', m.group(1))),
                  text)
    path = os.path.join(tmp, 'fit-%s.nml' % rtol)
    with open(path, 'w') as f:
        f.write(text + '\n&solver rtol = %s /\n' % rtol)
    return path


def path_constants(tmp, journal, nsets):
    """Constants files of nsets evaluations spread over the fit's journal (finite objective)"""
    rows = []
    for line in open(journal):
        if line.startswith('#'):
            continue
        w = line.split()
        if len(w) >= 17 and float(w[2]) < 1.0e10:
            rows.append([float(x) for x in w[-7:]])
    files = []
    for k in range(nsets):
        logc = rows[(k*(len(rows) - 1))//max(nsets - 1, 1)]
        path = os.path.join(tmp, 'c%03d.nml' % k)
        with open(path, 'w') as f:
            f.write("&model name = 'miller', units = 'MPa' /\n&constants\n")
            for name, v in zip(NAMES, logc):
                f.write('  %s = %.15e\n' % (name, 10.0**v))
            f.write('  q = 9.1e4\n/\n')
        files.append(path)
    return files


def bench(exe, deck, constants, tmp):
    """(ratio, steps, errors at the constants, errors at the deck's start) or None"""
    out = os.path.join(tmp, 'out')
    os.makedirs(out, exist_ok=True)
    r = subprocess.run([exe, os.path.join(ROOT, 'decks', 'thesis-run3.nml'), deck, constants, out],
                       capture_output=True, text=True, env=dict(os.environ, OMP_NUM_THREADS='1'))
    ratio, steps, here, start = None, 0, [], []
    part = 0      # 1 in the table at the given constants, 2 in the one at the deck's start
    for line in r.stdout.splitlines():
        w = line.split()
        if line.startswith('measured, smooth'):
            ratio = float(w[-1])
        elif line.startswith('# test:'):
            part = 1
        elif line.startswith('# at the deck'):
            part = 2
        elif part == 1 and len(w) == 9:
            steps += int(w[2])
            here.append(float(w[4]))
        elif part == 2 and len(w) == 3:
            start.append(float(w[2]))
    if r.returncode != 0 or len(here) < 7:
        return None
    return ratio, steps, here, start


def main():
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument('--sets', type=int, default=40)
    ap.add_argument('--rtols', default='2e-5,2.5e-5,3e-5,4e-5')
    a = ap.parse_args()
    if not os.path.isdir(os.path.join(ROOT, '..', 'shared', 'realdata', 'a617-950C')):
        sys.exit('measured data not found at ../shared/realdata/a617-950C')
    usharp = release('run')
    exe = release('run', '--example', 'bench_measured')
    with tempfile.TemporaryDirectory() as tmp:
        subprocess.run([usharp, 'run', '-q', '-o', os.path.join(tmp, 'fit'),
                        os.path.join(ROOT, 'decks', 'a617-950C-fit.nml')],
                       cwd=ROOT, check=True, capture_output=True)
        sets = path_constants(tmp, os.path.join(tmp, 'fit', 'fit.journal'), a.sets)
        best = os.path.join(ROOT, 'decks', 'a617-950C-best.nml')
        print('# rtol; at the fitted constants: cost ratio to the thesis, steps, largest error/peak; '
              'at the deck\'s start: largest error/peak; along the fit\'s path: sets with a tight '
              'reference, largest error/peak, sets above 1e-4')
        for rtol in a.rtols.split(','):
            deck = deck_copy(tmp, rtol)
            ratio, steps, here, start = bench(exe, deck, best, tmp)
            worst, above, n = 0.0, 0, 0
            for c in sets:
                got = bench(exe, deck, c, tmp)
                if got is None:      # the tight reference itself fails at some starts
                    continue
                n += 1
                worst = max(worst, max(got[2]))
                above += max(got[2]) > 1.0e-4
            print('%-8s %6.2f %6d %10.2e %10.2e %4d %10.2e %4d' %
                  (rtol, ratio, steps, max(here), max(start), n, worst, above), flush=True)


if __name__ == '__main__':
    main()
