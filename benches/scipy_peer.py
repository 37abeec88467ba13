#!/usr/bin/env python3
"""scipy's solve_ivp (LSODA, Radau, BDF) on stickslip's work-precision problem.

Part of the work-precision runner (tools/work_precision, docs/work-precision.md).

Usage:

    python3 benches/scipy_peer.py METHOD SETTING GAMMA XI EPSILON RTOL ATOL U0 W0 THETA0 T_END CYCLES RUNS BUDGET_S
    python3 benches/scipy_peer.py --version

METHOD: LSODA, Radau or BDF; SETTING: default (solve_ivp as a new user calls it: the method,
rtol, atol, the analytic Jacobian and two events) or tuned (see TUNING). Integrates the DRR
spring-slider in y = (u, w = ln v, theta) from (U0, W0, THETA0) at t = 0 to T_END, with rtol
RTOL and atol ATOL on every component, and measures the first CYCLES cycles:

- an upward crossing of v = 1 is an event on w (direction +1), which scipy locates with brentq
  on its dense output;
- a maximum of v lies in a step whose ends have the model's dw/dt > 0, then <= 0, and v > 1
  at either end; it is the root of dw/dt along the dense output (brentq), or, when the dense
  output's values at the step ends do not bracket it, the maximum of w on the dense output
  over the step and its neighbours (bounded scalar minimization). (An event on dw/dt, as the
  other peers locate the maximum, makes scipy's own brentq fail: "f(a) and f(b) must have
  different signs", the dense output not reproducing the sign at the step ends.)
- a cycle runs from one upward crossing to the next; t0 is the time to its highest maximum,
  ln v_max the value there.

One untimed warm-up run, then up to RUNS timed runs, stopping once they add up to BUDGET_S
seconds (a warm-up longer than that is the only, timed, run). Prints one JSON line, as the
other peers do: the means over the cycles of the period, t0 and ln v_max, the minimum time
per cycle and the counters of one run, or "ok": false with the failure's reason.

scipy is imported from the running interpreter if it has it; otherwise the script creates a
virtual environment under target/scipy-venv (next to this repository's cargo target), installs
scipy there with pip, and re-runs itself with that interpreter.
"""

import json
import math
import os
import subprocess
import sys
import time

REPO = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
VENV = os.path.join(REPO, "target", "scipy-venv")
METHODS = ("LSODA", "Radau", "BDF")
# The tuned setting: at gamma = 1e8 LSODA fails on its first step with the first step it
# estimates ("Unexpected istate"); a given first step of 1e-12 gets it going at most
# tolerances (chosen among 1e-9, 1e-12, 1e-15 and 1e-17 as the one that ran the most
# tolerances from 1e-3 to 1e-12). It does not change the failures of Radau and BDF (the time
# step falls below the spacing of t in the slip's arrest).
TUNING = {"first_step": 1e-12}


def ensure_scipy():
    """Imports scipy, or installs it into target/scipy-venv and re-executes there."""
    try:
        import scipy  # noqa: F401
        return
    except ImportError:
        pass
    python = os.path.join(VENV, "bin", "python")
    if os.path.abspath(sys.executable) == os.path.abspath(python):
        sys.exit("scipy_peer.py: scipy is still missing in %s after installing it" % VENV)
    if not os.path.exists(python):
        print("scipy_peer.py: creating %s and installing scipy with pip" % VENV, file=sys.stderr)
        subprocess.run([sys.executable, "-m", "venv", VENV], check=True)
    subprocess.run([python, "-m", "pip", "install", "--quiet", "scipy"], check=True, stdout=sys.stderr)
    os.execv(python, [python] + sys.argv)


def exp(x):
    """math.exp, but inf on overflow (as numpy gives) instead of an exception."""
    try:
        return math.exp(x)
    except OverflowError:
        return math.inf


def expm1(x):
    """math.expm1, inf on overflow."""
    try:
        return math.expm1(x)
    except OverflowError:
        return math.inf


def model(gamma, xi, epsilon):
    """The right-hand side and Jacobian of crates/stickslip/src/model/drr.rs (f = ln v), same operations
    (scalar math, which is faster than numpy on three components)."""
    import numpy as np

    gamma2 = gamma * gamma

    def rhs(t, y):
        u, w, th = y
        g = u + (th + w) / xi
        return np.array([expm1(w), -gamma2 * exp(-w) * g, -exp(w) * (th + (1.0 + epsilon) * w)])

    def jac(t, y):
        u, w, th = y
        v = exp(w)
        g = u + (th + w) / xi
        a = gamma2 * exp(-w)
        return np.array([
            [0.0, v, 0.0],
            [-a, a * (g - 1.0 / xi), -a / xi],
            [0.0, -v * (th + (1.0 + epsilon) * w) - v * (1.0 + epsilon), -v],
        ])

    return rhs, jac


