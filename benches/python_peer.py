#!/usr/bin/env python3
"""stickslip.solve_ivp against scipy.integrate.solve_ivp on the stiff test set, from Python.

Usage (in a venv with stickslip, scipy, numpy; see docs/python.md):
    python benches/python_peer.py [PROBLEM ...]   (default: every problem but MEDAKZO)
    python benches/python_peer.py SLIDER          (issue #27's done-when: the spring-slider
                                                   of python/tests/problems.py to t = 40)

Both sides get the same Python right-hand sides and analytic Jacobians (benches/
test_set_scipy.py, the problems of docs/test-set.md), tolerances (atol as the Test Set
prescribes) at rtol 1e-4, 1e-7 and 1e-10, and the same accuracy measure (mescd, significant
correct digits against the Test Set's reference). Wall time is the best of up to three runs
(one when a run takes over 2 s). Prints Markdown rows: per method its scd, time, f and J
calls, and the share of the time spent inside the Python callbacks (the f and J calls timed
alone at the initial state, times their counts).
"""
import os
import sys
import time

import numpy as np
from scipy.integrate import solve_ivp as scipy_solve_ivp

sys.path.insert(0, os.path.join(os.path.dirname(__file__)))
import test_set_scipy as ts  # noqa: E402

import stickslip  # noqa: E402

METHODS = [("scipy", "Radau"), ("scipy", "BDF"), ("scipy", "LSODA"),
           ("stickslip", "Radau"), ("stickslip", "BDF"), ("stickslip", "rodas5p")]


def run_once(side, method, f, jac, ts_, y0, rtol, atol):
    solve = scipy_solve_ivp if side == "scipy" else stickslip.solve_ivp
    y, nfev, njev = np.asarray(y0, float), 0, 0
    start = time.perf_counter()
    for t0, t1 in zip(ts_[:-1], ts_[1:]):
        try:
            sol = solve(f, (t0, t1), y, method=method, rtol=rtol, atol=atol, jac=jac)
        except stickslip.SolverError as e:
            return None, time.perf_counter() - start, 0, 0, f"{e.kind} at t = {e.t:.3e}"
        nfev, njev = nfev + sol.nfev, njev + sol.njev
        if not sol.success:
            return None, time.perf_counter() - start, nfev, njev, sol.message
        y = sol.y[:, -1]
    return y, time.perf_counter() - start, nfev, njev, ""


def callback_cost(f, jac, t0, y0):
    """Seconds per call of f and of jac at the initial state."""
    y0 = np.asarray(y0, float)
    out = []
    for fun in (f, jac):
        reps, start = 0, time.perf_counter()
        while time.perf_counter() - start < 0.05:
            fun(t0, y0)
            reps += 1
        out.append((time.perf_counter() - start) / reps)
    return out


def slider():
    """The spring-slider (fig. 1, in (u, ln v, θ)) to t = 40 at rtol 1e-10, atol 1e-12 with the
    upward ln v = 0 crossings: best of 3 for stickslip, one run for scipy."""
    sys.path.insert(0, os.path.join(os.path.dirname(__file__), "..", "python", "tests"))
    import problems

    kw = dict(rtol=1e-10, atol=1e-12, jac=problems.slider_jac, events=problems.upward)
    for side, solve, methods, runs in [("stickslip", stickslip.solve_ivp, ["Radau", "BDF", "rodas5p"], 3),
                                       ("scipy", scipy_solve_ivp, ["Radau", "BDF", "LSODA"], 1)]:
        for method in methods:
            best = None
            for _ in range(runs):
                start = time.perf_counter()
                r = solve(problems.slider, (0, 40), problems.SLIDER_Y0, method=method, **kw)
                took = time.perf_counter() - start
                best = took if best is None else min(best, took)
            print(f"| {side} {method} | {best:.3f} | {r.nfev} | {r.njev} | {len(r.t_events[0])} |", flush=True)


def main(names):
    if names == ["SLIDER"]:
        print("| method | time (s) | f calls | J calls | events |")
        print("|---|---|---|---|---|")
        return slider()
    makers = {m().__getitem__(0): m for m in [ts.hires, ts.orego, ts.rober, ts.e5, ts.pollu, ts.vdpol, ts.medakzo]}
    names = names or [n for n in makers if n != "MEDAKZO"]
    print("| problem | rtol | method | scd | time (ms) | f calls | J calls | in callbacks |")
    print("|---|---|---|---|---|---|---|---|")
    for name in names:
        _, f, jac, ts_, y0, ref, atol_of = makers[name]()
        f_cost, j_cost = callback_cost(f, jac, ts_[0], y0)
        for rtol in [1e-4, 1e-7, 1e-10]:
            atol = atol_of(rtol)
            for side, method in METHODS:
                best = None
                for _ in range(3):
                    y, took, nfev, njev, msg = run_once(side, method, f, jac, ts_, y0, rtol, atol)
                    if best is None or took < best[1]:
                        best = (y, took, nfev, njev, msg)
                    if took > 2.0 or y is None:
                        break
                y, took, nfev, njev, msg = best
                share = min(1.0, (nfev * f_cost + njev * j_cost) / took)
                scd = f"{ts.mescd(y, ref, atol, rtol):.2f}" if y is not None else f"failed: {msg}"
                print(f"| {name} | {rtol:.0e} | {side} {method} | {scd} | {took * 1e3:.1f} | {nfev} | {njev} | {share:.0%} |", flush=True)


if __name__ == "__main__":
    main(sys.argv[1:])
