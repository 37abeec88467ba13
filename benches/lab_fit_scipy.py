"""An independent fit of the lab model with scipy, and its cost beside `stickslip fit`.

    python benches/lab_fit_scipy.py [--stickslip target/release/stickslip] [--out FILE.json]

scipy's least_squares (method "lm", MINPACK, finite-difference Jacobian) over a model written
here from the equations, independent of stickslip: state (μ, ln θ) in time, V solved from μ,
each load segment integrated apart by solve_ivp's Radau at rtol 1e-10, atol 1e-12, output at the
record's times. Standard errors from σ̂²(JᵀJ)⁻¹ with the Jacobian least_squares returns.

Cases: the basalt step b819 (data/lab/, slip and ageing law; a, b, D_c, k, μ0, trend) and a
synthetic record (known a, b, D_c plus N(0, 1e-4²) noise; the record is made here by Radau at
rtol 1e-12). Each case is also fitted by `stickslip fit` (CLI, --json), timed the same way (wall
clock of the whole fit, best of 3). Prints a table and writes the numbers as JSON
(data/reference/lab/fit_reference.json, which tests/lab_fit.rs checks stickslip against).
Needs numpy and scipy (a venv: python3 -m venv V && V/bin/pip install scipy).
"""
import argparse, json, math, os, subprocess, sys, tempfile, time
import numpy as np
from scipy.integrate import solve_ivp
from scipy.optimize import least_squares

REPO = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
RTOL, ATOL = 1e-10, 1e-12
NAMES = ["a", "b_1", "d_c_1", "k", "mu0", "trend"]


def friction_model(law, v0, segments, t_end, times, a, b, dc, k, mu0):
    """μ at `times`, steady start at the first velocity."""
    def lnv(mu, lth):
        return (mu - mu0 - b * (lth + math.log(v0 / dc))) / a + math.log(v0)

    def f(vlp):
        def rhs(t, z):
            V = math.exp(lnv(z[0], z[1]))
            th = math.exp(z[1])
            if law == "ageing":
                d = 1 - V * th / dc
            else:
                x = V * th / dc
                d = -x * math.log(x)
            return [k * (vlp - V), d / th]
        return rhs

    v1 = segments[0][1]
    z = [mu0 + (a - b) * math.log(v1 / v0), math.log(dc / v1)]
    out = np.empty(len(times))
    i = 0
    for j, (t0, vlp) in enumerate(segments):
        t1 = segments[j + 1][0] if j + 1 < len(segments) else t_end
        last = j + 1 == len(segments)
        sel = [ii for ii in range(i, len(times)) if times[ii] >= t0 and (times[ii] < t1 or (last and times[ii] <= t1))]
        sol = solve_ivp(f(vlp), (t0, t1), z, method="Radau", rtol=RTOL, atol=ATOL, dense_output=True)
        if sol.status < 0:
            raise RuntimeError(sol.message)
        if sel:
            out[sel[0]:sel[-1] + 1] = sol.sol(np.array([times[ii] for ii in sel]))[0]
            i = sel[-1] + 1
        z = sol.y[:, -1]
    return out


def scipy_fit(case):
    t, mu = case["t"], case["mu"]
    segs = case["segments"]
    x_lp = np.array([seg_x(segs, tt) for tt in t])
    names = case["params"]
    start = dict(case["start"], trend=0.0)
    fixed = dict(start)

    def unpack(x):
        p = dict(fixed)
        for n, v in zip(names, x):
            p[n] = math.exp(v) if n == "d_c_1" else v
        return p

    def residuals(x):
        p = unpack(x)
        m = friction_model(case["law"], case["v0"], segs, case["t_end"], t, p["a"], p["b_1"], p["d_c_1"], p["k"], p["mu0"])
        return m + p["trend"] * (x_lp - x_lp[0]) - mu

    x0 = [math.log(start[n]) if n == "d_c_1" else start[n] for n in names]
    wall = time.perf_counter()
    res = least_squares(residuals, x0, method="lm", x_scale="jac")
    wall = time.perf_counter() - wall
    J, r = res.jac, res.fun
    s2 = r @ r / (len(r) - len(x0))
    cov = s2 * np.linalg.inv(J.T @ J)
    se = np.sqrt(np.diag(cov))
    values, errors = {}, {}
    for j, n in enumerate(names):
        if n == "d_c_1":
            values[n], errors[n] = math.exp(res.x[j]), math.exp(res.x[j]) * se[j]
        else:
            values[n], errors[n] = res.x[j], se[j]
    return {"values": values, "standard_errors": errors, "evaluations": int(res.nfev),
            "rms": float(math.sqrt(r @ r / len(r))), "seconds": wall, "status": int(res.status)}


def seg_x(segs, t):
    x = 0.0
    for j, (t0, v) in enumerate(segs):
        t1 = segs[j + 1][0] if j + 1 < len(segs) else math.inf
        if t <= t0:
            break
        x += v * (min(t, t1) - t0)
    return x


