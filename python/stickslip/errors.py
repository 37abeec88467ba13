"""The exceptions of stickslip.

- :class:`SceneError` (a ``ValueError``): a scene that does not validate; ``field`` is the
  path of the field at fault (e.g. ``"model.gamma"``).
- :class:`RunError` (a ``RuntimeError``): a scene's run failed; ``analysis`` names the
  analysis, ``state`` the state where it failed, and for an integration failure ``t``,
  ``kind`` and ``solver`` say when, how and in which integrator.
- :class:`SolverError` (a ``RuntimeError``): :func:`stickslip.solve_ivp` failed; ``t``, ``y``
  (the last good point), ``kind`` (e.g. ``"TooMuchWork"``, ``"ConvergenceFailures"``),
  ``solver`` and ``result`` (the :class:`stickslip.OdeResult` up to the failure, status -1).
"""

from __future__ import annotations

from typing import Any, Optional


class StickslipError(Exception):
    """Base class of every stickslip exception."""


class SceneError(StickslipError, ValueError):
    """A scene that does not validate.

    Attributes: ``field`` (path of the field at fault, e.g. ``"model.gamma"``), ``source``
    (the scene file or ``"<dict>"``), ``detail`` (what is wrong and what would be valid).
    """

    def __init__(self, message: str, *, field: str, source: str, detail: str) -> None:
        super().__init__(message)
        self.field = field
        self.source = source
        self.detail = detail


class RunError(StickslipError, RuntimeError):
    """A scene's run failed.

    Attributes: ``analysis`` (e.g. ``"cycle"``), ``state`` (numpy array, empty if unknown),
    ``t`` (time of the failure or None), ``kind`` (one word: the integrator's error kind,
    e.g. ``"ConvergenceFailures"``, or the analysis's, e.g. ``"TooMuchWork"`` for a budget),
    ``solver`` (the integrator's name or None), ``bad_input`` (an option that does not fit the
    computed orbit: the CLI's exit code 2).
    """

    def __init__(self, message: str, *, analysis: str, state: Any, t: Optional[float],
                 kind: str, solver: Optional[str], bad_input: bool) -> None:
        super().__init__(message)
        self.analysis = analysis
        self.state = state
        self.t = t
        self.kind = kind
        self.solver = solver
        self.bad_input = bad_input


class SolverError(StickslipError, RuntimeError):
    """An integration by :func:`stickslip.solve_ivp` failed.

    Attributes: ``t`` and ``y`` (the last accepted point), ``kind`` (``"TooMuchWork"``,
    ``"ErrorTestFailures"``, ``"ConvergenceFailures"``, ``"StepUnderflow"``,
    ``"RhsFailure"``, …), ``solver`` (the integrator), ``flag`` (its return code) and
    ``result`` (the :class:`stickslip.OdeResult` up to ``t``, with ``status`` -1).
    """

    def __init__(self, message: str, *, t: float, y: Any, kind: str, solver: str, flag: int,
                 result: Any = None) -> None:
        super().__init__(message)
        self.t = t
        self.y = y
        self.kind = kind
        self.solver = solver
        self.flag = flag
        self.result = result
