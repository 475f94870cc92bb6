"""Independent reference for usharp's diagnosis: the Miller (1976) model of the thesis and
unmodelled effects in forms of their own, integrated with scipy's Radau at tight tolerances,
sampled, with Gaussian noise. It shares no code with usharp: the equations are taken from the
technical reference (Section 1: Eqs. 2-5 and the D0 formula; Section 2: the three tests).

Units: ksi, s, K. Effects (none in usharp's catalogue in exactly this form):
- modulus:     E*(1 - delta) for every test (a softer specimen material or gauge error)
- temperature: every test at T + dT: theta(T + dT), E*(1 + dlnE_dT*dT), D0 at its nominal value
- softening:   drag in the flow law D*(1 - a*(1 - exp(-p/p0))): saturates at a after p >> p0
- drift:       extensometer drift, per test: the specimen sees the strain command less d*t; a
               stress-controlled test measures its strain plus d*t
- lag:         the applied control follows the command through u' = (command - u)/tau
- backstress2: a second back stress R2' = H3 eps_in' - gamma3 R2 |eps_in'|
"""
import math
import os
# One BLAS thread: numpy's OpenBLAS sums in an order set by its thread count, and the
# data made here must not change with the caller's OMP_NUM_THREADS
os.environ['OPENBLAS_NUM_THREADS'] = '1'

import numpy as np
from scipy.integrate import solve_ivp

K_GAS = 1.9859  # cal/(mol K)

TABLE4 = dict(A1=0.8, A2=7.42e-5, B=1.0e15, C2=0.1, H1=280.0, H2=100.0, n=5.8, Q=91000.0)
T_NOM, TM, E_NOM, YS, EE = 866.15, 1800.0, 22.5e3, 18.0, 5.0e-5
DLNE_DT = -4.0e-4  # 1/K, the slope usharp's &diagnose assumes by default


def theta(T, Q=TABLE4['Q'], Tm=TM):
    """Temperature factor of Eq. 5"""
    if T <= 0.6 * Tm:
        return math.exp(-Q / (0.6 * K_GAS * Tm) * (math.log(0.6 * Tm / T) + 1.0))
    return math.exp(-Q / (K_GAS * T))


def drag0(c, th):
    """Initial drag stress from the yield stress YS at the rate EE (reference, Section 1)"""
    return (YS - 0.002 * c['H1']) / math.asinh((EE / (c['B'] * th)) ** (1.0 / c['n'])) ** (2.0 / 3.0)


# Histories: corners (t, v) of the command, as in the reference's Section 2
def thesis_lcf():
    m = (0.005 / 0.0005) ** (1.0 / 11.0)
    t, v = [0.0], [0.0]
    for k in range(12):
        t += [(2 * k + 1) * 10.0, (2 * k + 2) * 10.0]
        v += [0.0005 * m ** k * (1 if k % 2 == 0 else -1), 0.0]
    return 'strain', np.array(t), np.array(v)


def relaxation():
    return 'strain', np.array([0.0, 1.0, 601.0, 602.0, 1202.0]), np.array([0.0, 7.5e-4, 7.5e-4, 1e-3, 1e-3])


def ratchet():
    t, v = [0.0], [0.0]
    for _ in range(15):
        t += [t[-1] + 40.0, t[-1] + 80.0]
        v += [v[-1] + 5e-4, v[-1] + 2.5e-4]
    return 'strain', np.array(t), np.array(v)


def creep(stress=15.0, ramp=1.0, duration=600.0):
    return 'stress', np.array([0.0, ramp, duration]), np.array([0.0, stress, stress])


def cyclic(strain_range, rate, cycles, hold=0.0):
    """Triangular cycling from zero, each cycle 0 -> +a (held hold s) -> 0 -> -a -> 0"""
    a = 0.5 * strain_range
    q = a / rate
    t, v = [0.0], [0.0]
    for _ in range(cycles):
        for val in (a, 0.0, -a, 0.0):
            t.append(t[-1] + q)
            v.append(val)
            if val == a and hold > 0.0:
                t.append(t[-1] + hold)
                v.append(val)
    return 'strain', np.array(t), np.array(v)


HISTORIES = dict(lcf=thesis_lcf, relax=relaxation, ratchet=ratchet, creep=creep,
                 c6=lambda: cyclic(0.006, 1.0e-3, 3), c8=lambda: cyclic(0.008, 1.0e-3, 3),
                 c10=lambda: cyclic(0.010, 1.0e-3, 3),
                 h6=lambda: cyclic(0.006, 1.0e-3, 3, 60.0), h8=lambda: cyclic(0.008, 1.0e-3, 3, 60.0),
                 h10=lambda: cyclic(0.010, 1.0e-3, 3, 60.0))


