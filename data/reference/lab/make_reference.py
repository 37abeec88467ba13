"""Independent reference numbers for the lab model (tests/lab_reference.rs).

Run:  /work/venvs/lab/bin/python data/reference/lab/make_reference.py [CASE ...] > data/reference/lab/reference.json
(with CASE names, only those cases; the shipped file was made case by case and joined).
(scipy 1.17.1, numpy; a venv of its own: python3 -m venv /work/venvs/lab && pip install scipy).

Independent of stickslip's formulation: the state here is (mu, ln theta_i) in time t (stickslip
integrates ln V, ln theta_i), V is solved from mu, every segment of constant V_lp is integrated
apart (restart at every jump) with scipy's Radau at rtol 1e-13, and checked against DOP853 /
LSODA at the same tolerance: `spread` is the largest disagreement between the two (abs in mu,
relative in V and theta), the reference's own uncertainty. Friction peaks after a hold are
solve_ivp events (V = V_lp) refined by Brent's method on the dense output; a finite-time blow-up
is integrated on with the slider's slip delta as the independent variable (dt/d delta = 1/V)
until ln V = 600, where the time left is below 1e-200 s.
"""
import json, math, sys
import numpy as np
from scipy.integrate import solve_ivp
from scipy.optimize import brentq

RTOL, ATOL = 1e-13, 1e-14


def lengths(states):
    return [2 * s["d_c"] if s["law"] == "prz" else s["d_c"] for s in states]


def ln_v(p, mu, lth):
    L = lengths(p["states"])
    s = sum(st["b"] * (l + math.log(p["v0"] / Li)) for st, l, Li in zip(p["states"], lth, L))
    return (mu - p["mu0"] - s) / p["a"] + math.log(p["v0"])


def rhs_factory(p, vlp):
    def f(t, z):
        mu, lth = z[0], z[1:]
        lv = ln_v(p, mu, lth)
        V = math.exp(lv)
        dmu = p["k"] * (vlp - V)
        out = [dmu]
        for st, l in zip(p["states"], lth):
            th = math.exp(l)
            dc = st["d_c"]
            if st["law"] == "ageing":
                d = 1 - V * th / dc
            elif st["law"] == "slip":
                d = -(V * th / dc) * math.log(V * th / dc)
            elif st["law"] == "prz":
                d = 1 - (V * th / (2 * dc)) ** 2
            else:
                d = 1 - V * th / dc - st["c"] / st["b"] * th * dmu
            out.append(d / th)
        return out
    return f


def steady(p, v):
    L = lengths(p["states"])
    lth = [math.log(Li / v) for Li in L]
    mu = p["mu0"] + (p["a"] - sum(s["b"] for s in p["states"])) * math.log(v / p["v0"])
    return [mu] + lth


def run(case, method):
    p, segs, t_end = case["params"], case["segments"], case["t_end"]
    times = case["times"]
    z = np.array(steady(p, segs[0]["velocity"]))
    rows, holds, blow = {}, [], None
    mu_end_prev = None
    for j, sg in enumerate(segs):
        t0 = sg["t_start"]
        t1 = segs[j + 1]["t_start"] if j + 1 < len(segs) else t_end
        vlp = sg["velocity"]
        f = rhs_factory(p, vlp)
        events = []
        after_hold = j > 0 and segs[j - 1]["velocity"] == 0 and vlp > 0
        if after_hold:
            ev = lambda t, z: ln_v(p, z[0], z[1:]) - math.log(vlp)
            ev.direction = 1
            events.append(ev)
        blow_ev = lambda t, z: ln_v(p, z[0], z[1:]) - case.get("blow_ln_v", 1e9)
        blow_ev.terminal = True
        blow_ev.direction = 1
        events.append(blow_ev)
        sol = solve_ivp(f, (t0, t1), z, method=method, rtol=RTOL, atol=ATOL,
                        dense_output=True, events=events)
        assert sol.status >= 0, sol.message
        for t in times:
            if t0 <= t <= t1 and (t not in rows or t == t0):
                rows[t] = sol.sol(t)
        if after_hold and len(sol.t_events[0]):
            te = sol.t_events[0][0]
            g = lambda t: ln_v(p, *[sol.sol(t)[0]], sol.sol(t)[1:]) - math.log(vlp)
            lo = max(t0, te - 1e-3 * (t1 - t0))
            te = brentq(g, lo, min(t1, te + 1e-3 * (t1 - t0)), xtol=1e-15, rtol=1e-15) if g(lo) < 0 else te
            holds[-1]["mu_peak"] = float(sol.sol(te)[0])
            holds[-1]["delta_mu_peak"] = holds[-1]["mu_peak"] - holds[-1]["mu_pre_hold"]
        if len(sol.t_events[-1]):
            blow = blow_up(p, vlp, sol.t_events[-1][0], sol.y_events[-1][0])
            break
        z = sol.y[:, -1]
        if vlp == 0:
            holds.append({"t_hold": t1 - t0, "mu_pre_hold": mu_end_prev})
        mu_end_prev = float(z[0])
    out_rows = []
    for t in times:
        if t in rows:
            zt = rows[t]
            out_rows.append([t, float(zt[0]), math.exp(ln_v(p, zt[0], zt[1:]))] + [math.exp(l) for l in zt[1:]])
    res = {"rows": out_rows}
    if holds:
        res["holds"] = holds
        pts = [(math.log10(h["t_hold"]), h["delta_mu_peak"]) for h in holds if "delta_mu_peak" in h]
        x = np.array([q[0] for q in pts]); y = np.array([q[1] for q in pts])
        res["healing_rate"] = float(((x - x.mean()) * (y - y.mean())).sum() / ((x - x.mean()) ** 2).sum())
    if blow is not None:
        res["blow_up_time"] = blow
    return res


