"""Makes problems.py importable and shares the slow scipy reference of the spring-slider."""

import os
import sys

import pytest

sys.path.insert(0, os.path.dirname(__file__))


@pytest.fixture(scope="session")
def slider_reference():
    """scipy's Radau on the spring-slider to t = 40 at rtol 1e-12, atol 1e-14, with the
    upward ln v = 0 crossings and dense output (about 10 s)."""
    from scipy.integrate import solve_ivp

    import problems

    return solve_ivp(problems.slider, (0.0, 40.0), problems.SLIDER_Y0, method="Radau",
                     rtol=1e-12, atol=1e-14, jac=problems.slider_jac, events=problems.upward,
                     dense_output=True)
