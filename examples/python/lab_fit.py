"""A laboratory velocity step fitted from Python: the basalt step b819 (data/lab/) under the
slip and the ageing law, with standard errors and the residuals.

    python examples/python/lab_fit.py [OUT_DIR]     (writes OUT_DIR/lab_fit.png)

The same numbers as `stickslip fit data/scenes/lab-basalt-b819.json --data
data/lab/velstep4_BRAVA_expb819_basalt.txt --columns 't=Time(s),x_lp=Displ(microns),mu=Friction'
--params a,b_1,d_c_1,k,mu0,trend` (docs/lab.md). Run from the repository's root.
"""
import json
import os
import sys

import matplotlib.pyplot as plt

import stickslip

out = sys.argv[1] if len(sys.argv) > 1 else "."
os.makedirs(out, exist_ok=True)
with open("data/scenes/lab-basalt-b819.json") as f:
    scene = json.load(f)
data = "data/lab/velstep4_BRAVA_expb819_basalt.txt"
columns = {"t": "Time(s)", "x_lp": "Displ(microns)", "mu": "Friction"}
fig, (top, bottom) = plt.subplots(2, 1, figsize=(6, 5), sharex=True)
for law in ["slip", "ageing"]:
    scene["model"]["states"][0]["law"] = law
    fit = stickslip.fit(scene, data, ["a", "b_1", "d_c_1", "k", "mu0", "trend"], columns=columns)
    print(f"{law} law: {'converged' if fit['converged'] else 'NOT converged'}, residual rms {fit['residual_rms']:.3e}")
    for p in fit["parameters"]:
        print(f"  {p['name']:6} = {p['value']:.5e} ± {p['standard_error']:.1e}")
    for w in fit["warnings"]:
        print("  warning:", w)
    s = fit["series"]
    t = s["t"] - s["t"][0]
    if law == "slip":
        top.plot(t, s["mu_data"], ".", ms=1, color="0.6", label="data")
    top.plot(t, s["mu_fit"], label=f"{law} law")
    bottom.plot(t, s["mu_data"] - s["mu_fit"], ".", ms=1, label=f"{law} law")
top.set_ylabel("μ")
top.legend()
bottom.set_ylabel("residual")
bottom.set_xlabel(f"t − {s['t'][0]} s")
fig.tight_layout()
fig.savefig(os.path.join(out, "lab_fit.png"), dpi=120)
