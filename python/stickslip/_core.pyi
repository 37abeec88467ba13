"""Type stubs of the compiled module stickslip._core (see python/src/lib.rs)."""

from typing import Any, Optional, Sequence

DENSE_NODES: int

def run(text: str, source: str, threads: Optional[int] = None) -> tuple[str, list[tuple[str, Any]]]:
    """Runs a scene (JSON text): the report as JSON text and the time series' columns (name, numpy array)."""

def fit(text: str, source: str, data: str, params: str, columns: str, loading: str) -> tuple[str, list[tuple[str, Any]]]:
    """Fits a lab scene (JSON text) to the record in `data`: the report as JSON text and the columns t, x_lp, mu_data, mu_fit."""

def sweep(text: str, source: str, axes: Sequence[tuple[str, Any]], threads: Optional[int] = None) -> str:
    """Runs a sweep of the scene over the axes and returns the rows as a JSON array."""

def solve_ivp(fun: Any, jac: Any, method: str, table: Optional[str], tolerances: Optional[str],
              t0: float, t_bound: float,
              y0: Sequence[float], rtol: float, atol: Sequence[float],
              t_eval: Optional[Sequence[float]], dense_output: bool,
              events: Sequence[tuple[Any, float, float]], options: dict[str, Any]) -> dict[str, Any]:
    """The stepping loop of stickslip.solve_ivp (raw arrays, counters, status, error)."""

def sundials_version() -> str:
    """The SUNDIALS version the package runs with."""
