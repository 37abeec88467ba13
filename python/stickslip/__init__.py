"""stickslip from Python: very stiff stick-slip (rate-and-state friction) dynamics.

- :func:`run`: a scene (dict or JSON file) → its report as a dict, with the keys of
  ``stickslip run --json``.
- :func:`sweep`: a scene over a grid of parameters → one row per point, as ``stickslip sweep``.
- :func:`solve_ivp`: ``scipy.integrate.solve_ivp``'s signature and result over stickslip's
  integrators (SUNDIALS' CVODE and ARKODE, Radau5, Rodas5P, extrapolation).

Exceptions are in :mod:`stickslip.errors`: :class:`SceneError` (``field`` names the bad
field), :class:`RunError`, :class:`SolverError` (``t``, ``y``, ``kind``).
"""

from __future__ import annotations

import importlib.metadata
import json
import os
from typing import Any, Dict, List, Mapping, Optional, Sequence, Union

import numpy as np

from . import _core
from ._ivp import METHODS, SCIPY_METHODS, OdeResult, solve_ivp
from ._solution import OdeSolution
from .errors import RunError, SceneError, SolverError, StickslipError

__all__ = ["run", "sweep", "fit", "solve_ivp", "OdeResult", "OdeSolution", "METHODS", "SCIPY_METHODS",
           "SceneError", "RunError", "SolverError", "StickslipError", "sundials_version"]
# Single-sourced: the workspace version in the root Cargo.toml, which maturin writes into the
# package metadata (pyproject.toml's `dynamic = ["version"]`).
__version__ = importlib.metadata.version("stickslip")

Scene = Union[Mapping[str, Any], str, "os.PathLike[str]"]


def sundials_version() -> str:
    """The version of the SUNDIALS library stickslip runs with (Debian's)."""
    return _core.sundials_version()


def _scene_text(scene: Any) -> tuple:
    """(JSON text, source name) of a scene given as a dict or a path."""
    if isinstance(scene, Mapping):
        return json.dumps(scene), "<dict>"
    if isinstance(scene, (str, os.PathLike)):
        path = os.fspath(scene)
        with open(path, encoding="utf-8") as f:
            return f.read(), path
    raise TypeError(f"`scene` must be a dict or the path of a scene file, got {type(scene).__name__}")


def _arrays(report: Dict[str, Any]) -> Dict[str, Any]:
    """The recorded trajectory's series as numpy arrays (in place)."""
    cycle = report.get("cycle")
    if isinstance(cycle, dict):
        for c in cycle.get("trajectory", []):
            for key in ("t", "u", "v", "theta"):
                if key in c:
                    c[key] = np.asarray(c[key], dtype=float)
    return report


def run(scene: Scene, threads: Optional[int] = None, arrays: bool = True) -> Dict[str, Any]:
    """Run a scene and return its report as a dict with the keys of ``stickslip run --json``.

    ``scene`` is a dict (the JSON scene) or the path of a scene file; ``threads`` the worker
    threads of ensembles (None: every core). With ``arrays`` (default), the trajectory that
    ``{"trajectory": {"cycles": k}}`` records comes back as numpy arrays (``report["cycle"]
    ["trajectory"][i]["t"]``, ``"u"``, ``"v"``, ``"theta"``; t counts from each cycle's upward
    crossing of v = 1, as in the JSON report); ``arrays=False`` leaves every value as the JSON
    report has it.

    A scene with a ``"time_series"`` analysis (a run from t = 0 in absolute time, see
    docs/scenes.md) also gets the one key the JSON report does not have: ``"series"``, its rows
    (those ``stickslip run --series FILE`` writes) as a dict of numpy arrays by column:
    ``report["series"]["t"]`` (absolute time), ``"u"``, ``"v"``, ``"theta"``, ``"ln_v"``,
    ``"slip"``, ``"stress"`` (and the physical columns with ``model.dimensional``). A lab scene
    (``"model": {"kind": "lab"}``, docs/lab.md) gives its columns ``"t"``, ``"x_lp"``,
    ``"delta"``, ``"mu"``, ``"v"``, ``"theta_1"``, … there in place of the report's rows. The GIL is released while the scene runs; Ctrl-C raises KeyboardInterrupt
    at once (the abandoned run finishes in the background and is dropped).

    Raises :class:`SceneError` (a ValueError; ``field`` is the path of the bad field, e.g.
    ``"model.gamma"``) for a scene that does not validate and :class:`RunError` when the run
    fails (``analysis``, ``t``, ``state``, ``kind``).
    """
    text, source = _scene_text(scene)
    report_json, series = _core.run(text, source, threads)
    report = json.loads(report_json)
    if series:
        report["series"] = dict(series)
    return _arrays(report) if arrays else report


