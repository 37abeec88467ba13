"""``stickslip.solve_ivp``: scipy's ``solve_ivp`` over stickslip's integrators."""

from __future__ import annotations

import numbers
import warnings
from typing import Any, Callable, Optional, Sequence, Union

import numpy as np

from . import _core
from ._solution import OdeSolution
from .errors import SolverError

#: stickslip's own methods, read from the Rust method table (``stickslip::solver::Method``).
METHODS = tuple(_core.METHODS)

#: scipy's method names and what they run here: (stickslip method, ARKODE Butcher table,
#: radau5's reading of the tolerances). Radau reads rtol and atol as scipy's Radau does (as
#: given); stickslip's own "radau5" keeps RADAU5's transform rtol' = 0.1·rtol^(2/3).
#: RK45 and RK23 are the same Dormand–Prince 5(4) and Bogacki–Shampine 3(2) pairs as scipy's
#: (through ARKODE's adaptivity, not scipy's); DOP853 becomes Fehlberg's 13-stage 8(7) pair,
#: the ARKODE table of the same order (DOP853's own pair is not in ARKODE).
SCIPY_METHODS = {
    "Radau": ("radau5", None, "as_given"),
    "BDF": ("cvode-bdf", None, None),
    "RK45": ("arkode-erk", "DORMAND_PRINCE_7_4_5", None),
    "RK23": ("arkode-erk", "BOGACKI_SHAMPINE_4_2_3", None),
    "DOP853": ("arkode-erk", "FEHLBERG_13_7_8", None),
}

#: The options stickslip's methods take (scipy's names first); others warn, as in scipy.
OPTIONS = ("first_step", "max_step", "min_step", "max_steps", "max_order", "jacobian_max_age",
           "table", "raise_on_failure")

#: The methods without a Jacobian (those run by an explicit Butcher table, from the Rust method
#: table): a ``jac`` given to them warns, as scipy's explicit methods do. Every other method takes
#: the analytic ``jac`` or differences ``fun``.
EXPLICIT = tuple(_core.EXPLICIT_METHODS)

_EPS = np.finfo(float).eps

_MESSAGES = {
    0: "The solver successfully reached the end of the integration interval.",
    1: "A termination event occurred.",
}


class OdeResult(dict):
    """The result of :func:`solve_ivp`, a dict whose keys are also attributes (as scipy's).

    Fields: ``t`` (times, shape (n_points,)), ``y`` (values, shape (n, n_points)), ``sol``
    (:class:`OdeSolution` or None), ``t_events`` and ``y_events`` (per event, the times and
    states of its zeros; None without events), ``nfev`` (calls of ``fun``), ``njev`` (calls
    of ``jac``, or Jacobians by differences), ``nlu`` (matrix factorisations), ``status``
    (-1 failure, 0 end reached, 1 terminal event), ``message``, ``success`` (status ≥ 0).
    """

    def __getattr__(self, name: str) -> Any:
        try:
            return self[name]
        except KeyError as e:
            raise AttributeError(name) from e

    __setattr__ = dict.__setitem__  # type: ignore[assignment]
    __delattr__ = dict.__delitem__  # type: ignore[assignment]

    def __repr__(self) -> str:
        width = max(map(len, self.keys())) + 1 if self else 0
        return "\n".join(f"{k.rjust(width)}: {v!r}" for k, v in self.items())


def resolve_method(method: Any) -> tuple:
    """(stickslip method, Butcher table or None, tolerance reading or None) for a stickslip or
    scipy method name."""
    if not isinstance(method, str):
        raise ValueError(f"`method` must be one of {list(METHODS)} or of scipy's names "
                         f"{list(SCIPY_METHODS)}; stickslip takes no OdeSolver class, got {method!r}")
    if method in METHODS:
        return method, None, None
    if method in SCIPY_METHODS:
        return SCIPY_METHODS[method]
    if method == "LSODA":
        raise ValueError("method 'LSODA' (automatic stiff/non-stiff switching) has no counterpart "
                         "in stickslip: use 'BDF' (cvode-bdf) or 'Radau' (radau5), or 'rodas5p', "
                         "for stiff problems, and 'cvode-adams' or 'RK45' (arkode-erk) for "
                         f"non-stiff ones; all methods: {list(METHODS) + list(SCIPY_METHODS)}")
    raise ValueError(f"`method` {method!r} is not a method; use one of {list(METHODS)} or "
                     f"scipy's {list(SCIPY_METHODS)}")


