"""Tests of jetnh.algebra.zero: the zero tests, symbolic (expand, a witness, simplify when
asked) and by evaluation at random points."""

from __future__ import annotations

import sympy as sp

from jetnh.algebra import zero
from jetnh.models import rolling_disk


def test_identities_and_non_identities():
    x, y = sp.symbols("x y")
    assert zero.vanishes(sp.sin(x + y) - sp.sin(x) * sp.cos(y) - sp.cos(x) * sp.sin(y))
    assert zero.vanishes([sp.sqrt(x**2) - sp.Abs(x), (x**2 - y**2) / (x - y) - x - y])
    assert zero.vanishes(sp.sqrt(x) ** 2 - x)
    assert not zero.vanishes([x - x, sp.sin(x) ** 2 - sp.sin(x)])
    assert not zero.vanishes(sp.Rational(1, 10**30) * x)        # tiny, exact: not zero


def test_expressions_not_analytic_across_a_sign_change_are_tested_at_both_signs():
    """sqrt(x**2) = x and (|x| - x) y = 0 hold for positive x only: not zero."""
    x, y = sp.symbols("x y")
    assert not zero.vanishes(sp.sqrt(x**2) - x)
    assert not zero.vanishes((sp.Abs(x) - x) * y)
    assert not zero.vanishes(sp.sign(x) - 1)
    assert zero.vanishes(sp.sign(x) * sp.Abs(x) - x)


def test_signed_points_keep_each_symbols_declared_sign():
    """The points of both signs respect the assumptions: |m x + m| = m |x + 1| for m
    positive (not for m of any sign), |n| = -n for n nonpositive, |p| = p for p
    nonnegative; x of any sign still taken both ways."""
    x = sp.Symbol("x", real=True)
    m, p = sp.Symbol("m", positive=True), sp.Symbol("p", nonnegative=True)
    n, k = sp.Symbol("n", negative=True), sp.Symbol("k", nonpositive=True)
    assert zero.vanishes([sp.Abs(m * x + m) - m * sp.Abs(x + 1)])
    assert zero.vanishes([sp.Abs(n) + n, sp.Abs(k) + k, sp.Abs(p) - p, sp.sign(m) - 1])
    mu = sp.Symbol("mu", real=True)
    assert not zero.vanishes([sp.Abs(mu * x + mu) - mu * sp.Abs(x + 1)])
    assert not zero.vanishes([sp.Abs(m * x) - m * x])


def test_compare_sees_a_difference_at_negative_coordinates():
    """z_t = (|x| - x) y_t is free for x > 0 and the nonholonomic particle for x < 0:
    Chetaev and Suslov differ there (jetnh's own accelerations at x = -0.6 differ)."""
    import jetnh as jn

    J = jn.JetSpace("x y z")
    (x, y, z), (xt, yt, zt) = J.q, J.qd
    s = jn.System(J, (xt**2 + yt**2 + zt**2) / 2, [zt - (sp.Abs(x) - x) * yt],
                  dependent=[z])
    assert not jn.compare(s, "chetaev", "suslov").identical
    a1 = s.equations("chetaev").accelerations()
    a2 = s.equations("suslov").accelerations()
    pt = {x: sp.Rational(-3, 5), y: sp.Rational(7, 10), xt: sp.Rational(4, 5),
          yt: sp.Rational(1, 2)}
    pt[zt] = s.phi[zt].subs(pt)
    assert abs(float((a1[J.qdd[1]] - a2[J.qdd[1]]).subs(pt))) > 0.1


def test_on_the_constraint_manifold_and_on_a_branch():
    """The constraints vanish on the manifold of their system only; a multiplier set
    by ``derived`` (here lambda = -p, the branch (32)) is evaluated at each point."""
    s = rolling_disk()
    f = s.constraints[0]
    assert zero.vanishes(s.constraints, s)
    assert not zero.vanishes(f)
    lam = sp.Symbol("lambda_x")
    p = s.on_constraints(s.p_dependent[0])
    assert zero.vanishes(lam + p, s, derived={lam: -p})
    assert not zero.vanishes(lam + p, s, derived={lam: p})