def stickslip_fit(exe, case, scene_path, data_path, columns):
    best, report = math.inf, None
    for _ in range(3):
        wall = time.perf_counter()
        out = subprocess.run([exe, "fit", scene_path, "--data", data_path, "--columns", columns,
                              "--params", ",".join(case["params"]), "--json"],
                             capture_output=True, text=True, check=True)
        best = min(best, time.perf_counter() - wall)
        report = json.loads(out.stdout)
    p = {q["name"]: q for q in report["parameters"]}
    return {"values": {n: p[n]["value"] for n in case["params"]},
            "standard_errors": {n: p[n]["standard_error"] for n in case["params"]},
            "evaluations": report["evaluations"], "rms": report["residual_rms"], "seconds": best}


def scene(case, name):
    return {"name": name, "model": {"kind": "lab", "mu0": case["start"]["mu0"], "a": case["start"]["a"],
            "v0": case["v0"], "k": case["start"]["k"],
            "states": [{"law": case["law"], "b": case["start"]["b_1"], "d_c": case["start"]["d_c_1"]}]},
            "loading": {"segments": [{"t_start": t0, "velocity": v} for t0, v in case["segments"]], "t_end": case["t_end"]},
            "initial": "steady", "solver": {"method": "cvode-bdf", "rtol": 1e-10}}


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("--stickslip", default=os.path.join(REPO, "target", "release", "stickslip"))
    ap.add_argument("--out")
    args = ap.parse_args()
    tmp = tempfile.mkdtemp()
    basalt = np.loadtxt(os.path.join(REPO, "data", "lab", "velstep4_BRAVA_expb819_basalt.txt"), skiprows=1)
    b819 = json.load(open(os.path.join(REPO, "data", "scenes", "lab-basalt-b819.json")))
    m = b819["model"]
    segs = [(s["t_start"], s["velocity"]) for s in b819["loading"]["segments"]]
    cases = {}
    for law in ["slip", "ageing"]:
        cases[f"basalt_{law}"] = {
            "law": law, "v0": m["v0"], "segments": segs, "t_end": b819["loading"]["t_end"],
            "t": basalt[:, 0], "mu": basalt[:, 2], "params": NAMES,
            "start": {"a": m["a"], "b_1": m["states"][0]["b"], "d_c_1": m["states"][0]["d_c"], "k": m["k"], "mu0": m["mu0"]},
            "data": os.path.join(REPO, "data", "lab", "velstep4_BRAVA_expb819_basalt.txt"),
            "columns": "t=Time(s),x_lp=Displ(microns),mu=Friction"}
    # Synthetic: truth a = 0.011, b = 0.015, D_c = 5, k = 3e-3, steps 1 -> 10 -> 3 um/s, 10 Hz.
    t = np.round(np.arange(0, 801) * 0.1, 10)
    ssegs = [(0.0, 1.0), (10.0, 10.0), (40.0, 3.0)]
    global RTOL, ATOL
    RTOL, ATOL = 1e-12, 1e-14
    truth = friction_model("slip", 1.0, ssegs, 80.0, t, 0.011, 0.015, 5.0, 3e-3, 0.6)
    RTOL, ATOL = 1e-10, 1e-12
    rng = np.random.default_rng(7)
    noisy = truth + 1e-4 * rng.standard_normal(len(t))
    path = os.path.join(tmp, "synthetic.csv")
    with open(path, "w") as fh:
        fh.write("t,mu\n")
        for a, b in zip(t, noisy):
            fh.write(f"{float(a)!r},{float(b)!r}\n")
    cases["synthetic_slip"] = {"law": "slip", "v0": 1.0, "segments": ssegs, "t_end": 80.0, "t": t, "mu": noisy,
                               "params": ["a", "b_1", "d_c_1"],
                               "start": {"a": 0.011 * 1.3, "b_1": 0.015 * 0.8, "d_c_1": 10.0, "k": 3e-3, "mu0": 0.6},
                               "data": path, "columns": "t=t,mu=mu", "truth": {"a": 0.011, "b_1": 0.015, "d_c_1": 5.0}}
    result = {"note": __doc__.strip().splitlines()[0], "command": "python benches/lab_fit_scipy.py --out data/reference/lab/fit_reference.json", "cases": {}}
    print(f"{'case':16} {'param':6} {'scipy':>14} {'± se':>10} {'stickslip':>14} {'± se':>10}  diff/se")
    for name, case in cases.items():
        scene_path = os.path.join(tmp, name + ".json")
        json.dump(scene(case, name), open(scene_path, "w"))
        ours = stickslip_fit(args.stickslip, case, scene_path, case["data"], case["columns"])
        ref = scipy_fit(case)
        for n in case["params"]:
            d = (ours["values"][n] - ref["values"][n]) / ref["standard_errors"][n]
            print(f"{name:16} {n:6} {ref['values'][n]:14.7e} {ref['standard_errors'][n]:10.2e} {ours['values'][n]:14.7e} {ours['standard_errors'][n]:10.2e}  {d:+.1e}")
        print(f"{name:16} time: scipy {ref['seconds']:.2f} s ({ref['evaluations']} evaluations), stickslip {ours['seconds']:.3f} s ({ours['evaluations']} evaluations): {ref['seconds'] / ours['seconds']:.0f}x")
        result["cases"][name] = {"law": case["law"], "params": case["params"], "scipy": ref, "stickslip": ours,
                                 **({"truth": case["truth"]} if "truth" in case else {})}
    if args.out:
        json.dump(result, open(args.out, "w"), indent=1)


if __name__ == "__main__":
    main()
