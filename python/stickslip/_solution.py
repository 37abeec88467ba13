"""The dense output of :func:`stickslip.solve_ivp` (``sol``), as scipy's ``OdeSolution``."""

from __future__ import annotations

from typing import Any

import numpy as np


class OdeSolution:
    """The continuous solution of :func:`stickslip.solve_ivp` over its steps.

    Call it as ``sol(t)`` with a scalar (returns shape ``(n,)``) or an array of times
    (returns ``(n, len(t))``), as scipy's ``OdeSolution``. Each step's interpolant is the
    method's own dense output, sampled at 8 Chebyshev–Lobatto points of the step and
    evaluated by barycentric interpolation, which reproduces any interpolant of degree ≤ 7
    (CVODE's of order ≤ 5, Radau5's, Rodas5P's, ARKODE's) to round-off. Outside
    ``[t_min, t_max]`` the first or last step's polynomial is extrapolated, as in scipy.

    For a complex system (integrated as its real and imaginary parts) the values are complex.

    Attributes: ``ts`` (the step boundaries, in the direction of integration), ``t_min``,
    ``t_max``, ``n_segments``.
    """

    def __init__(self, ts: Any, spans: Any, values: Any, complex_: bool = False) -> None:
        self.ts = np.asarray(ts, dtype=float)
        self._spans = np.asarray(spans, dtype=float)
        self._values = np.asarray(values, dtype=float)
        self.n_segments = len(self.ts) - 1
        self.t_min = float(min(self.ts[0], self.ts[-1]))
        self.t_max = float(max(self.ts[0], self.ts[-1]))
        self._ascending = self.ts[-1] >= self.ts[0]
        self._ts_sorted = self.ts if self._ascending else self.ts[::-1]
        k = self._values.shape[1]
        j = np.arange(k)
        self._nodes = np.cos(np.pi * j / (k - 1))
        w = (-1.0) ** j
        w[0] *= 0.5
        w[-1] *= 0.5
        self._weights = w
        #: A complex system integrated as (real parts, imaginary parts): values come back complex.
        self._complex = complex_

    def _segments(self, t: np.ndarray) -> np.ndarray:
        """The step of each time, as scipy's OdeSolution picks it (a boundary belongs to the
        step that ends there)."""
        ind = np.searchsorted(self._ts_sorted, t, side="left")
        seg = np.clip(ind - 1, 0, self.n_segments - 1)
        return seg if self._ascending else self.n_segments - 1 - seg

    def __call__(self, t: Any) -> np.ndarray:
        """The solution at ``t`` (a number: shape (n,); an array: shape (n, len(t)))."""
        if self.n_segments < 1:
            raise ValueError("the solution has no step to interpolate (t_span of length 0)")
        t = np.asarray(t, dtype=float)
        if t.ndim > 1:
            raise ValueError("`t` must be a float or a 1-D array.")
        scalar = t.ndim == 0
        tt = np.atleast_1d(t)
        seg = self._segments(tt)
        a, b = self._spans[seg, 0], self._spans[seg, 1]
        x = (0.5 * (a + b) - tt) / (0.5 * (b - a))
        diff = x[:, None] - self._nodes[None, :]
        exact = diff == 0.0
        with np.errstate(divide="ignore", invalid="ignore"):
            c = self._weights[None, :] / diff
        c[exact.any(axis=1)] = 0.0
        c[exact] = 1.0
        vals = self._values[seg]  # (m, k, n)
        y = np.einsum("mk,mkn->mn", c, vals) / c.sum(axis=1)[:, None]
        if self._complex:
            m = y.shape[1] // 2
            y = y[:, :m] + 1j * y[:, m:]
        return y[0] if scalar else y.T