def test_floats_are_zero_up_to_their_rounding():
    """Input with Floats is zero below ROUNDING times the terms that cancel in it, or
    below a double's rounding (exact input is decided exactly: the same residual with a
    Rational is not zero)."""
    x, y = sp.Symbol("x"), sp.Symbol("y")
    assert zero.vanishes(sp.Float(0.1) * 3 * x - sp.Float(0.3) * x + sp.Float(1e-17) * x)
    assert zero.vanishes(sp.Float(0.3) * (sp.sin(x) ** 2 + sp.cos(x) ** 2) - sp.Float(0.3))
    assert zero.vanishes(y * (sp.Float(0.7) * sp.sin(x) ** 2 + sp.Float(0.7) * sp.cos(x) ** 2
                              - sp.Float(0.7)) ** 3)
    assert not zero.vanishes(sp.Float(1e-6) * x)
    assert not zero.vanishes(sp.Rational(1, 10**17) * x)


def test_a_small_typed_coefficient_is_not_rounding():
    """A Float the user typed is data: 1e-9*y, 1e-14 (a lone constant), a 1e-10 term
    inside a function, are not zero."""
    x, y = sp.Symbol("x"), sp.Symbol("y")
    for c in (1e-9, 1e-10, 1e-14):
        assert not zero.vanishes(sp.Float(c) * y)
        assert not zero.vanishes(sp.Float(c))
    assert not zero.vanishes(sp.sin(sp.Float(1e-10) * x * y))


def test_compare_and_linearize_keep_a_tiny_float_coefficient():
    """z_t = 1e-10 y x_t is not holonomic: vakonomic and Chetaev differ (as with a
    Rational); y'' = 1e-9 y keeps y (unstable), not dropped as cyclic."""
    import jetnh as jn

    J = jn.JetSpace("x y z")
    (x, y, z), (xt, yt, zt) = J.q, J.qd
    s = jn.System(J, (xt**2 + yt**2 + zt**2) / 2, [zt - sp.Float(1e-10) * y * xt],
                  dependent=[z])
    assert not jn.compare(s, "vakonomic", "chetaev").identical
    J2 = jn.JetSpace("x y")
    (x, y), (xt, yt) = J2.q, J2.qd
    s2 = jn.System(J2, (xt**2 + yt**2) / 2 - x**2 / 2 + sp.Float(1e-9) * y**2 / 2)
    lin = jn.linearize(s2, at={"x": 0.0, "y": 0.0, "x_t": 0.0, "y_t": 0.0})
    assert "y" in lin.state_names and lin.dropped == ()
    assert lin.verdict == "unstable"


def test_value_and_manifold_point():
    import random

    s = rolling_disk()
    pt = zero.on_manifold_point(s, s.J.q, random.Random(0))
    assert set(s.dependent_velocities) <= set(pt)
    assert all(abs(zero.value(f, pt)) < 1e-25 for f in s.constraints)


def test_symbolic_zero_tests():
    """expand, a random witness, a common denominator, simplify only when asked; the
    numeric test samples both signs."""
    x, y = sp.symbols("x y")
    trig = sp.sin(x) ** 2 + sp.cos(x) ** 2 - 1
    assert not zero.expr_is_zero(trig)
    assert zero.expr_is_zero(trig, simplify=True)
    assert zero.expr_is_zero(trig, numeric=True)
    assert zero.expr_is_zero(1 / (x + 1) - x / (x * x + x))          # common denominator
    assert zero.zero_residual(x * (x + y) - x * y) == x ** 2
    assert zero.zero_residual((x + y) ** 2 - x ** 2 - 2 * x * y - y ** 2) is None
    assert not zero.numeric_is_zero(sp.sqrt(x ** 2) - x, samples=6)      # negative samples too
    assert zero.numeric_is_zero(sp.sqrt(x ** 2) - sp.Abs(x))