def run_inertial(case, method):
    """With inertia M: state (tau, V, theta) in linear variables (tau = k (x_lp - delta), the
    spring's load), M dV/dt = tau - mu(V, theta), dtau/dt = k (V_lp - V); rows (t, tau, V, theta)."""
    p, segs, t_end, times = case["params"], case["segments"], case["t_end"], case["times"]
    st = p["states"][0]
    M, k, a, b, dc = p["mass"], p["k"], p["a"], st["b"], st["d_c"]
    mu = lambda V, th: p["mu0"] + a * math.log(V / p["v0"]) + b * math.log(p["v0"] * th / dc)
    v1 = segs[0]["velocity"]
    z = np.array([mu(v1, dc / v1), v1, dc / v1])
    rows = {}
    for j, sg in enumerate(segs):
        t0 = sg["t_start"]
        t1 = segs[j + 1]["t_start"] if j + 1 < len(segs) else t_end
        vlp = sg["velocity"]
        def f(t, y):
            tau, V, th = y
            if st["law"] == "ageing":
                d = 1 - V * th / dc
            else:
                d = -(V * th / dc) * math.log(V * th / dc)
            return [k * (vlp - V), (tau - mu(V, th)) / M, d]
        sol = solve_ivp(f, (t0, t1), z, method=method, rtol=RTOL, atol=[1e-15, 1e-14 * v1, 1e-14 * dc / v1], dense_output=True)
        assert sol.status >= 0, sol.message
        for t in times:
            if t0 <= t <= t1:
                rows[t] = sol.sol(t)
        z = sol.y[:, -1]
    return {"rows": [[t, float(rows[t][0]), float(rows[t][1]), float(rows[t][2])] for t in times]}


def blow_up(p, vlp, t_e, z_e):
    """Time of V -> infinity: integrate (t, mu, ln theta) in the slip delta."""
    f = rhs_factory(p, vlp)
    def g(d, y):
        V = math.exp(ln_v(p, y[1], y[2:]))
        dz = f(y[0], y[1:])
        return [1 / V] + [x / V for x in dz]
    stop = lambda d, y: ln_v(p, y[1], y[2:]) - 600
    stop.terminal = True
    y0 = np.concatenate([[t_e], z_e])
    sol = solve_ivp(g, (0, 1e6), y0, method="DOP853", rtol=RTOL, atol=1e-300, events=[stop])
    assert sol.status == 1, sol.message
    return float(sol.y_events[0][0][0])


def seg(*pairs):
    return [{"t_start": t, "velocity": v} for t, v in pairs]


def P(a, k, states, mu0=0.6, v0=1.0):
    return {"mu0": mu0, "a": a, "v0": v0, "k": k, "states": states}


def S(law, b, d_c, **kw):
    return dict(law=law, b=b, d_c=d_c, **kw)


def shs(law, k):
    # slide 100 um at 10 um/s, holds 10, 100, 1000 s, each reloaded for 100 um at 10 um/s
    t, out = 0.0, []
    for hold in [10, 100, 1000]:
        out += [(t, 10.0), (t + 10.0, 0.0)]
        t += 10.0 + hold
    out.append((t, 10.0))
    return {"params": P(0.005, k, [S(law, 0.01, 10.0)]), "segments": seg(*out), "t_end": t + 10.0,
            "times": sorted(set([round(x, 6) for x in np.linspace(0, t + 10.0, 24)]))}


