"""QDYN's first events under periodic loading, for data/reference/qdyn_periodic.json. Usage:
    python periodic_reference.py QDYN_BINARY OUT.json data/qdyn/classic_slip_per03.in ...
Runs QDYN (github ydluo/qdyn at e06edb1, SOLVER = 2, as the files say) on each input file as
it is, in a temporary folder, and keeps the first 20 events of its output_ot_0 (written at
every step, NTOUT_OT = 1): each event is a local maximum of V above 100 V_pl, refined by the
parabola in ln V through the three samples around it (peak time and v_max). QDYN prints its
columns in e15.7 (V to 7 digits: a rounding of up to 5e-7 relative, more than the parabola's
correction near the peak); the reference runs used a QDYN built with its output format
(output.f90, pb%ot%fmt) changed to e25.16, so that the printed samples are QDYN's doubles."""
import json, os, shutil, subprocess, sys, tempfile
import numpy as np

EVENTS = 20
binary, out, files = os.path.abspath(sys.argv[1]), sys.argv[2], sys.argv[3:]
cases = []
for path in files:
    with tempfile.TemporaryDirectory() as d:
        shutil.copy(path, os.path.join(d, "qdyn.in"))
        subprocess.run([binary], cwd=d, stdout=subprocess.DEVNULL, check=False)
        ot = np.loadtxt(os.path.join(d, "output_ot_0"), comments="#")
    t, v = ot[:, 0], ot[:, 3]
    events = []
    for i in range(1, len(v) - 1):
        if v[i] > 1e-7 and v[i] >= v[i - 1] and v[i] > v[i + 1]:
            tt, yy = t[i - 1:i + 2], np.log(v[i - 1:i + 2])
            c = np.polyfit(tt - tt[1], yy, 2)
            dt = -c[1] / (2 * c[0])
            events.append({"t_peak_s": float(tt[1] + dt),
                           "v_max_m_per_s": float(np.exp(np.polyval(c, dt))),
                           "v_max_sample_m_per_s": float(v[i])})
            if len(events) == EVENTS:
                break
    cases.append({"file": os.path.relpath(path), "samples": len(t), "events": events})
    print(path, len(t), "samples", len(events), "events")
description = (
    "QDYN's spring-block under periodic loading (APER = 40 kPa, TPER = 0.3 and 3 times the "
    "unforced period of classic_slip, 4779201.059348583 s), run by QDYN itself (github "
    "ydluo/qdyn at e06edb1, mpif90 -O3, serial; output format e25.16 instead of e15.7) on the "
    "input files named, as written by pyqdyn (data/qdyn/make_fixtures.py): SOLVER = 2 (RK45), "
    "ACC = 1e-11, output at every step. Events: the first 20 local maxima of V above 100 V_pl, "
    "each refined by the parabola in ln V through the three samples around it (t_peak_s, "
    "v_max_m_per_s); v_max_sample_m_per_s is the largest sample itself.")
command = "python data/qdyn/periodic_reference.py QDYN_BINARY " + " ".join([out] + files)
json.dump({"description": description, "command": command, "cases": cases},
          open(out, "w"), indent=1)
