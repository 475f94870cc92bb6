#!/usr/bin/env python3
"""Summary of the cases selfcheck.py kept (--keep DIR): per matrix and injected effect, how
often the answer was right (an accepted effect first, or named as explaining the gap equally
well with a separating test proposed; clean data: no significant effect), the held-out
structured gap the right answers removed (least and median, and how many removed at least
80 % of it or left a rest below its floor, which the verdict says; and how many of those or,
every test fitted together, removed at least 80 % at constants the fit tests allow, where the
fit tests leave the held-out tests' constants open), and the answers at the low end
of each effect's range (each row's first repetition, or every one of a folder whose name ends
in 'low', made with --u 0). A case kept in several folders (the same data: the same seed,
matrix, row and repetition) counts once, as diagnosed in the last folder given.

usage: summarise.py DIR [DIR ...]
"""
import os, sys, re, glob, collections, hashlib
sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
import selfcheck as sc

def data_key(case):
    """The identity of a case's data: a digest of its data files"""
    h = hashlib.sha1()
    for f in sorted(glob.glob(os.path.join(case, '*.csv'))):
        h.update(os.path.basename(f).encode())
        h.update(open(f, 'rb').read())
    return h.hexdigest()


def unique_cases(dirs):
    """The cases of the folders, each once: a later folder's diagnosis of the same data
    replaces an earlier one's. A list of (case folder, whether its folder is all low end)"""
    cases = collections.OrderedDict()
    for d in dirs:
        lowall = d.rstrip('/').endswith('low')
        for case in sorted(glob.glob(os.path.join(d, '*'))):
            if os.path.exists(os.path.join(case, 'truth.txt')):
                key = data_key(case)
                cases.pop(key, None)
                cases[key] = (case, lowall)
    return list(cases.values())


def verdict(case):
    """selfcheck.verdict_of of the case's report (per specimen: the specimen's report)"""
    spec = glob.glob(os.path.join(case, 'out', 'diagnose', 'specimen-*.md'))
    return sc.verdict_of(open(spec[0]).read() if spec else open(os.path.join(case, 'report.md')).read())


def right(row, v, mname=None, label=None):
    """An accepted effect first, or named as explaining the gap equally well with a
    separating test proposed, or (given the case's matrix and truth) a miss the verdict
    states as one the tests could make at the injected magnitude (selfcheck.hidden_right)"""
    lead, rem, text, alike = v
    return lead in sc.ACCEPT[row] or any(x in sc.ACCEPT[row] for x in alike) or \
        (mname is not None and sc.hidden_right(row, mname, label, text))


def main(dirs):
    rows = collections.OrderedDict()
    low = collections.defaultdict(list)
    for case, lowall in unique_cases(dirs):
        txt = open(os.path.join(case, 'truth.txt')).read()
        m = re.match(r'([\w-]+): (.*)\nverdict: (.*)', txt, re.S)
        row, label = m.group(1), m.group(2)
        name = os.path.basename(case)
        mname = name[:name.index('-' + row + '-')]
        rep = int(name.rsplit('-', 1)[1])
        lead, rem, v, alike = verdict(case)
        ok = right(row, (lead, rem, v, alike), mname, label)
        key = (mname, row)
        r = rows.setdefault(key, dict(n=0, ok=0, rem=[], ans=[], most=0, agree=0))
        r['n'] += 1
        r['ok'] += ok
        if ok and rem == rem:
            r['rem'].append(rem)
            most = rem >= 80.0 or bool(re.search(r'% on the held-out tests, the rest below its floor', v))
            r['most'] += most
            # or, every test fitted together, most of the held-out gap removed at constants the
            # fit tests allow (what the prediction left is what the fit tests leave open)
            m6 = re.search(r"([0-9.]+) % of the held-out tests' gap against their noise, at constants the fit "
                           r"tests allow", v)
            r['agree'] += most or bool(m6 and float(m6.group(1)) >= 80.0)
        if lead in sc.ACCEPT[row] or not ok:
            r['ans'].append(lead)
        elif any(x in sc.ACCEPT[row] for x in alike):
            r['ans'].append(lead + '~' + next(x for x in alike if x in sc.ACCEPT[row]))
        else:
            r['ans'].append(lead + '~' + sc.HIDE[row] + '(could miss)')
        if rep == 0 or lowall:
            low[row].append((mname, label, ok, lead))
    print(f'{"matrix":20s} {"injected":12s} {"right/reps":>10s} {"held-out gap removed min/median %":>34s} '
          f'{">=80 % or rest at noise":>24s} {"or agreeing":>12s}  answers')
    tot = ok = nrem = nmost = nagree = 0
    order = lambda k: (list(sc.MATRICES).index(k[0]), list(sc.ACCEPT).index(k[1]))
    for (mname, row), r in sorted(rows.items(), key=lambda kr: order(kr[0])):
        rem = sorted(r['rem'])
        rs = f'{rem[0]:.0f} / {rem[len(rem)//2]:.0f}' if rem else '-'
        ms = f'{r["most"]} of {len(rem)}' if rem else '-'
        ag = f'{r["agree"]} of {len(rem)}' if rem else '-'
        print(f'{mname:20s} {row:12s} {r["ok"]:>4d} / {r["n"]:<3d} {rs:>34s} {ms:>24s} {ag:>12s}  '
              f'{" ".join(r["ans"])}')
        tot += r['n']; ok += r['ok']
        nrem += len(rem); nmost += r['most']; nagree += r['agree']
    print(f'right {ok} of {tot}')
    print(f'held-out gap removed >= 80 % or rest at noise: {nmost} of {nrem}; or, every test fitted '
          f'together, >= 80 % at constants the fit tests allow: {nagree} of {nrem}')
    print('\nlow end (first repetition of each row, or --u 0):')
    for row, L in low.items():
        print(f'{row:12s} {sum(x[2] for x in L)} of {len(L)}: ' + '; '.join(f'{m} {l} -> {a}' for m, l, o, a in L))


if __name__ == '__main__':
    main(sys.argv[1:])
