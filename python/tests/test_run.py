"""stickslip.run and stickslip.sweep against the CLI, and their exceptions."""

import json
import os
import signal
import subprocess
import sys
import threading
import time

import numpy as np
import pytest

import stickslip
from problems import REPO

# The CLI that tools/test.sh built (CARGO_TARGET_DIR as cargo reads it: relative to the repo).
CLI = os.path.join(REPO, os.environ.get("CARGO_TARGET_DIR", "target"), "release", "stickslip")
# The shipped scenes that run in under a second (the others are ensembles or long scans).
FAST_SCENES = ["earthquake", "earthquake-ageing", "earthquake-ageing-damped", "fig1", "ice-stream",
               "period-doubling", "power-law", "power-law-lyapunov", "prz", "quasi-dynamic"]


def scene_path(name):
    return os.path.join(REPO, "data", "scenes", name + ".json")


def cli(*args):
    out = subprocess.run([CLI, *args], capture_output=True, text=True, check=True)
    return out.stdout


def without_wall_time(value):
    if isinstance(value, dict):
        return {k: without_wall_time(v) for k, v in value.items() if k != "wall_time_s"}
    if isinstance(value, list):
        return [without_wall_time(v) for v in value]
    return value


@pytest.mark.parametrize("name", FAST_SCENES)
def test_run_equals_the_cli_report(name):
    expected = json.loads(cli("run", scene_path(name), "--json"))
    got = stickslip.run(scene_path(name), arrays=False)
    assert without_wall_time(got) == without_wall_time(expected)
    assert list(got) == list(expected)


def test_lab_scene_gives_its_columns_as_arrays():
    expected = json.loads(cli("run", scene_path("lab-velocity-step"), "--json"))
    got = stickslip.run(scene_path("lab-velocity-step"))
    assert got["velocity_steps"] == expected["velocity_steps"]
    assert got["v_maxima"] == expected["v_maxima"]
    rows = np.array(expected["series"]["rows"])
    assert list(got["series"]) == expected["series"]["columns"] == ["t", "x_lp", "delta", "mu", "v", "theta_1"]
    for i, column in enumerate(expected["series"]["columns"]):
        np.testing.assert_array_equal(got["series"][column], rows[:, i])


def test_run_from_a_dict_and_arrays():
    with open(scene_path("fig1")) as f:
        scene = json.load(f)
    report = stickslip.run(scene)
    assert report["scene"] == scene
    trajectory = report["cycle"]["trajectory"][0]
    assert isinstance(trajectory["t"], np.ndarray) and trajectory["t"].shape == trajectory["v"].shape
    expected = json.loads(cli("run", scene_path("fig1"), "--json"))
    assert report["cycle"]["period"] == expected["cycle"]["period"]
    np.testing.assert_array_equal(trajectory["u"], expected["cycle"]["trajectory"][0]["u"])


def test_earthquake_period_prints_exactly_the_cli_period():
    code = ("import stickslip; print(stickslip.run('data/scenes/earthquake.json')"
            "['cycle']['period'])")
    printed = subprocess.run([sys.executable, "-c", code], cwd=REPO, capture_output=True,
                             text=True, check=True).stdout.strip()
    expected = json.loads(cli("run", scene_path("earthquake"), "--json"))["cycle"]["period"]
    assert printed == repr(expected)


def test_scene_errors_name_the_field():
    with open(scene_path("fig1")) as f:
        scene = json.load(f)
    scene["model"]["gamma"] = -1
    with pytest.raises(stickslip.SceneError, match="model.gamma") as info:
        stickslip.run(scene)
    assert info.value.field == "model.gamma" and isinstance(info.value, ValueError)
    scene["model"]["gamma"] = 1e3
    scene["solver"]["rtol"] = "tight"
    with pytest.raises(stickslip.SceneError) as info:
        stickslip.run(scene)
    assert info.value.field == "solver.rtol"
    with pytest.raises(FileNotFoundError):
        stickslip.run("no/such/scene.json")
    with pytest.raises(TypeError):
        stickslip.run(42)
    with pytest.raises(ValueError, match="threads"):
        stickslip.run(scene_path("fig1"), threads=0)


def test_run_error_carries_t_state_and_kind():
    scene = {"name": "t", "model": {"gamma": 1e5, "xi": 0.8, "epsilon": 1},
             "solver": {"method": "arkode-erk"}, "analyses": [{"cycle": {"max_steps": 20000}}]}
    with pytest.raises(stickslip.RunError) as info:
        stickslip.run(scene)
    e = info.value
    assert e.analysis == "cycle" and e.t is not None and e.state.shape == (3,)
    assert e.kind == "TooMuchWork" and not e.bad_input
    assert "at t =" in str(e)


def interrupted_after(seconds, work):
    """Runs work(), sending SIGINT after `seconds`; asserts KeyboardInterrupt within a second
    of the signal, then that the work has stopped: no CPU used by the process over 0.5 s (a
    run going on in the background would use about 0.5 s of it)."""
    timer = threading.Timer(seconds, os.kill, (os.getpid(), signal.SIGINT))
    start = time.monotonic()
    timer.start()
    with pytest.raises(KeyboardInterrupt):
        work()
    assert time.monotonic() - start < seconds + 1.0
    cpu = time.process_time()
    time.sleep(0.5)
    assert time.process_time() - cpu < 0.05


def test_ctrl_c_stops_a_long_run():
    """SIGINT during a 3.5 s scene (shooting, then a continuation of 51 points)."""
    interrupted_after(0.3, lambda: stickslip.run(scene_path("fig1b")))


