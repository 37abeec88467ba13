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
calls, and the share of the time spent inside the Python callbacks, measured in more runs
with f and jac wrapped in timers (the rest is the integrator and the call overhead; of up to
three runs the one with the least rest), and that rest per callback call.
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


def timed(fun, spent):
    """fun, adding the seconds spent in it to spent[0]."""
    clock = time.perf_counter

    def wrapped(t, y):
        start = clock()
        try:
            return fun(t, y)
        finally:
            spent[0] += clock() - start

    return wrapped


def callback_share(side, method, f, jac, ts_, y0, rtol, atol):
    """Runs with f and jac timed (the one with the least time outside them, of up to three):
    the share of its time spent in them, and the rest of the time per call of either (µs)."""
    best = None
    for _ in range(3):
        spent = [0.0]
        _, took, nfev, njev, _ = run_once(side, method, timed(f, spent), timed(jac, spent), ts_,
                                          y0, rtol, atol)
        if best is None or took - spent[0] < best[0] - best[1]:
            best = (took, spent[0], nfev + njev)
        if took > 2.0:
            break
    took, spent, calls = best
    return spent / took, (took - spent) / max(calls, 1) * 1e6


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


def at_scd(points, scd):
    """A peer's time at accuracy scd: log time linear in scd between its (scd, time) points;
    None outside their range."""
    points = sorted(points)
    for (s0, t0), (s1, t1) in zip(points, points[1:]):
        if s0 <= scd <= s1 and s1 > s0:
            return float(np.exp(np.log(t0) + (scd - s0) / (s1 - s0) * (np.log(t1) - np.log(t0))))
    return None


def equal_accuracy(results):
    """The second table: each stickslip row against scipy's Radau, LSODA and BDF at its scd."""
    peers = ["Radau", "LSODA", "BDF"]
    print()
    print("| problem | stickslip method | scd | time (ms) | "
          + " | ".join(f"scipy {p} at that scd (ms) | ×" for p in peers) + " |")
    print("|---|---|---|---|" + "---|---|" * len(peers))
    for (name, side, method), rows in results.items():
        if side != "stickslip":
            continue
        for scd, took in rows:
            cells = []
            for peer in peers:
                t = at_scd(results.get((name, "scipy", peer), []), scd)
                cells += ["outside its range", ""] if t is None else [f"{t:.1f}", f"{t / took:.1f}"]
            print(f"| {name} | {method} | {scd:.2f} | {took:.1f} | " + " | ".join(cells) + " |",
                  flush=True)


def main(names):
    if names == ["SLIDER"]:
        print("| method | time (s) | f calls | J calls | events |")
        print("|---|---|---|---|---|")
        return slider()
    makers = {m().__getitem__(0): m for m in [ts.hires, ts.orego, ts.rober, ts.e5, ts.pollu, ts.vdpol, ts.medakzo]}
    names = names or [n for n in makers if n != "MEDAKZO"]
    print("| problem | rtol | method | scd | time (ms) | f calls | J calls | in callbacks | rest per call (µs) |")
    print("|---|---|---|---|---|---|---|---|---|")
    results = {}
    for name in names:
        _, f, jac, ts_, y0, ref, atol_of = makers[name]()
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
                share, rest = callback_share(side, method, f, jac, ts_, y0, rtol, atol)
                scd = f"{ts.mescd(y, ref, atol, rtol):.2f}" if y is not None else f"failed: {msg}"
                if y is not None:
                    results.setdefault((name, side, method), []).append((float(scd), took * 1e3))
                print(f"| {name} | {rtol:.0e} | {side} {method} | {scd} | {took * 1e3:.1f} | {nfev} | {njev} | {share:.0%} | {rest:.1f} |", flush=True)
    equal_accuracy(results)


if __name__ == "__main__":
    main(sys.argv[1:])
