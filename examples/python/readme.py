"""The README's five lines of Python: a scene's report, and scipy's solve_ivp over radau5.

Run from the repository's root (tools/test.sh runs every script here); tests/readme.rs checks
that the README shows these lines verbatim.
"""

import stickslip
report = stickslip.run("data/scenes/earthquake.json")
print(f"period {report['cycle']['period']:.6f}, v_max {report['cycle']['v_max']:.4e}")
sol = stickslip.solve_ivp(lambda t, y: [-1e6 * (y[0] - 1.0)], (0.0, 1.0), [0.0], method="radau5")
print(f"y(1) = {sol.y[0, -1]:.12f} in {sol.t.size - 1} steps")
