"""The search of a watched step for a dip of a singularity indicator below its threshold
(``methods._events.sing_dip``), on interpolants and indicators whose least value is known
in closed form: q(theta) = c (theta - s) + d (theta - s)^2 (zero at s only, |d| <= |c|/2),
the indicator ``q^2 + m`` or ``sin(q)^2 + m`` (least value m at theta = s), the threshold
``eps = tol g(0)``.  A dip reaches the threshold exactly when m <= eps.

The search is compiled once per module (a numba harness calling the helper the loops
inline, with an indicator callback that counts its evaluations)."""

import math

import numba
import numpy as np
import pytest
from hypothesis import assume, given, strategies as st

from jetnh.numeric.methods._common import RHS_SIGNATURE, function_at
from jetnh.numeric.methods._events import SAMPLES, dense_eval, sing_dip

TOL = 1e-10


@numba.cfunc(RHS_SIGNATURE)
def _indicator(t, y, p, out):
    """q^2 + m (p[2] == 0) or sin(q)^2 + m, m = p[0]; p[1] counts the evaluations."""
    p[1] += 1.0
    q = y[0]
    out[0] = (q * q if p[2] == 0.0 else math.sin(q) ** 2) + p[0]


@numba.njit
def _dip(address, y_old, F, p, g_old, g_new, eps, gref):
    sing = function_at(address)
    sig = np.ones(1)
    ytmp = np.empty(1)
    return sing_dip(sing, 1, 0.0, 1.0, y_old, F, p, g_old.copy(), g_new, sig, eps, gref,
                    ytmp)


def rows(c, d, s):
    """y_old and the rows F (``dense_eval``'s form, three rows) of q."""
    a, b, g = -c * s + d * s * s, c - 2 * d * s, d      # q = a + b theta + g theta^2
    return np.array([a]), np.array([[b + g], [-g], [0.0]])


def search(c, d, s, m, kind=0):
    """(theta returned, evaluations, g at that theta, eps) of the search on q."""
    y_old, F = rows(c, d, s)
    p = np.array([m, 0.0, float(kind)])
    ind = (lambda q: q * q + m) if kind == 0 else (lambda q: math.sin(q) ** 2 + m)
    q = lambda th: c * (th - s) + d * (th - s) ** 2          # noqa: E731
    g0, g1 = ind(q(0.0)), ind(q(1.0))
    eps = np.array([TOL * g0])
    th = _dip(_indicator.address, y_old, F, p, np.array([g0]), np.array([g1]), eps,
              np.array([g0]))
    g_th = None
    if th > 0.0:
        y = np.empty(1)
        dense_eval(th, y_old, F, y)
        g_th = ind(y[0])
    return th, int(p[1]), g_th, eps[0], (g0, g1)


slopes = st.floats(0.1, 10.0).flatmap(lambda c: st.sampled_from([c, -c]))
where = st.floats(0.002, 0.998)
bends = st.floats(-0.5, 0.5)
kinds = st.sampled_from([0, 1])


def test_the_interpolant_is_q():
    y_old, F = rows(2.0, 0.5, 0.3)
    y = np.empty(1)
    for th in (0.0, 0.25, 0.3, 0.9, 1.0):
        dense_eval(th, y_old, F, y)
        assert y[0] == pytest.approx(2.0 * (th - 0.3) + 0.5 * (th - 0.3) ** 2, abs=1e-15)


@given(slopes, bends, where, kinds)
def test_touching_zero_found_anywhere_in_the_step(c, bend, s, kind):
    """An indicator that only touches zero (xdot^2 + ydot^2 at a velocity reversal) is
    found wherever the touch falls between the samples."""
    if kind == 1:
        c = math.copysign(min(abs(c), 1.0), c)       # sin(q)^2: one zero of q in the step
    th, n, g_th, eps, (g0, g1) = search(c, bend * abs(c), s, 0.0, kind)
    assume(g0 > 10 * eps and g1 > 10 * eps)           # the step's ends are regular
    assert th > 0.0, (c, bend, s)
    assert g_th <= eps * (1 + 1e-9) + 1e-300, (th, g_th, eps)


