#!/usr/bin/env python3
"""scipy's solve_ivp (Radau, BDF, LSODA) on the stiff test set of tests/test_set/ (HIRES, OREGO,
ROBER, E5, POLLU, VDPOL, MEDAKZO), as peers in docs/test-set.md.

Usage: python3 benches/test_set_scipy.py   (prints the Markdown rows of the peer table)

Same problems, reference solutions (Test Set for IVP Solvers, release 2.4), tolerances (atol as
the Test Set prescribes) and accuracy measure (mixed-error significant correct digits, mescd) as
tests/test_set/; analytic Jacobians; one solve_ivp call per smooth segment (MEDAKZO restarts at
t = 5). Wall time is the best of three runs.
"""
import os
import time

import numpy as np
from scipy.integrate import solve_ivp


def hires():
    def f(t, y):
        d = np.empty(8)
        d[0] = -1.71 * y[0] + 0.43 * y[1] + 8.32 * y[2] + 0.0007
        d[1] = 1.71 * y[0] - 8.75 * y[1]
        d[2] = -10.03 * y[2] + 0.43 * y[3] + 0.035 * y[4]
        d[3] = 8.32 * y[1] + 1.71 * y[2] - 1.12 * y[3]
        d[4] = -1.745 * y[4] + 0.43 * (y[5] + y[6])
        d[5] = -280.0 * y[5] * y[7] + 0.69 * y[3] + 1.71 * y[4] - 0.43 * y[5] + 0.69 * y[6]
        d[6] = 280.0 * y[5] * y[7] - 1.81 * y[6]
        d[7] = -d[6]
        return d

    def jac(t, y):
        j = np.zeros((8, 8))
        for r, c, v in [(0, 0, -1.71), (0, 1, 0.43), (0, 2, 8.32), (1, 0, 1.71), (1, 1, -8.75), (2, 2, -10.03),
                        (2, 3, 0.43), (2, 4, 0.035), (3, 1, 8.32), (3, 2, 1.71), (3, 3, -1.12), (4, 4, -1.745),
                        (4, 5, 0.43), (4, 6, 0.43), (5, 3, 0.69), (5, 4, 1.71), (5, 5, -280.0 * y[7] - 0.43),
                        (5, 6, 0.69), (5, 7, -280.0 * y[5]), (6, 5, 280.0 * y[7]), (6, 6, -1.81), (6, 7, 280.0 * y[5]),
                        (7, 5, -280.0 * y[7]), (7, 6, 1.81), (7, 7, -280.0 * y[5])]:
            j[r, c] = v
        return j

    ref = [0.7371312573325668e-3, 0.1442485726316185e-3, 0.5888729740967575e-4, 0.1175651343283149e-2,
           0.2386356198831331e-2, 0.6238968252742796e-2, 0.2849998395185769e-2, 0.2850001604814231e-2]
    return "HIRES", f, jac, [0, 321.8122], [1, 0, 0, 0, 0, 0, 0, 0.0057], ref, lambda r: r


def orego():
    s, q, w = 77.27, 8.375e-6, 0.161

    def f(t, y):
        return np.array([s * (y[1] + y[0] * (1 - q * y[0] - y[1])), (y[2] - (1 + y[0]) * y[1]) / s, w * (y[0] - y[2])])

    def jac(t, y):
        return np.array([[s * (1 - 2 * q * y[0] - y[1]), s * (1 - y[0]), 0],
                         [-y[1] / s, -(1 + y[0]) / s, 1 / s], [w, 0, -w]])

    return "OREGO", f, jac, [0, 360.0], [1, 2, 3], [0.1000814870318523e1, 0.1228178521549917e4, 0.1320554942846706e3], lambda r: r


def rober():
    def f(t, y):
        return np.array([-0.04 * y[0] + 1e4 * y[1] * y[2], 0.04 * y[0] - 1e4 * y[1] * y[2] - 3e7 * y[1] ** 2, 3e7 * y[1] ** 2])

    def jac(t, y):
        return np.array([[-0.04, 1e4 * y[2], 1e4 * y[1]], [0.04, -1e4 * y[2] - 6e7 * y[1], -1e4 * y[1]], [0, 6e7 * y[1], 0]])

    ref = [0.2083340149701255e-7, 0.8333360770334713e-13, 0.9999999791665050e0]
    return "ROBER", f, jac, [0, 1e11], [1, 0, 0], ref, lambda r: 1e-4 * r


