"""Writes the QDYN input files of this folder with QDYN's own writer, pyqdyn's write_input
(QDYN's src/pyqdyn.py, github ydluo/qdyn at e06edb1; it needs pandas < 3). Usage:
    PYTHONPATH=/path/to/qdyn/src python make_fixtures.py OUTDIR
The spring-block of data/reference/qdyn_spring_block.json: sigma 1e7 Pa, a 0.01, b 0.015,
Dc 1e-4 m, V_pl 1e-9 m/s, L 120 m (k = MU/L = 2.5e8 Pa/m), MU 3e10 Pa, VS 3e3 m/s, MU_SS 0.6,
V_SS 1e-6 m/s, V_0 5e-10 m/s, TH_0 1e5 s, ACC 1e-11, TMAX 40 periods (QDYN's reference runs
were made from these very files); the no-healing case runs to TMAX = 1e6 s; and classic_slip
under periodic loading (FORCED below)."""
import os, sys
from pyqdyn import qdyn

CASES = {  # name: RNS_LAW, THETA_LAW, V1, V2, TMAX (s)
    "classic_ageing": (0, 1, 0.01, 1e-7, 208334765.05483),
    "classic_slip": (0, 2, 0.01, 1e-7, 191168042.37512),
    "cut_a_ageing": (1, 1, 1e-6, 1e-7, 86428778.2444523),
    "cut_a_slip": (1, 2, 1e-6, 1e-7, 81578186.8239715),
    "cut_b_ageing": (1, 1, 1e-2, 1e-2, 199946581.640314),
    "cut_b_slip": (1, 2, 1e-2, 1e-2, 183565245.635459),
    "reg_ageing": (2, 1, 0.01, 1e-7, 208334765.054716),
    "reg_slip": (2, 2, 0.01, 1e-7, 191168042.375346),
    # No healing (THETA_LAW = 0): no cycle; V reaches 1 m/s at t = 1.35e5 s, QDYN's solver
    # stops soon after (data/reference/qdyn_no_healing.json).
    "classic_no_healing": (0, 0, 0.01, 1e-7, 1e6),
}
# Periodic loading (APER = 40 kPa) of classic_slip, whose unforced period is
# P = 4779201.059348583 s (data/reference/qdyn_spring_block.json): TPER = 0.3 P and 3 P,
# TMAX = 30 P. name: TPER (s), APER (Pa), TMAX (s).
FORCED = {
    "classic_slip_per03": (1433760.317804575, 4e4, 143376031.7804575),
    "classic_slip_per3": (14337603.17804575, 4e4, 143376031.7804575),
}

out = os.path.abspath(sys.argv[1])
runs = {name: case + (0.0, 31536000.0) for name, case in CASES.items()}
for name, (tper, aper, tmax) in FORCED.items():
    runs[name] = CASES["classic_slip"][:4] + (tmax, aper, tper)
for name, (rns, law, v1, v2, tmax, aper, tper) in runs.items():
    p = qdyn()
    p.settings({
        "MESHDIM": 0, "V_PL": 1e-9, "L": 120.0, "SIGMA": 1e7, "VS": 3e3, "MU": 3e10,
        "TMAX": tmax, "ACC": 1e-11, "NTOUT_OT": 1, "NTOUT": 1000000, "SOLVER": 2,
        "APER": aper, "TPER": tper,
        "SET_DICT_RSF": {"RNS_LAW": rns, "THETA_LAW": law, "A": 0.01, "B": 0.015, "DC": 1e-4,
                         "V1": v1, "V2": v2, "MU_SS": 0.6, "V_SS": 1e-6, "V_0": 5e-10,
                         "TH_0": 1e5},
    })
    p.render_mesh()
    os.chdir(out)
    p.write_input()
    os.rename("qdyn.in", f"{name}.in")