def _events(events: Any, args: Optional[tuple]) -> list:
    if callable(events):
        events = (events,)
    try:
        events = list(events)
    except TypeError as e:
        raise TypeError(f"`events` must be a callable or a sequence of callables, got {events!r}") from e
    prepared = []
    for event in events:
        if not callable(event):
            raise TypeError(f"each event must be callable as event(t, y), got {event!r}")
        terminal = getattr(event, "terminal", None)
        direction = getattr(event, "direction", 0)
        if terminal is None or terminal is False:
            max_events = np.inf
        elif terminal is True:
            max_events = 1.0
        elif isinstance(terminal, numbers.Integral) and not isinstance(terminal, bool) and terminal > 0:
            max_events = float(terminal)
        else:
            raise ValueError("The `terminal` attribute of each event must be a boolean or positive integer.")
        try:
            direction = float(direction)
        except (TypeError, ValueError) as e:
            raise ValueError(f"The `direction` attribute of an event must be a number, got {direction!r}") from e
        if args is not None:
            event = (lambda t, x, event=event: event(t, x, *args))
        prepared.append((event, float(np.sign(direction)), max_events))
    return prepared


def solve_ivp(fun: Callable, t_span: Sequence[float], y0: Any, method: str = "RK45",
              t_eval: Any = None, dense_output: bool = False, events: Any = None,
              vectorized: bool = False, args: Optional[tuple] = None, rtol: float = 1e-3,
              atol: Union[float, Sequence[float]] = 1e-6, jac: Any = None,
              **options: Any) -> OdeResult:
    """Solve an initial value problem, as ``scipy.integrate.solve_ivp``, with stickslip's methods.

    Same signature, arguments, result fields and event rules as scipy's: ``fun(t, y, *args)``
    returns dy/dt (shape (n,)); ``jac`` is a callable ``jac(t, y, *args)``, an (n, n) array or
    None (differences); ``events`` are callables ``event(t, y, *args)`` with optional
    ``terminal`` (bool, or a positive int: stop at that occurrence) and ``direction``
    attributes; ``t_eval`` picks output times, ``dense_output`` gives ``sol``.

    ``method``: stickslip's own methods by name (``"cvode-bdf"``, ``"cvode-adams"``,
    ``"arkode-dirk"``, ``"arkode-erk"``, ``"radau5"``, ``"rodas5p"``, ``"extrapolation"``;
    ``"arkode-imex"`` needs a split system and is refused here) or scipy's names mapped to
    them: ``"Radau"`` → radau5 with rtol and atol as given (scipy's meaning; ``"radau5"``
    applies RADAU5's transform, see below), ``"BDF"`` → cvode-bdf,
    ``"RK45"``/``"RK23"``/``"DOP853"`` → arkode-erk with the Dormand–Prince 5(4),
    Bogacki–Shampine 3(2) and Fehlberg 8(7) tables.
    ``"LSODA"`` has no counterpart and raises ValueError naming the alternatives.

    ``options``: ``first_step``, ``max_step``, ``min_step`` (scipy's names), and stickslip's
    ``max_steps`` (internal steps of the whole integration, default no limit), ``max_order``
    (cvode, extrapolation), ``jacobian_max_age``, ``table`` (an ARKODE Butcher table name) and
    ``raise_on_failure``. An option a method does not have is a ValueError; an unknown option
    warns, as in scipy.

    A failed integration returns ``status`` -1, ``success`` False and the integrator's
    ``message`` (where, when and why), with ``t`` and ``y`` up to the last accepted step, as
    scipy does. ``raise_on_failure=True`` (stickslip's keyword) raises
    :class:`stickslip.SolverError` instead (``t``, ``y``, ``kind``, ``solver`` and the partial
    ``result``).

    A complex ``y0`` is integrated as the real system of twice the size (real parts, then
    imaginary parts); ``fun`` gets and returns complex arrays, ``jac`` returns the complex
    derivative df/dy (f holomorphic in y, as scipy's BDF also assumes), and
    ``y``, ``sol`` and ``y_events`` are complex. A ``jac`` with a method that has no Jacobian
    (``RK45``, ``RK23``, ``DOP853``, ``"arkode-erk"``) warns, as in scipy, and is not used.
    Every method takes a complex ``y0`` (scipy's Radau and LSODA refuse one).

    Differences that remain from scipy:

    - ``Radau`` is RADAU5's Radau IIA (Hairer & Wanner) with rtol and atol as given, as scipy
      reads them, and its Newton iteration stops no earlier than the second iteration, as
      scipy's; its step-size control and Jacobian reuse are RADAU5's, not scipy's port of
      them, so the same (rtol, atol) gives a different, not a systematically better or worse,
      error (docs/python.md measures both: within about ±0.6 digits of scipy's, and on HIRES
      and van der Pol sometimes more than 0.1 digit below it). ``"radau5"`` is the same method with
      RADAU5's own tolerance transform rtol' = 0.1·rtol^(2/3), atol' = atol·rtol'/rtol, as the
      scenes run it: about CVODE's accuracy for an rtol, fewer digits than scipy's ``Radau``.
    - ``BDF`` is CVODE's variable-order BDF, not scipy's NDF; ``RK45``/``RK23`` are scipy's
      Runge–Kutta pairs with ARKODE's step control; ``DOP853`` is Fehlberg's 8(7) pair;
      ``LSODA`` is refused (ValueError naming the alternatives).
    - A complex system's error is weighed per real and imaginary part (scipy weighs |z|), and
      one ``atol`` per complex component applies to both its parts.
    - ``rtol`` is a scalar; ``jac_sparsity``, ``lband`` and ``uband`` are not options (they
      warn and are ignored: the Jacobian is dense).
    - An exception raised in ``fun``, ``jac`` or an event propagates unchanged; ``nfev``
      counts the calls of ``fun`` (Jacobians by differences included), ``njev`` the calls of
      ``jac`` (or the Jacobians by differences), ``nlu`` the integrator's linear-solver
      setups (Radau5 factors a real and a complex matrix per setup, counted once).
    - ``sol`` interpolates each step's own dense output (the method's interpolant), and
      events are located on it by Brent's method as in scipy.
    - A failure's ``message`` is the integrator's (e.g. "radau5 failed at t = … : step
      underflow …"), not scipy's wording, and a step underflow is RADAU5's or SUNDIALS'
      test, not scipy's "step size less than spacing between numbers".
    """
    stick_method, table, tolerances = resolve_method(method)
    table = options.pop("table", table)
    raise_on_failure = bool(options.pop("raise_on_failure", False))
    unknown = sorted(set(options) - set(OPTIONS))
    if unknown:
        warnings.warn("The following arguments have no effect for a chosen solver: "
                      + ", ".join(f"`{k}`" for k in unknown) + ".", UserWarning, stacklevel=2)
        for k in unknown:
            options.pop(k)
    if not callable(fun):
        raise TypeError(f"`fun` must be callable as fun(t, y), got {fun!r}")
    t0, tf = map(float, t_span)
    if not (np.isfinite(t0) and np.isfinite(tf)):
        raise ValueError("`t_span` must hold two finite numbers.")
    if args is not None:
        try:
            _ = [*(args)]
        except TypeError as exp:
            raise TypeError("Supplied 'args' cannot be unpacked. Please supply `args` as a tuple "
                            "(e.g. `args=(arg,)`)") from exp
        args = tuple(args)
        user_fun = fun
        fun = (lambda t, x, fun=user_fun: fun(t, x, *args))
        if callable(jac):
            user_jac = jac
            jac = (lambda t, x, jac=user_jac: jac(t, x, *args))
    if jac is not None and stick_method in EXPLICIT:
        warnings.warn("The following arguments have no effect for a chosen solver: `jac`.",
                      UserWarning, stacklevel=2)
        jac = None
    if vectorized:
        vec_fun = fun
        fun = (lambda t, y, fun=vec_fun: np.asarray(fun(t, y[:, None])).ravel())
    y0 = np.asarray(y0)
    is_complex = np.issubdtype(y0.dtype, np.complexfloating)
    if y0.ndim != 1:
        raise ValueError("`y0` must be 1-dimensional.")
    if not np.isfinite(y0).all():
        raise ValueError("All components of the initial state `y0` must be finite.")
    n = y0.size
    if is_complex:
        fun, jac, events = _as_real(fun, jac, events, n)
        y0 = np.concatenate([y0.real, y0.imag])
    y0 = y0.astype(float, copy=False)
    rtol_a = np.asarray(rtol, dtype=float)
    if rtol_a.ndim != 0:
        raise ValueError("`rtol` must be a scalar in stickslip (one relative tolerance for every component).")
    rtol = float(rtol_a)
    if not np.isfinite(rtol) or rtol <= 0:
        raise ValueError("`rtol` must be a finite positive number.")
    if rtol < 100 * _EPS:
        warnings.warn(f"At least one element of `rtol` is too small. Setting `rtol = max(rtol, {100 * _EPS})`.",
                      stacklevel=2)
        rtol = 100 * _EPS
    atol_a = np.asarray(atol, dtype=float)
    if atol_a.ndim > 0 and atol_a.shape != (n,):
        raise ValueError("`atol` has wrong shape.")
    if np.any(atol_a < 0):
        raise ValueError("`atol` must be positive.")
    if not np.all(np.isfinite(atol_a)):
        raise ValueError("`atol` must be finite.")
    if is_complex and atol_a.ndim > 0:
        atol_a = np.concatenate([atol_a, atol_a])
    first_step = options.get("first_step")
    if first_step is not None:
        if first_step <= 0:
            raise ValueError("`first_step` must be positive.")
        if first_step > abs(tf - t0):
            raise ValueError("`first_step` exceeds bounds.")
    max_step = options.get("max_step")
    if max_step is not None:
        if max_step <= 0:
            raise ValueError("`max_step` must be positive.")
        if np.isinf(max_step):
            options["max_step"] = None
    if t_eval is not None:
        t_eval = np.asarray(t_eval, dtype=float)
        if t_eval.ndim != 1:
            raise ValueError("`t_eval` must be 1-dimensional.")
        if np.any(t_eval < min(t0, tf)) or np.any(t_eval > max(t0, tf)):
            raise ValueError("Values in `t_eval` are not within `t_span`.")
        d = np.diff(t_eval)
        if tf > t0 and np.any(d <= 0) or tf < t0 and np.any(d >= 0):
            raise ValueError("Values in `t_eval` are not properly sorted.")
        t_eval = [float(s) for s in t_eval]
    if jac is not None and not callable(jac):
        if hasattr(jac, "toarray"):
            jac = jac.toarray()
        jac = np.asarray(jac, dtype=float)
    prepared = _events(events, args) if events is not None else []
    raw = _core.solve_ivp(fun, jac, stick_method, table, tolerances, t0, tf,
                          [float(v) for v in y0], rtol, [float(a) for a in np.atleast_1d(atol_a)],
                          t_eval, bool(dense_output), prepared, options)
    status = raw["status"]
    error = raw["error"]
    complex_ = _to_complex if is_complex else (lambda y: y)
    sol = (OdeSolution(raw["sol_ts"], raw["sol_spans"], raw["sol_values"], complex_=is_complex)
           if dense_output else None)
    result = OdeResult(
        t=raw["t"], y=complex_(raw["y"]), sol=sol,
        t_events=raw["t_events"] if events is not None else None,
        # scipy's y_events[i] is np.asarray of a list: shape (k, n), or (0,) without zeros.
        y_events=[complex_(ye.T).T if len(ye) else np.empty((0,)) for ye in raw["y_events"]]
        if events is not None else None,
        nfev=raw["nfev"], njev=raw["njev"], nlu=raw["nlu"], status=status,
        message=error["message"] if error else _MESSAGES[status], success=status >= 0)
    if error and raise_on_failure:
        y_err = error["y"]
        raise SolverError(error["message"], t=error["t"],
                          y=_to_complex(y_err) if is_complex and len(y_err) else y_err,
                          kind=error["kind"], solver=error["solver"], flag=error["flag"],
                          result=result)
    return result