def run_once(method, setting, gamma, xi, epsilon, rtol, atol, y0, t_end, cycles):
    """One solve; returns (measured, counts) or raises RuntimeError with the reason."""
    import numpy as np
    from scipy.integrate import solve_ivp
    from scipy.optimize import brentq, minimize_scalar

    rhs, jac = model(gamma, xi, epsilon)

    def crossing(t, y):
        return y[1]

    crossing.direction = 1.0
    extra = TUNING if setting == "tuned" else {}
    sol = solve_ivp(rhs, (0.0, t_end), y0, method=method, rtol=rtol, atol=atol, jac=jac,
                    events=[crossing], dense_output=True, **extra)
    if sol.status != 0:
        raise RuntimeError("solve_ivp status %d at t = %r: %s" % (sol.status, float(sol.t[-1]), sol.message))
    finite = np.isfinite(sol.y).all(axis=0)
    if not finite.all():
        first = int(np.argmin(finite))
        raise RuntimeError("solve_ivp returned success, but its solution is not finite from t = %r on "
                           "(last finite step at t = %r)" % (float(sol.t[first]), float(sol.t[first - 1])))
    ups = [float(t) for t in sol.t_events[0]]
    maxima = []
    dw = [rhs(t, y)[1] for t, y in zip(sol.t, sol.y.T)]
    for i in range(len(sol.t) - 1):
        a, b = float(sol.t[i]), float(sol.t[i + 1])
        if not (dw[i] > 0.0 >= dw[i + 1] and max(sol.y[1, i], sol.y[1, i + 1]) > 0.0):
            continue
        g = lambda t: rhs(t, sol.sol(t))[1]  # noqa: E731
        if g(a) > 0.0 > g(b):
            tp = brentq(g, a, b, xtol=4 * np.finfo(float).eps * abs(b))
        else:  # the dense output does not bracket the root: maximize w on it instead
            lo = float(sol.t[max(i - 1, 0)])
            hi = float(sol.t[min(i + 2, len(sol.t) - 1)])
            tp = minimize_scalar(lambda t: -sol.sol(t)[1], bounds=(lo, hi), method="bounded",
                                 options={"xatol": 1e-15 * max(1.0, abs(hi))}).x
        wp = float(sol.sol(tp)[1])
        if wp > 0.0:
            maxima.append((float(tp), wp))
    if len(ups) < cycles + 1:
        raise RuntimeError("only %d upward crossings of v = 1 before the end time (%d needed)" % (len(ups), cycles + 1))
    period = t0 = ln_v_max = 0.0
    for k in range(cycles):
        c0, c1 = ups[k], ups[k + 1]
        inside = [m for m in maxima if c0 <= m[0] < c1]
        if not inside:
            raise RuntimeError("cycle %d (%r to %r) has no maximum of v above 1" % (k, c0, c1))
        tp, wp = max(inside, key=lambda m: m[1])
        period += c1 - c0
        t0 += tp - c0
        ln_v_max += wp
    measured = {"period": period / cycles, "t0": t0 / cycles, "ln_v_max": ln_v_max / cycles}
    if not all(math.isfinite(v) for v in measured.values()):
        raise RuntimeError("non-finite cycle values %r" % measured)
    counts = {"steps": len(sol.t) - 1, "rhs": int(sol.nfev), "jac": int(sol.njev), "lu": int(sol.nlu), "rejected": None}
    return measured, counts


def main():
    if sys.argv[1:] == ["--version"]:
        ensure_scipy()
        import numpy
        import scipy
        print(json.dumps({"python": sys.version.split()[0], "scipy": scipy.__version__, "numpy": numpy.__version__}))
        return
    args = sys.argv[1:]
    if len(args) != 14 or args[0] not in METHODS or args[1] not in ("default", "tuned"):
        sys.stderr.write(__doc__)
        sys.exit(64)
    ensure_scipy()
    method, setting = args[0], args[1]
    try:
        gamma, xi, epsilon, rtol, atol, u0, w0, th0, t_end = (float(a) for a in args[2:11])
        cycles, runs = int(args[11]), int(args[12])
        budget = float(args[13])
    except ValueError:
        sys.stderr.write(__doc__)
        sys.exit(64)
    line = {"method": "scipy-" + method.lower(), "setting": setting, "gamma": gamma, "rtol": rtol, "atol": atol}
    if setting == "tuned":
        line["tuning"] = ", ".join("%s %r" % kv for kv in TUNING.items())
    problem = (method, setting, gamma, xi, epsilon, rtol, atol, [u0, w0, th0], t_end, cycles)
    timed = []
    try:
        clock = time.perf_counter()
        measured, counts = run_once(*problem)
        warm_up = time.perf_counter() - clock
        if warm_up > budget:
            timed.append(warm_up)
        else:
            while len(timed) < runs and sum(timed) < budget:
                clock = time.perf_counter()
                measured, counts = run_once(*problem)
                timed.append(time.perf_counter() - clock)
        line.update(ok=True, cycles=cycles, time_per_cycle_s=min(timed) / cycles, runs=len(timed))
        line.update(measured)
        line.update(counts)
    except Exception as e:  # every failure is reported with its reason, never dropped
        line.update(ok=False, error="%s: %s" % (type(e).__name__, e))
    print(json.dumps(line))


if __name__ == "__main__":
    main()
