"""solve_ivp on a user's own model: a spring-slider written in Python, in (u, ln v, θ).

    python examples/python/own_model.py [OUT_DIR]     (writes OUT_DIR/own_model.png)

stickslip.solve_ivp has scipy.integrate.solve_ivp's signature: the same call runs
stickslip's Radau5 ("Radau"), CVODE ("BDF") and Rodas5P. Fig. 1's γ = 1e3, ξ = 0.7, ε = 0.72
(slip law), to t = 40 at rtol 1e-10, with the upward crossings of v = 1 as events.
"""
import os
import sys
import time

import matplotlib.pyplot as plt
import numpy as np

import stickslip


def slider(t, y, gamma, xi, epsilon):
    u, w, theta = y
    v = np.exp(w)
    return np.array([v - 1.0, -gamma**2 * np.exp(-w) * (u + (theta + w) / xi),
                     -v * (theta + (1.0 + epsilon) * w)])


def jacobian(t, y, gamma, xi, epsilon):
    u, w, theta = y
    v, a = np.exp(w), gamma**2 * np.exp(-w)
    return np.array([[0.0, v, 0.0],
                     [-a, a * (u + (theta + w) / xi) - a / xi, -a / xi],
                     [0.0, -v * (theta + (1.0 + epsilon) * w) - v * (1.0 + epsilon), -v]])


def v_up(t, y, *args):
    return y[1]


v_up.direction = 1

out = sys.argv[1] if len(sys.argv) > 1 else "."
os.makedirs(out, exist_ok=True)
y0 = [0.9902102579427791, np.log(0.5), 0.0]
fig, ax = plt.subplots(figsize=(7, 3.5))
grid = np.linspace(0, 40, 4001)
for method in ["Radau", "BDF", "rodas5p"]:
    start = time.perf_counter()
    sol = stickslip.solve_ivp(slider, (0, 40), y0, method=method, rtol=1e-10, atol=1e-12,
                              jac=jacobian, args=(1e3, 0.7, 0.72), events=v_up,
                              dense_output=True)
    took = time.perf_counter() - start
    print(f"{method:8s} {took:6.3f} s, {sol.nfev} f, {sol.njev} J, {sol.nlu} LU; "
          f"v = 1 upwards at t = {np.array2string(sol.t_events[0], precision=6)}")
    ax.plot(grid, sol.sol(grid)[1], lw=1, label=method)
ax.set_xlabel("t (D_c/v0)")
ax.set_ylabel("ln v")
ax.legend()
fig.tight_layout()
path = os.path.join(out, "own_model.png")
fig.savefig(path, dpi=120)
print(f"wrote {path}")