def simulate(control, tc, vc, tout, c=TABLE4, T=T_NOM, eff=None):
    """Measured strain and stress of one test at the times tout. eff: dict of effects."""
    eff = dict(eff or {})
    th_nom = theta(T, c['Q'])
    d0 = drag0(c, th_nom) * (1.0 + eff.get('drag_factor', 0.0))
    dT = eff.get('dT', 0.0)
    th = theta(T + dT, c['Q'])
    E = E_NOM * (1.0 - eff.get('delta', 0.0)) * (1.0 + DLNE_DT * dT)
    bth = c['B'] * th
    a_soft, p0 = eff.get('soft_a', 0.0), eff.get('soft_p0', 0.005)
    drift = eff.get('drift', 0.0)
    tau = eff.get('tau', 0.0)
    h3, g3 = eff.get('H3', 0.0), eff.get('gamma3', 0.0)
    # The stress channel reads (1 + gain) times the specimen's stress; a stress-controlled
    # specimen is so driven to the command over (1 + gain)
    gain = eff.get('gain', 0.0)

    def command(t, k):
        s = (vc[k + 1] - vc[k]) / (tc[k + 1] - tc[k])
        return vc[k] + s * (t - tc[k]), s

    def sigma_of(t, y, k):
        u = y[5] if tau > 0.0 else command(t, k)[0]
        if control == 'strain':
            return E * (u - drift * t - y[0])
        return u / (1.0 + gain)

    def rates(t, y, k):
        try:
            return rates_at(t, y, k)
        except OverflowError:
            # a trial state of the implicit solver far outside the physical ones: rates so
            # large that its Newton iteration fails and the step is cut
            return [1e100] * len(y)

    def rates_at(t, y, k):
        eps_in, R, D, p, R2 = y[:5]
        s = sigma_of(t, y, k) - R - R2
        # Trial states of the implicit solver can lie far outside the physical ones: the
        # arguments are capped where the rates are already astronomically large
        dflow = max(D * (1.0 - a_soft * (1.0 - math.exp(-max(p, 0.0) / p0))), 1e-6)
        x = min((abs(s) / dflow) ** 1.5, 50.0)
        f = bth * math.sinh(x) ** c['n']
        de = math.copysign(f, s)
        dR = c['H1'] * de - c['H1'] * bth * math.sinh(min(c['A1'] * abs(R), 50.0)) ** c['n'] * np.sign(R)
        dD = c['H2'] * f * (c['C2'] + abs(R) - c['A2'] / c['A1'] * D ** 3) \
            - c['H2'] * c['C2'] * bth * math.sinh(min(c['A2'] * abs(D) ** 3, 50.0)) ** c['n']
        dR2 = h3 * de - g3 * R2 * f
        out = [de, dR, dD, f, dR2]
        if tau > 0.0:
            out.append((command(t, k)[0] - y[5]) / tau)
        return out

    y = [0.0, 0.0, d0, 0.0, 0.0] + ([vc[0]] if tau > 0.0 else [])
    eps_m = np.empty(len(tout))
    sig_m = np.empty(len(tout))
    for k in range(len(tc) - 1):
        sel = np.where((tout >= tc[k]) & (tout <= tc[k + 1]) if k == len(tc) - 2 else
                       (tout >= tc[k]) & (tout < tc[k + 1]))[0]
        sol = solve_ivp(rates, (tc[k], tc[k + 1]), y, method='Radau', t_eval=tout[sel], args=(k,),
                        rtol=1e-9, atol=[1e-13, 1e-9, 1e-9, 1e-13, 1e-9, 1e-13][:len(y)])
        if not sol.success:
            raise RuntimeError('integration failed: ' + sol.message)
        for j, i in enumerate(sel):
            yi = sol.y[:, j]
            s = sigma_of(tout[i], yi, k)
            sig_m[i] = (1.0 + gain) * s
            if control == 'strain':
                eps_m[i] = command(tout[i], k)[0]
            else:
                eps_m[i] = s / E + yi[0] + drift * tout[i]
        y = list(sol.y[:, -1]) if sol.t.size and sol.t[-1] == tc[k + 1] else \
            list(solve_ivp(rates, (tc[k], tc[k + 1]), y, method='Radau', args=(k,), rtol=1e-9,
                           atol=[1e-13, 1e-9, 1e-9, 1e-13, 1e-9, 1e-13][:len(y)]).y[:, -1])
    return eps_m, sig_m


def output_grid(tc, dt):
    """Every dt s and every corner"""
    t = np.arange(0.0, tc[-1] + 1e-9, dt)
    t = np.union1d(np.round(t, 9), tc)
    return t


def make_data(name, dt, eff, noise, rng):
    """(time, strain, stress) of test `name` with effects eff and Gaussian noise of sd
    noise*max|response| on the fitted response (stress; strain of a creep test)"""
    control, tc, vc = HISTORIES[name]()
    t = output_grid(tc, dt)
    eps, sig = simulate(control, tc, vc, t, eff=eff)
    if control == 'strain':
        sig = sig + noise * np.max(np.abs(sig)) * rng.standard_normal(sig.size)
    else:
        eps = eps + noise * np.max(np.abs(eps)) * rng.standard_normal(eps.size)
    return t, eps, sig


def write_csv(path, t, eps, sig):
    with open(path, 'w') as f:
        f.write('time,strain,stress\n')
        for a, b, c in zip(t, eps, sig):
            f.write(f'{a:.6f},{b:.9e},{c:.9e}\n')
