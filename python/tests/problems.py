"""Problems shared by the tests and benches/python_peer.py: the stiff test set's Python
right-hand sides and Jacobians (one definition, in benches/test_set_scipy.py) and a user's
spring-slider written in Python."""

import os
import sys

import numpy as np

REPO = os.path.abspath(os.path.join(os.path.dirname(__file__), "..", ".."))
sys.path.insert(0, os.path.join(REPO, "benches"))

import test_set_scipy  # noqa: E402  (benches/test_set_scipy.py)

hires = test_set_scipy.hires
rober = test_set_scipy.rober
vdpol = test_set_scipy.vdpol
orego = test_set_scipy.orego
e5 = test_set_scipy.e5
pollu = test_set_scipy.pollu
medakzo = test_set_scipy.medakzo
mescd = test_set_scipy.mescd

# The paper's fig. 1 (data/scenes/fig1.json): γ = 1e3, ξ = 0.7, ε = 0.72, slip law, and its
# default start on the slow manifold (u, v, θ) = (0.9902102579427791, 0.5, 0).
GAMMA, XI, EPSILON = 1e3, 0.7, 0.72
SLIDER_Y0 = [0.9902102579427791, np.log(0.5), 0.0]


def slider(t, y, gamma=GAMMA, xi=XI, epsilon=EPSILON):
    """The spring-slider in (u, w = ln v, θ):
    du/dt = v − 1, dw/dt = −γ² e^(−w) (u + (θ + w)/ξ), dθ/dt = −v (θ + (1 + ε) w)."""
    u, w, theta = y
    v = np.exp(w)
    return np.array([v - 1.0, -gamma * gamma * np.exp(-w) * (u + (theta + w) / xi),
                     -v * (theta + (1.0 + epsilon) * w)])


def slider_jac(t, y, gamma=GAMMA, xi=XI, epsilon=EPSILON):
    """∂f/∂(u, w, θ) of :func:`slider`."""
    u, w, theta = y
    v = np.exp(w)
    a = gamma * gamma * np.exp(-w)
    return np.array([
        [0.0, v, 0.0],
        [-a, a * (u + (theta + w) / xi) - a / xi, -a / xi],
        [0.0, -v * (theta + (1.0 + epsilon) * w) - v * (1.0 + epsilon), -v],
    ])


def upward(t, y, *args):
    """ln v = 0 crossed upwards (v rising through the driving velocity)."""
    return y[1]


upward.direction = 1
