#!/usr/bin/env python3
"""Independent check of the Chaboche model against NEML (pip install neml).

Reads the output of the bench_chaboche example (constants, then per history the times,
strains and usharp's stresses), builds the same model in NEML (ChabocheFlowRule with
constant fluidity, ChabocheVoceRecovery hardening with the isotropic recovery off), drives
it in uniaxial stress through the same strain points, and prints per history the largest
difference relative to the peak stress. NEML integrates by backward Euler: it runs with
nsub and 2*nsub substeps per output interval and the Richardson extrapolation of the two
is compared (its own first-order error is printed too).

Usage: python3 bench/chaboche_neml.py OUTPUT_OF_bench_chaboche
"""
import sys

import numpy as np
from neml import elasticity, general_flow, hardening, models, surfaces, visco_flow


def read(path):
    names, values, hists = None, None, []
    for line in open(path):
        if line.startswith("# constants"):
            names = line.split()[2:]
        elif line.startswith("# values"):
            values = [float(v) for v in line.split()[2:]]
        elif line.startswith("# history"):
            hists.append((line.split()[2], []))
        elif line.strip():
            hists[-1][1].append([float(v) for v in line.split()])
    return dict(zip(names, values)), [(n, np.array(r)) for n, r in hists]


def neml_model(c):
    elastic = elasticity.IsotropicLinearElasticModel(c["E"], "youngs", c["nu"], "poissons")
    gammas = [hardening.ConstantGamma(c["g1"]), hardening.ConstantGamma(c["g2"])]
    # theta0 = b Q, Rmax = Q gives R_dot = b (Q - R) p_dot; r1 = 0 turns the isotropic
    # static recovery off (Rmin is then irrelevant)
    hmodel = hardening.ChabocheVoceRecovery(
        c["s0"], c["b"] * c["Q"], max(c["Q"], 1.0e-12), 0.0, 0.0, 1.0,
        [c["C1"], c["C2"]], gammas, [c["A1"], c["A2"]], [c["m1"], c["m2"]])
    flow = visco_flow.ChabocheFlowRule(
        surfaces.IsoKinJ2(), hmodel, visco_flow.ConstantFluidity(c["eta"]), c["n"])
    return models.GeneralIntegrator(elastic, general_flow.TVPFlowRule(elastic, flow),
                                    verbose=False)


def drive(model, t, e, nsub):
    """Uniaxial stress, strain prescribed at the points t, e with nsub substeps between"""
    state = model.init_store()
    eps = np.zeros(6)
    sig = np.zeros(6)
    out = [0.0]
    tn, T, u, p = t[0], 1223.15, 0.0, 0.0
    for k in range(1, len(t)):
        for j in range(1, nsub + 1):
            tnp1 = t[k - 1] + (t[k] - t[k - 1]) * j / nsub
            e_np1 = e[k - 1] + (e[k] - e[k - 1]) * j / nsub
            # Newton on the lateral strain so that sigma_22 = sigma_33 = 0 (Mandel, NEML order)
            trial = eps.copy()
            trial[0] = e_np1
            for _ in range(30):
                s, h, A, u1, p1 = model.update_sd(trial, eps, T, T, tnp1, tn, sig, state, u, p)
                r = s[1]
                if abs(r) <= 1.0e-10 * max(abs(s[0]), 1.0):
                    break
                trial[1] -= r / (A[1, 1] + A[1, 2])
                trial[2] = trial[1]
            eps, sig, state, u, p, tn = trial, s, h, u1, p1, tnp1
        out.append(sig[0])
    return np.array(out)


def main():
    c, hists = read(sys.argv[1])
    model = neml_model(c)
    print("history                  peak(MPa)  |usharp-NEML|/peak  NEML BE error/peak")
    worst = 0.0
    for name, d in hists:
        t, e, s = d[:, 0], d[:, 1], d[:, 2]
        n1 = drive(model, t, e, 50)
        n2 = drive(model, t, e, 100)
        ref = 2.0 * n2 - n1
        peak = np.max(np.abs(ref))
        dev = np.max(np.abs(s - ref)) / peak
        worst = max(worst, dev)
        print("%-24s %9.2f  %18.2e  %18.2e" % (name, peak, dev, np.max(np.abs(n2 - ref)) / peak))
    print("largest |usharp - NEML| / peak: %.2e" % worst)


if __name__ == "__main__":
    main()