def test_ctrl_c_stops_a_sweep_inside_its_points():
    """SIGINT during a sweep whose points take about 3.5 s each, on two threads."""
    with open(scene_path("fig1b")) as f:
        scene = json.load(f)
    interrupted_after(0.3, lambda: stickslip.sweep(scene, {"xi": [0.7, 0.71]}, threads=2))


SWEEP_SCENE = {"name": "sweep", "model": {"gamma": 1e3, "xi": 0.7, "epsilon": 0.72},
               "solver": {"method": "cvode-bdf", "rtol": 1e-8, "atol": 1e-10},
               "analyses": ["hopf", "cycle"]}


def test_sweep_rows_equal_the_cli_and_threads(tmp_path):
    scene = tmp_path / "scene.json"
    scene.write_text(json.dumps(SWEEP_SCENE))
    out = tmp_path / "rows.jsonl"
    cli("sweep", str(scene), "--param", "epsilon=0.6:0.9:4", "--param", "xi=0.5:0.7:2",
        "--out", str(out), "--threads", "2")
    expected = sorted((json.loads(l) for l in out.read_text().splitlines()), key=lambda r: r["index"])
    one = stickslip.sweep(str(scene), {"epsilon": "0.6:0.9:4", "xi": [0.5, 0.7]}, threads=1)
    two = stickslip.sweep(SWEEP_SCENE, ["epsilon=0.6:0.9:4", "xi=0.5:0.7:2"], threads=2)
    assert one == two == expected
    assert [r["index"] for r in one] == list(range(8))


def test_sweep_errors():
    with pytest.raises(ValueError, match="unknown parameter"):
        stickslip.sweep(SWEEP_SCENE, {"mass": [1.0]})
    with pytest.raises(ValueError, match="START:STOP:COUNT"):
        stickslip.sweep(SWEEP_SCENE, {"xi": "0.5:0.7"})
    with pytest.raises(ValueError):
        stickslip.sweep(SWEEP_SCENE, {"xi": ["a"]})
    with pytest.raises(TypeError):
        stickslip.sweep(SWEEP_SCENE, 3)
    bad = dict(SWEEP_SCENE, model={"gamma": -1, "xi": 0.7, "epsilon": 0.72})
    with pytest.raises(stickslip.SceneError, match="model.gamma"):
        stickslip.sweep(bad, {"xi": [0.5]})


SERIES_SCENE = {"name": "series", "model": {"gamma": 1e3, "xi": 0.7, "epsilon": 0.72},
                "solver": {"method": "cvode-bdf", "rtol": 1e-10, "atol": 1e-12},
                "analyses": [{"time_series": {"t_max": 40, "points": 401}}]}


def test_time_series_as_arrays_with_absolute_time(tmp_path):
    """The "time_series" rows come back as numpy arrays, the same doubles as the CLI's
    --series file, and agree with solve_ivp on the same model written in Python."""
    import problems
    from stickslip import solve_ivp

    report = stickslip.run(SERIES_SCENE)
    series = report["series"]
    assert list(series)[:4] == ["t", "u", "v", "theta"]
    np.testing.assert_array_equal(series["t"], np.arange(401) * 40.0 / 400)  # t_i = i·t_max/(N − 1)
    scene = tmp_path / "series.json"
    scene.write_text(json.dumps(SERIES_SCENE))
    csv = tmp_path / "series.csv"
    cli("run", str(scene), "--series", str(csv))
    rows = np.genfromtxt(csv, delimiter=",", names=True)
    for name in series:
        np.testing.assert_array_equal(series[name], rows[name])
    own = solve_ivp(problems.slider, (0, 40), problems.SLIDER_Y0, method="Radau", rtol=1e-10,
                    atol=1e-12, jac=problems.slider_jac, t_eval=series["t"])
    # CVODE's BDF (the scene) against Radau5 (solve_ivp), both at rtol 1e-10: 1.3e-6 apart at
    # most, BDF's global error on this orbit (test_solve_ivp's spring-slider: 1.0e-6).
    for k, name in enumerate(["u", "ln_v", "theta"]):
        assert np.abs(own.y[k] - series[name]).max() < 1e-5, name
    assert "series" not in stickslip.run(scene_path("fig1"))


def test_the_version_is_the_workspace_version():
    # One source: [workspace.package] in the root Cargo.toml, through python/Cargo.toml and
    # maturin into the installed metadata that stickslip.__version__ reads.
    import tomllib

    with open(os.path.join(REPO, "Cargo.toml"), "rb") as f:
        version = tomllib.load(f)["workspace"]["package"]["version"]
    assert stickslip.__version__ == version


def test_fit_equals_the_cli_report():
    scene = scene_path("lab-basalt-b819")
    data = os.path.join(REPO, "data", "lab", "velstep4_BRAVA_expb819_basalt.txt")
    columns = {"t": "Time(s)", "x_lp": "Displ(microns)", "mu": "Friction"}
    expected = json.loads(cli("fit", scene, "--data", data, "--params", "a,b_1,d_c_1,k,mu0,trend",
                              "--columns", ",".join(f"{k}={v}" for k, v in columns.items()), "--json"))
    got = stickslip.fit(scene, data, ["a", "b_1", "d_c_1", "k", "mu0", "trend"], columns=columns)
    assert got["parameters"] == expected["parameters"]
    assert got["correlation"] == expected["correlation"]
    series = got["series"]
    assert series["t"].shape == series["mu_fit"].shape == (5849,)
    residual = series["mu_data"] - series["mu_fit"]
    assert abs(np.sqrt(np.mean(residual ** 2)) - got["residual_rms"]) < 1e-12
    with pytest.raises(ValueError, match="choose from"):
        stickslip.fit(scene, data, "a,alpha", columns=columns)
