"""A sweep from Python: the period of fig. 1's cycle as ε varies, in parallel.

    python examples/python/sweep.py [OUT_DIR]     (writes OUT_DIR/sweep.png)

The same rows as `stickslip sweep --param epsilon=0.6:1.2:7` (one per point, in order).
"""
import os
import sys

import matplotlib.pyplot as plt

import stickslip

out = sys.argv[1] if len(sys.argv) > 1 else "."
os.makedirs(out, exist_ok=True)
scene = {"name": "fig1-epsilon", "model": {"gamma": 1e3, "xi": 0.7, "epsilon": 0.72},
         "solver": {"method": "cvode-bdf", "rtol": 1e-8, "atol": 1e-10},
         "analyses": ["hopf", "cycle"]}
rows = stickslip.sweep(scene, {"epsilon": "0.6:1.2:7"}, threads=2)
eps, periods = [], []
for row in rows:
    if row["error"] is None and row["report"]["cycle"].get("period") is not None:
        eps.append(row["params"]["epsilon"])
        periods.append(row["report"]["cycle"]["period"])
    print(f"epsilon = {row['params']['epsilon']:.2f}: "
          + (f"period {row['report']['cycle'].get('period')}" if row["error"] is None else row["error"]))
if not periods:
    sys.exit("no point of the sweep found a cycle")
fig, ax = plt.subplots(figsize=(5, 3.5))
ax.plot(eps, periods, "o-")
ax.set_xlabel("ε = (B − A)/A")
ax.set_ylabel("period (D_c/v0)")
ax.set_title("γ = 1e3, ξ = 0.7")
fig.tight_layout()
path = os.path.join(out, "sweep.png")
fig.savefig(path, dpi=120)
print(f"wrote {path}")
