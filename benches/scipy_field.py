#!/usr/bin/env python3
"""A trajectory of the field scene written by scipy, for `stickslip compare --against`.

The scene: quasi-dynamic (no inertia), ageing law, xi = 0.25, epsilon = 0.5, radiation
damping eta = 5e-8, start v = 0.5, theta = 0 (docs/compare.md). Independent of stickslip's
formulation: the state is (u, theta), du/dt = v - 1, dtheta/dt = (1+eps)(exp(-theta/(1+eps)) - v),
and v comes from the force balance xi*u + theta + ln v + eta*v = 0, solved by Newton at each
evaluation; the Jacobian is analytic. Every step of solve_ivp is written as CSV t,u,v,theta.

Usage (scipy in a venv: python3 -m venv V && V/bin/pip install scipy):

    V/bin/python benches/scipy_field.py METHOD RTOL T_END OUT.csv

METHOD: Radau or BDF (solve_ivp's names); RTOL is also the atol. Measured (scipy 1.17.1):
Radau at rtol 1e-10 to t = 1354.2 (26 periods): 116 931 steps, ~160 s, agrees with
stickslip's reference at --tolerance 1e-6; BDF at rtol 1e-10 stops in the first slip
(t = 11.96) with "Required step size is less than spacing between numbers".
"""
import sys, time, math
import numpy as np
from scipy.integrate import solve_ivp

XI, EPS, ETA = 0.25, 0.5, 5e-8

def w_of(u, th):
    c = -(XI * u + th)          # w + eta e^w = c
    w = min(c, math.log(c / ETA) if c > 0 else c)
    for _ in range(100):
        e = ETA * math.exp(w)
        f = w + e - c
        dw = -f / (1.0 + e)
        w += dw
        if abs(dw) <= 1e-16 * max(1.0, abs(w)):
            break
    return w

def rhs(t, y):
    u, th = y
    v = math.exp(w_of(u, th))
    return [v - 1.0, (1.0 + EPS) * (math.exp(-th / (1.0 + EPS)) - v)]

def jac(t, y):
    u, th = y
    v = math.exp(w_of(u, th))
    # dw/du = -xi/(1+eta v), dw/dtheta = -1/(1+eta v); dv = v dw
    s = 1.0 + ETA * v
    dvdu, dvdth = -XI * v / s, -v / s
    a = 1.0 + EPS
    return [[dvdu, dvdth], [-a * dvdu, -math.exp(-th / a) - a * dvdth]]

method, rtol, end, out = sys.argv[1], float(sys.argv[2]), float(sys.argv[3]), sys.argv[4]
v0, th0 = 0.5, 0.0
u0 = -(th0 + math.log(v0) + ETA * v0) / XI
start = time.time()
sol = solve_ivp(rhs, (0.0, end), [u0, th0], method=method, rtol=rtol, atol=rtol, jac=jac)
print(method, rtol, sol.status, sol.message, len(sol.t), "steps", f"{time.time()-start:.1f} s", file=sys.stderr)
with open(out, "w") as f:
    f.write(f"# field scene by scipy {method} rtol {rtol}: (u, theta), v from the force balance\n")
    f.write("t,u,v,theta\n")
    for t, u, th in zip(sol.t, sol.y[0], sol.y[1]):
        f.write(f"{t:.17e},{u:.17e},{math.exp(w_of(u, th)):.17e},{th:.17e}\n")