ag = lambda: [S("ageing", 0.01, 10.0)]
kc = 0.005 / 10.0  # (b - a)/D_c of a = 0.005, b = 0.01, D_c = 10
CASES = {
    "step_up_ageing": {"params": P(0.005, 1e-3, ag()), "segments": seg((0, 1), (10, 10)), "t_end": 60, "times": list(range(0, 61, 2))},
    "step_down_slip": {"params": P(0.01, 2e-3, [S("slip", 0.015, 10.0)]), "segments": seg((0, 10), (10, 1)), "t_end": 200, "times": list(range(0, 201, 5))},
    "two_states_ageing": {"params": P(0.012, 3e-3, [S("ageing", 0.0185, 5.0), S("ageing", 0.0088, 50.0)]), "segments": seg((0, 1), (10, 10)), "t_end": 100, "times": list(range(0, 101, 4))},
    "stiff_460kc": {"params": P(0.005, 460 * kc, ag()), "segments": seg((0, 1), (10, 10)), "t_end": 40, "times": list(range(0, 41, 1))},
    "soft_1.5kc": {"params": P(0.005, 1.5 * kc, ag()), "segments": seg((0, 1), (10, 10)), "t_end": 300, "times": list(range(0, 301, 10))},
    "soft_0.92kc": {"params": P(0.005, 0.92 * kc, ag()), "segments": seg((0, 1), (10, 1.5)), "t_end": 400, "times": list(range(0, 401, 10))},
    "blow_up_slip": {"params": P(0.005, 0.5 * kc, [S("slip", 0.01, 10.0)]), "segments": seg((0, 1), (10, 10)), "t_end": 100, "times": list(range(0, 11, 1)), "blow_ln_v": 20.0},
    "shs_ageing": shs("ageing", 1e-3),
    # At k = 1e-3 (2 k_c) the slip law's reload after the 100 s hold blows up in finite time
    # (t = 133.76 s): a slide-hold-slide needs a stiffer machine under the slip law.
    "shs_slip": shs("slip", 1e-2),
    "prz_step": {"params": P(0.011, 3e-3, [S("prz", 0.01, 5.0)]), "segments": seg((0, 1), (10, 10)), "t_end": 60, "times": list(range(0, 61, 2))},
    # Inertia M (friction s^2/um): the inertial period 2 pi sqrt(M/k) is 2 s against D_c/V = 1 s.
    "inertia_step_ageing": {"params": dict(P(0.005, 1e-3, ag()), mass=1e-3 / (math.pi ** 2)), "segments": seg((0, 1), (10, 10)), "t_end": 40, "times": list(range(0, 41, 1))},
    "inertia_step_slip": {"params": dict(P(0.005, 1e-3, [S("slip", 0.01, 10.0)]), mass=1e-4), "segments": seg((0, 1), (10, 10)), "t_end": 40, "times": list(range(0, 41, 1))},
    "nagata_step": {"params": P(0.027, 0.01, [S("nagata", 0.029, 3.33, c=2.0)]), "segments": seg((0, 1), (10, 10)), "t_end": 40, "times": list(range(0, 41, 1))},
}


def spread(a, b):
    worst = [0.0, 0.0]
    for ra, rb in zip(a["rows"], b["rows"]):
        worst[0] = max(worst[0], abs(ra[1] - rb[1]))
        worst[1] = max(worst[1], max(abs(x / y - 1) for x, y in zip(ra[2:], rb[2:])))
    return worst


out = {"note": __doc__.strip().splitlines()[0], "command": "/work/venvs/lab/bin/python data/reference/lab/make_reference.py > data/reference/lab/reference.json",
       "rtol": RTOL, "cases": {}}
only = sys.argv[1:]
for name, case in CASES.items():
    if only and name not in only:
        continue
    # The first two of these methods that finish: the first is the reference, the second its check.
    done = []
    runner = run_inertial if "mass" in case["params"] else run
    for method in ["Radau", "LSODA" if name.startswith(("stiff", "shs", "blow")) else "DOP853", "LSODA", "DOP853"]:
        if len(done) < 2 and method not in [m for m, _ in done]:
            try:
                done.append((method, runner(case, method)))
            except (AssertionError, ValueError) as e:
                print(name, method, "failed:", e, file=sys.stderr)
    (m_ref, ref), (m_other, other) = done
    sp = spread(ref, other)
    extra = {}
    if "holds" in ref:
        extra["delta_mu_peak_spread"] = max(abs(h1["delta_mu_peak"] - h2["delta_mu_peak"]) for h1, h2 in zip(ref["holds"], other["holds"]))
        extra["healing_rate_spread"] = abs(ref["healing_rate"] - other["healing_rate"])
    if "blow_up_time" in ref:
        extra["blow_up_time_spread"] = abs(ref["blow_up_time"] - other.get("blow_up_time", float("nan")))
    c = {k: v for k, v in case.items() if k != "blow_ln_v"}
    c.update(ref)
    c["methods"] = [m_ref, m_other]
    c["spread"] = {"mu_abs": sp[0], "v_theta_rel": sp[1], **extra}
    out["cases"][name] = c
    print(name, c["spread"], c.get("blow_up_time"), c.get("healing_rate"), file=sys.stderr)
json.dump(out, sys.stdout, indent=1)