@given(slopes, bends, where, st.floats(1e-6, 0.999), kinds)
def test_dip_just_below_the_threshold_found(c, bend, s, below, kind):
    if kind == 1:
        c = math.copysign(min(abs(c), 1.0), c)
    y0 = -c * s + bend * abs(c) * s * s               # q(0)
    m_frac = 1.0 - below                              # m = (1 - below) eps
    g0 = (y0 * y0 if kind == 0 else math.sin(y0) ** 2)
    m = m_frac * TOL * g0 / (1.0 - m_frac * TOL)      # then m = m_frac TOL g(0) exactly
    th, n, g_th, eps, (g0, g1) = search(c, bend * abs(c), s, m, kind)
    assume(g1 > 10 * eps)
    assert m < eps
    assert th > 0.0, (c, bend, s, below)
    assert g_th <= eps * (1 + 1e-9)


@given(slopes, bends, where, st.floats(1.001, 1e8), kinds)
def test_dip_above_the_threshold_not_reported(c, bend, s, above, kind):
    if kind == 1:
        c = math.copysign(min(abs(c), 1.0), c)
    y0 = -c * s + bend * abs(c) * s * s               # q(0)
    g0 = (y0 * y0 if kind == 0 else math.sin(y0) ** 2)
    m = above * TOL * g0 / (1.0 - above * TOL)
    th, n, g_th, eps, _ = search(c, bend * abs(c), s, m, kind)
    assert m > eps
    assert th == -1.0


@given(slopes, bends, where, st.floats(1e-4, 1.0), kinds)
def test_a_dip_clearly_above_the_threshold_is_decided_early(c, bend, s, rel, kind):
    """Where the step's least value is well above the threshold (a fraction ``rel`` of
    the indicator's size at the step's start), the search stops once that is certain,
    instead of narrowing the bracket to 1e-15 (~70 evaluations)."""
    if kind == 1:
        c = math.copysign(min(abs(c), 1.0), c)
    y0 = -c * s + bend * abs(c) * s * s               # q(0)
    g0 = (y0 * y0 if kind == 0 else math.sin(y0) ** 2)
    assume(g0 > 1e-6)
    th, n, g_th, eps, _ = search(c, bend * abs(c), s, rel * g0, kind)
    assert th == -1.0
    assert n <= SAMPLES - 1 + 30, n


def test_an_indicator_far_from_its_threshold_costs_the_samples_only():
    """A step where the indicator moves away from zero: the samples decide it."""
    th, n, _, _, _ = search(1.0, 0.0, -0.5, 0.0)      # q from 0.5 to 1.5
    assert th == -1.0 and n == SAMPLES - 1


def test_a_second_dip_is_searched_too():
    """Two touching zeros in one step, the samples smallest near the one that stays
    above the threshold: the other one is searched as well."""
    # q = (theta - 0.31) (theta - 0.86) / ... : two simple zeros of q -> two touches of
    # q^2; with m just above eps near one of them they differ only through q's slope
    y_old = np.array([0.31 * 0.86])
    F = np.array([[1.0 - 0.31 - 0.86], [-1.0], [0.0]])  # q = a + b th + th^2
    y = np.empty(1)
    for th in (0.31, 0.86):
        dense_eval(th, y_old, F, y)
        assert abs(y[0]) < 1e-15
    p = np.array([0.0, 0.0, 0.0])
    g0 = y_old[0] ** 2
    dense_eval(1.0, y_old, F, y)
    g1 = y[0] ** 2
    th = _dip(_indicator.address, y_old, F, p, np.array([g0]), np.array([g1]),
              np.array([TOL * g0]), np.array([g0]))
    assert th > 0.0
    dense_eval(th, y_old, F, y)
    assert y[0] ** 2 <= TOL * g0 * (1 + 1e-9)