def e5():
    a, b, cm, c = 7.89e-10, 1.1e7, 1.13e9, 1.13e3

    def f(t, y):
        p1, p2, p3, p4 = a * y[0], b * y[0] * y[2], cm * y[1] * y[2], c * y[3]
        f1, f2, f4 = -p1 - p2, p1 - p3, p2 - p4
        return np.array([f1, f2, f2 - f4, f4])

    def jac(t, y):
        return np.array([[-a - b * y[2], 0, -b * y[0], 0], [a, -cm * y[2], -cm * y[1], 0],
                         [a - b * y[2], -cm * y[2], -b * y[0] - cm * y[1], c], [b * y[2], 0, b * y[0], -c]])

    ref = [0.1152903278711829e-290, 0.8867655517642120e-22, 0.8854814626268838e-22, 0.0]
    return "E5", f, jac, [0, 1e13], [1.76e-3, 0, 0, 0], ref, lambda r: 1.7e-24


K = [0.0, 0.35, 0.266e2, 0.123e5, 0.86e-3, 0.82e-3, 0.15e5, 0.13e-3, 0.24e5, 0.165e5, 0.9e4, 0.22e-1, 0.12e5,
     0.188e1, 0.163e5, 0.48e7, 0.35e-3, 0.175e-1, 0.1e9, 0.444e12, 0.124e4, 0.21e1, 0.578e1, 0.474e-1, 0.178e4, 0.312e1]
# Reactions of POLLU: (rate constant, reactants, products), 1-based species as in pollu.f.
POLLU_REACTIONS = [
    (1, [1], [2, 3]), (2, [2, 4], [1]), (3, [5, 2], [1, 6]), (4, [7], [5, 5, 8]), (5, [7], [8]), (6, [7, 6], [5, 8]),
    (7, [9], [5, 8, 10]), (8, [9, 6], [11]), (9, [11, 2], [1, 10, 12]), (10, [11, 1], [13]), (11, [13], [1, 11]),
    (12, [10, 2], [1, 14]), (13, [14], [5, 7]), (14, [1, 6], [15]), (15, [3], [4]), (16, [4], [16]), (17, [4], [3]),
    (18, [16], [6, 6]), (19, [16], [3]), (20, [17, 6], [5, 18]), (21, [19], [2]), (22, [19], [1, 3]),
    (23, [1, 4], [19]), (24, [19, 1], [20]), (25, [20], [1, 19]),
]


def pollu():
    def f(t, y):
        d = np.zeros(20)
        for k, reac, prod in POLLU_REACTIONS:
            r = K[k] * np.prod([y[i - 1] for i in reac])
            for i in reac:
                d[i - 1] -= r
            for i in prod:
                d[i - 1] += r
        return d

    def jac(t, y):
        j = np.zeros((20, 20))
        for k, reac, prod in POLLU_REACTIONS:
            for m, s in enumerate(reac):
                dr = K[k] * np.prod([y[i - 1] for n, i in enumerate(reac) if n != m])
                for i in reac:
                    j[i - 1, s - 1] -= dr
                for i in prod:
                    j[i - 1, s - 1] += dr
        return j

    y0 = np.zeros(20)
    y0[[1, 3, 6, 7, 8, 16]] = [0.2, 0.04, 0.1, 0.3, 0.01, 0.007]
    ref = [0.5646255480022769e-01, 0.1342484130422339e+00, 0.4139734331099427e-08, 0.5523140207484359e-02,
           0.2018977262302196e-06, 0.1464541863493966e-06, 0.7784249118997964e-01, 0.3245075353396018e+00,
           0.7494013383880406e-02, 0.1622293157301561e-07, 0.1135863833257075e-07, 0.2230505975721359e-02,
           0.2087162882798630e-03, 0.1396921016840158e-04, 0.8964884856898295e-02, 0.4352846369330103e-17,
           0.6899219696263405e-02, 0.1007803037365946e-03, 0.1772146513969984e-05, 0.5682943292316392e-04]
    return "POLLU", f, jac, [0, 60.0], y0, ref, lambda r: r


