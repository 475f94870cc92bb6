#!/usr/bin/env python3
"""Diagnose again, with another build, the cases selfcheck.py kept (--keep DIR), and compare
each verdict with the one kept: how many were right before and after, and every case whose
leading effect or rightness changed. The cases are taken as summarise.py takes them (a case
kept in several folders counts once, as diagnosed in the last folder given); each is copied
(its data, deck and truth) to OUT/<folder>/<case> and diagnosed there, JOBS at a time, one
thread each. A case already diagnosed in OUT is not run again, so a stopped run continues.
Then summarise.py prints the table of OUT.

usage: rediagnose.py EXE OUT DIR [DIR ...] [--jobs N]
"""
import os, sys, glob, shutil, subprocess, collections, argparse
from concurrent.futures import ThreadPoolExecutor
sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
import selfcheck as sc
import summarise as cases_of


def diagnose(exe, case):
    """Diagnose one case in its folder (report.md written whole, as selfcheck.py writes it)"""
    if os.path.exists(os.path.join(case, 'report.md')):
        return
    env = dict(os.environ, OMP_NUM_THREADS='1', OMP_WAIT_POLICY='passive')
    p = subprocess.run([exe, 'diagnose', 'diagnose.nml', '--force', '-o', 'out'], cwd=case,
                       capture_output=True, text=True, env=env)
    with open(os.path.join(case, 'report.tmp'), 'w') as f:
        f.write(p.stdout + p.stderr)
    os.replace(os.path.join(case, 'report.tmp'), os.path.join(case, 'report.md'))


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument('exe')
    ap.add_argument('out')
    ap.add_argument('dirs', nargs='+')
    ap.add_argument('--jobs', type=int, default=2)
    a = ap.parse_args()
    exe = os.path.abspath(a.exe)
    kept = cases_of.unique_cases(a.dirs)
    pairs = []
    for old, _ in kept:
        folder = os.path.normpath(os.path.dirname(old)).strip('/').replace('/', '_')
        new = os.path.join(a.out, folder, os.path.basename(old))
        os.makedirs(new, exist_ok=True)
        for f in glob.glob(os.path.join(old, '*.csv')) + [os.path.join(old, n) for n in
                                                          ('diagnose.nml', 'truth.txt')]:
            shutil.copy(f, new)
        pairs.append((old, new))
    # Clean data first, then each row's first repetition (the low end)
    first = lambda p: (0 if '-clean-' in p[1] else 1 if p[1].endswith('-0') else 2)
    with ThreadPoolExecutor(a.jobs) as pool:
        list(pool.map(lambda p: diagnose(exe, p[1]), sorted(pairs, key=first)))
    before = after = changed = 0
    for old, new in pairs:
        txt = open(os.path.join(new, 'truth.txt')).read()
        row = txt.split(':')[0]
        label = txt.split('\n')[0].split(': ', 1)[1]
        name = os.path.basename(new)
        mname = name[:name.index('-' + row + '-')]
        vo, vn = cases_of.verdict(old), cases_of.verdict(new)
        ro, rn = cases_of.right(row, vo, mname, label), cases_of.right(row, vn, mname, label)
        before += ro
        after += rn
        if ro != rn or vo[0] != vn[0]:
            changed += 1
            print(f'{new}: {"right" if ro else "wrong"} -> {"right" if rn else "wrong"}, '
                  f'{vo[0]} -> {vn[0]}: {vn[2][:150]}')
    print(f'{len(pairs)} cases: right {before} before, {after} after; leader or rightness changed in {changed}')
    folders = []
    for _, new in pairs:
        if os.path.dirname(new) not in folders:
            folders.append(os.path.dirname(new))
    subprocess.run([sys.executable, os.path.join(os.path.dirname(os.path.abspath(__file__)), 'summarise.py')]
                   + folders)


if __name__ == '__main__':
    main()
