#!/usr/bin/env python3
"""What the held-out tests have of their own, from the cases selfcheck.py kept (--keep DIR)
of the row softening-colder (a softening in every test, the held-out test colder besides):
per case the injected values, the one-effect verdict's leader, the effect carried to the
held-out tests and the effect their own diagnosis names with its fitted magnitude, and
whether that is a temperature offset within 2 K of the injected one.

usage: own.py DIR [DIR ...]
"""
import os, re, sys, glob
sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
import selfcheck as sc


def main(dirs):
    n = ok = 0
    print(f'{"case":42s} {"injected":28s} {"leader":12s} {"carried":10s} own')
    for d in dirs:
        for case in sorted(glob.glob(os.path.join(d, '*-softening-colder-*'))):
            rep = os.path.join(case, 'report.md')
            if not os.path.exists(rep):
                continue
            text = open(rep).read()
            m = re.search(r'\*\*Verdict:\*\*\s*(.*(?:\n  .*)*)', text)
            v = ' '.join(x.strip() for x in m.group(1).split('\n')) if m else ''
            label = open(os.path.join(case, 'truth.txt')).read().split('\n')[0].split(': ', 1)[1]
            dt_true = float(re.search(r'held-out dT ([-+0-9.]+)', label).group(1))
            lead = sc.verdict_of(text)[0]
            c = re.search(r';\s*(\S+) explains the fit tests \(BIC.*?each held-out test beside the fit tests:\s*(.*)', v)
            carried, own, good = '-', '-', False
            if c:
                carried = c.group(1)
                own = c.group(2)
                t = re.match(r'(\S+) explains', own)
                f = re.search(r'fitted dT = ([-+0-9.E]+)', own)
                if t and t.group(1) == 'temperature' and f:
                    good = abs(float(f.group(1)) - dt_true) <= 2.0
                own = (t.group(1) if t else own[:40]) + (f' dT {float(f.group(1)):+.1f} K' if f else '')
            n += 1
            ok += good
            print(f'{os.path.basename(case):42s} {label:28s} {lead:12s} {carried:10s} {own}')
    print(f'temperature within 2 K of the injected offset: {ok} of {n}')


if __name__ == '__main__':
    main(sys.argv[1:])
