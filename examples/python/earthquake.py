"""The earthquake scene from Python: its report, and one cycle of v(t) drawn with matplotlib.

    python examples/python/earthquake.py [OUT_DIR]     (writes OUT_DIR/earthquake.png)

Runs data/scenes/earthquake.json (γ = 1e8, ξ = 0.8, ε = 1; D_c/v0 = 2.7 years) with one
cycle's trajectory recorded, prints the period in years and plots ln v over the cycle.
"""
import json
import os
import sys

import matplotlib
import matplotlib.pyplot as plt
import numpy as np

import stickslip

here = os.path.dirname(os.path.abspath(__file__))
out = sys.argv[1] if len(sys.argv) > 1 else "."
os.makedirs(out, exist_ok=True)
with open(os.path.join(here, "..", "..", "data", "scenes", "earthquake.json")) as f:
    scene = json.load(f)
scene["analyses"].append({"trajectory": {"cycles": 1}})
report = stickslip.run(scene)
cycle = report["cycle"]
years = report["physical"]["time_scale"]
print(f"earthquake: period {cycle['period']:.6f} D_c/v0 = {report['physical']['period']:.4f} "
      f"{report['physical']['time_unit']}, {report['solver']['stats']['steps']} steps, "
      f"SUNDIALS {report['sundials_version']}")
c = cycle["trajectory"][0]  # numpy arrays; t from the cycle's upward crossing of v = 1
fig, ax = plt.subplots(figsize=(7, 3.5))
ax.plot(c["t"] * years, np.log10(c["v"]), lw=1)
ax.set_xlabel("time since v = 1 (years)")
ax.set_ylabel("log10 v / v0")
ax.set_title(f"earthquake scene: one cycle, period {report['physical']['period']:.2f} years")
fig.tight_layout()
path = os.path.join(out, "earthquake.png")
fig.savefig(path, dpi=120)
print(f"wrote {path} (matplotlib backend {matplotlib.get_backend()})")