def vdpol():
    eps = 1e-6

    def f(t, y):
        return np.array([y[1], ((1 - y[0] ** 2) * y[1] - y[0]) / eps])

    def jac(t, y):
        return np.array([[0, 1], [(-2 * y[0] * y[1] - 1) / eps, (1 - y[0] ** 2) / eps]])

    return "VDPOL", f, jac, [0, 2.0], [2, 0], [0.1706167732170483e1, -0.8928097010247975e0], lambda r: r


def medakzo():
    n, kk, cc = 200, 100.0, 4.0
    dz = 1.0 / n
    zeta = np.arange(1, n + 1) * dz
    dum = (zeta - 1) * ((zeta - 1) / cc)
    alpha = 2 * (zeta - 1) * (dum / cc)
    bz = dum * dum / (dz * dz)

    def f(t, y):
        u, v = y[0::2], y[1::2]
        phi = 2.0 if t <= 5.0 else 0.0
        left = np.concatenate(([phi], u[:-1]))
        right = np.concatenate((u[1:], [0.0]))
        du = (left - 2 * u + right) * bz + alpha * (right - left) / (2 * dz) - kk * u * v
        du[-1] = -kk * u[-1] * v[-1]
        d = np.empty(2 * n)
        d[0::2], d[1::2] = du, -kk * u * v
        return d

    def jac(t, y):
        j = np.zeros((2 * n, 2 * n))
        for k in range(n):
            i = 2 * k
            j[i + 1, i], j[i + 1, i + 1], j[i, i + 1] = -kk * y[i + 1], -kk * y[i], -kk * y[i]
            if k == n - 1:
                j[i, i] = -kk * y[i + 1]
                continue
            j[i, i] = -2 * bz[k] - kk * y[i + 1]
            j[i, i + 2] = bz[k] + alpha[k] / (2 * dz)
            if k > 0:
                j[i, i - 2] = bz[k] - alpha[k] / (2 * dz)
        return j

    path = os.path.join(os.path.dirname(__file__), "..", "data", "test_set", "medakzo.txt")
    with open(path) as fh:
        ref = [float(l.strip().replace("d", "e")) for l in fh if l.strip() and not l.startswith("#")]
    y0 = np.tile([0.0, 1.0], n)
    return "MEDAKZO", f, jac, [0, 5.0, 20.0], y0, ref, lambda r: r


def mescd(y, ref, atol, rtol):
    y, ref = np.asarray(y), np.asarray(ref)
    err = np.max(np.abs(y - ref) / (atol / rtol + np.abs(ref)))
    return float("inf") if err == 0 else -np.log10(err)


def main():
    print("| problem | method | rtol | scd | steps | f evals | J evals | LU | time (ms) |")
    print("|---|---|---|---|---|---|---|---|---|")
    for make in [hires, orego, rober, e5, pollu, vdpol, medakzo]:
        name, f, jac, ts, y0, ref, atol_of = make()
        for method in ["BDF", "Radau", "LSODA"]:
            for rtol in [1e-4, 1e-7, 1e-10]:
                atol = atol_of(rtol)
                best, row = float("inf"), None
                for _ in range(3):
                    start = time.perf_counter()
                    y, ok, nfev, njev, nlu, msg, steps = np.asarray(y0, float), True, 0, 0, 0, "", 0
                    for t0, t1 in zip(ts[:-1], ts[1:]):
                        sol = solve_ivp(f, (t0, t1), y, method=method, rtol=rtol, atol=atol, jac=jac)
                        nfev, njev, nlu, steps = nfev + sol.nfev, njev + sol.njev, nlu + sol.nlu, steps + sol.t.size - 1
                        if not sol.success:
                            ok, msg = False, sol.message
                            break
                        y = sol.y[:, -1]
                    elapsed = time.perf_counter() - start
                    if elapsed < best:
                        best = elapsed
                        row = (ok, y, nfev, njev, nlu, msg, steps)
                    if best > 5.0:
                        break
                ok, y, nfev, njev, nlu, msg, steps = row
                if ok:
                    print(f"| {name} | scipy {method} | {rtol:.0e} | {mescd(y, ref, atol, rtol):.2f} | {steps} | {nfev} | {njev} | {nlu} | {best * 1e3:.1f} |", flush=True)
                else:
                    print(f"| {name} | scipy {method} | {rtol:.0e} | failed: {msg} | | | | | {best * 1e3:.1f} |", flush=True)


if __name__ == "__main__":
    main()