def fit(scene: Scene, data: Union[str, os.PathLike], params: Union[str, Sequence[str]],
        columns: Optional[Mapping[str, str]] = None, loading: str = "scene") -> Dict[str, Any]:
    """Fit a lab scene's model to a friction record, as ``stickslip fit`` does (docs/lab.md).

    ``scene`` is a lab scene (dict or path): starting values, tolerances and the load-point
    history in the record's time origin. ``data`` is the record (a header line of column names,
    then rows). ``params`` names what to fit: ``["a", "b_1", "d_c_1", "k", "mu0", "trend"]`` or
    the same comma-separated. ``columns`` maps ``t``, ``mu`` and ``x_lp`` to the record's header
    names, e.g. ``{"t": "Time(s)", "mu": "Friction", "x_lp": "Displ(microns)"}``. ``loading``
    is ``"scene"`` or ``"data"`` (the record's x_lp column).

    Returns the report of ``stickslip fit --json`` as a dict: ``parameters`` (name, value,
    standard_error, initial), ``correlation``, ``residual_rms``, ``evaluations``,
    ``converged``, ``lag1_autocorrelation``, ``warnings``, ``model``; and ``"series"``, numpy
    arrays ``t``, ``x_lp``, ``mu_data`` and ``mu_fit``. Raises :class:`SceneError` for a bad
    scene, ValueError for a bad request, :class:`RunError` when the model cannot be
    integrated.
    """
    text, source = _scene_text(scene)
    names = params if isinstance(params, str) else ",".join(params)
    spec = ",".join(f"{k}={v}" for k, v in (columns or {}).items())
    report_json, series = _core.fit(text, source, os.fspath(data), names, spec, loading)
    report = json.loads(report_json)
    report["series"] = dict(series)
    return report


def sweep(scene: Scene, params: Union[Mapping[str, Any], Sequence[str]],
          threads: Optional[int] = None) -> List[Dict[str, Any]]:
    """Run a scene over a grid of parameters, as ``stickslip sweep``; returns the rows in order.

    ``params`` maps each swept parameter (gamma, xi, epsilon, radiation_damping, alpha) to a
    sequence of values or to ``"START:STOP:COUNT[:log]"``, or is a list of CLI specs
    ``"NAME=START:STOP:COUNT[:log]"``; the first parameter varies slowest. Each row is a dict:
    ``index``, ``params``, ``report`` (the requested report sections) and ``error`` (the
    message that ended the point, or None). ``threads`` > 1 runs points in parallel (None:
    every core). The GIL is released; Ctrl-C raises KeyboardInterrupt and starts no new point.
    """
    text, source = _scene_text(scene)
    if isinstance(params, Mapping):
        axes = []
        for name, values in params.items():
            if not isinstance(values, str):
                values = [float(v) for v in np.atleast_1d(np.asarray(values, dtype=float))]
            axes.append((str(name), values))
    elif isinstance(params, Sequence) and not isinstance(params, str):
        axes = []
        for spec in params:
            if not isinstance(spec, str) or "=" not in spec:
                raise ValueError(f"params: {spec!r} is not NAME=START:STOP:COUNT[:log]")
            name, _, rest = spec.partition("=")
            axes.append((name, rest))
    else:
        raise TypeError("`params` must be a dict {name: values or 'START:STOP:COUNT[:log]'} or a "
                        "list of 'NAME=START:STOP:COUNT[:log]' strings")
    return json.loads(_core.sweep(text, source, axes, threads))