def _to_complex(y: np.ndarray) -> np.ndarray:
    """The complex states of real ones stacked as (real parts, imaginary parts) on axis 0."""
    m = y.shape[0] // 2
    return y[:m] + 1j * y[m:]


def _as_real(fun: Callable, jac: Any, events: Any, n: int) -> tuple:
    """``fun``, ``jac`` and ``events`` of a complex system of dimension n as those of the real
    system of dimension 2n whose state is (Re z, Im z)."""
    def real_fun(t, x, fun=fun):
        f = np.asarray(fun(t, x[:n] + 1j * x[n:]), dtype=complex)
        return np.concatenate([f.real, f.imag])

    def blocks(j):
        # df/dz = A + iB of a holomorphic f: d(Re f, Im f)/d(Re z, Im z) = [[A, −B], [B, A]].
        if hasattr(j, "toarray"):
            j = j.toarray()
        j = np.asarray(j, dtype=complex)
        if j.shape != (n, n):
            raise ValueError(f"`jac` is expected to have shape {(n, n)}, but actually has {j.shape}.")
        a, b = j.real, j.imag
        return np.block([[a, -b], [b, a]])

    if callable(jac):
        user_jac = jac
        jac = (lambda t, x: blocks(user_jac(t, x[:n] + 1j * x[n:])))
    elif jac is not None:
        jac = blocks(jac)
    if events is not None:
        if callable(events):
            events = (events,)
        wrapped = []
        for event in events:
            if not callable(event):
                wrapped.append(event)
                continue

            def real_event(t, x, *args, event=event):
                return event(t, x[:n] + 1j * x[n:], *args)

            for attr in ("terminal", "direction"):
                if hasattr(event, attr):
                    setattr(real_event, attr, getattr(event, attr))
            wrapped.append(real_event)
        events = wrapped
    return real_fun, jac, events
