"""Conjugate points of even multiplicity and whole vanishing Jacobi fields: geodesics of
the round 3-sphere in stereographic coordinates, L = 2 |qdot|^2 / (1 + |q|^2)^2, no
constraints.  Along the a-axis the great circle through a0 and a1 has length
2 (atan|a0| + atan|a1|) when it passes the origin; its conjugate point is the antipode
of its start, a time pi / length into the unit span, where two Jacobi fields vanish at
once (det dq/du changes no sign)."""

import math

import numpy as np
import pytest

import jetnh as jn
from jetnh.errors import ArgumentError, ConnectError
from jetnh.numeric.connect import levenberg


@pytest.fixture(scope="module")
def sphere():
    J = jn.JetSpace("a b c")
    return jn.System(J, 2 * sum(v**2 for v in J.qd) / (1 + sum(q**2 for q in J.q))**2)


def _arc(sphere, a1, **kw):
    zero = {"b": 0.0, "c": 0.0}
    return jn.connect(sphere, "vakonomic", {"a": 0.5, **zero}, {"a": a1, **zero},
                      (0.0, 1.0), **kw)


def test_the_antipode_is_conjugate_at_t1(sphere):
    """To the antipode of a = 0.5 (a = -2): a half circle, length pi; two columns of
    dq/du vanish as a whole at t1, which the verdict reports (and nothing before)."""
    c = _arc(sphere, -2.0)
    assert abs(c.cost - math.pi**2 / 2) < 1e-8
    assert c.conjugate_times == (1.0,) and c.minimizer is True


def test_a_conjugate_point_of_multiplicity_two_inside_the_span(sphere):
    """Past the antipode (a = -3): the long arc, length 2 (atan 0.5 + atan 3) > pi, is
    conjugate at pi / length (no sign change of det dq/du there), so no minimizer."""
    c = _arc(sphere, -3.0)
    length = 2 * (math.atan(0.5) + math.atan(3.0))
    assert abs(c.cost - length**2 / 2) < 1e-8
    assert len(c.conjugate_times) == 1
    assert abs(c.conjugate_times[0] - math.pi / length) < 1e-6
    assert c.minimizer is False


def test_restarts_are_for_the_action_principles(sphere):
    with pytest.raises(ArgumentError, match="restarts.*chetaev.*leave restarts at 0"):
        jn.connect(sphere, "chetaev", {"a": 0.5, "b": 0, "c": 0}, {"a": -1.0},
                   (0.0, 1.0), restarts=2)
    with pytest.raises(ArgumentError, match="restarts"):
        _arc(sphere, -1.0, restarts=np.array([1, 2]))


def test_the_compiled_step_takes_only_fitting_arrays():
    """A residual and Jacobian that do not fit the unknowns never reach the compiled
    step (it indexes without bounds checks)."""
    def evaluate(u):
        return np.ones(3), np.ones((3, 1))           # a Jacobian for one unknown

    with pytest.raises(ConnectError, match="internal: .*shape \\(3, 1\\) for 2 unknowns"):
        levenberg.levenberg_marquardt(evaluate, np.zeros(2), 1.0, 1e-10, 5, 1e-9)
