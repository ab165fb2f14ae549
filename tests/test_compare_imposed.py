"""compare in the "imposed" convention, where Hoelder leaves its multiplier free: its
motions are a family with a free lambda(t) that contains Chetaev's (lambda = 0) and the
vakonomic ones (lambda following the vakonomic equation).  Second route: the accelerations
substituted and compared at random states on the constraints, by sympy."""

import random

import sympy as sp
from hypothesis import given, settings

import jetnh as jn
import jetnh.strategies as jst


def particle():
    J = jn.JetSpace("x y z")
    x, y, z = J.q
    xd, yd, zd = J.qd
    return jn.System(J, (xd**2 + yd**2 + zd**2) / 2, [zd - y * xd], dependent=[z])


def forced_time_dependent():
    J = jn.JetSpace("x y z")
    x, y, z = J.q
    xd, yd, zd = J.qd
    t = J.t
    L = (xd**2 + 2 * yd**2 + zd**2) / 2 + x * zd + t * y * xd - sp.cos(z)
    return jn.System(J, L, [(1 + y**2) * zd - y * xd**2 - t * yd], dependent=[z])


def _differ(s, a, b, sub, seed=1):
    """max |q''_a - q''_b| (``sub`` applied to a's) at 3 random states on the
    constraints, by direct substitution."""
    rng = random.Random(seed)
    acc_a, acc_b = a.accelerations(), b.accelerations()
    worst = 0
    for _ in range(3):
        syms = {*s.J.q, *s.J.qd, s.J.t, *a.multipliers, *a.arbitrary, *b.multipliers,
                *s.parameters}
        pt = {v: sp.Rational(rng.randint(-9, 9) or 1, rng.randint(2, 7)) for v in syms}
        for v, e in s.phi.items():
            pt[v] = e.xreplace(pt)
        for q in s.J.qdd:
            d = (acc_a[q].xreplace(sub) - acc_b[q]).xreplace(pt)
            worst = max(worst, abs(sp.N(d, 30)))
    return worst


def test_chetaev_is_holder_at_zero():
    s = particle()
    c = jn.compare(s, "chetaev", "holder", convention="imposed")
    h = s.equations("holder", convention="imposed")
    (lam,) = h.arbitrary
    assert c.free == (lam,) and c.family == "holder"
    assert c.choice == {lam: 0}
    assert not c.identical
    text = str(c)
    assert "do not share" not in text
    assert "lambda_z = 0" in text and "every chetaev motion is a holder motion" in text
    # second route: the accelerations at lambda = 0 are Chetaev's, at lambda = 1 not
    ch = s.equations("chetaev")
    assert _differ(s, h, ch, {lam: 0}) < 1e-25
    assert _differ(s, h, ch, {lam: 1}) > 1e-3


def test_vakonomic_is_holder_with_its_own_multiplier():
    s = particle()
    c = jn.compare(s, "vakonomic", "holder", convention="imposed")
    h = s.equations("holder", convention="imposed")
    v = s.equations("vakonomic", convention="imposed")
    assert not c.identical, "Hoelder's lambda(t) is free: not the same motions"
    assert "same accelerations at every state" not in str(c)
    assert c.family == "holder" and c.choice == dict(zip(h.arbitrary, v.multipliers))
    assert "which then follows vakonomic's equation" in str(c)
    assert "lambda_z" in repr(c) and "family='holder'" in repr(c)
    assert _differ(s, h, v, dict(zip(h.arbitrary, v.multipliers))) < 1e-25


def test_audit_system_time_dependent():
    s = forced_time_dependent()
    c = jn.compare(s, "holder", "chetaev", convention="imposed")
    h = s.equations("holder", convention="imposed")
    assert c.family == "holder" and c.choice == {h.arbitrary[0]: 0}
    assert _differ(s, h, s.equations("chetaev"), c.choice) < 1e-25


def test_paper_convention_unchanged():
    s = particle()
    c = jn.compare(s, "vakonomic", "holder")
    assert c.identical and c.free == () and c.family is None and c.choice == {}
    assert str(c).startswith("vakonomic and holder have the same accelerations")


@settings(max_examples=4, deadline=None)
@given(jst.systems(max_n=3, affine=True))
def test_chetaev_in_the_holder_family_on_random_systems(s):
    c = jn.compare(s, "holder", "chetaev", convention="imposed")
    h = s.equations("holder", convention="imposed")
    if not c.free:                        # lambda does not enter: a determined motion
        return
    assert c.choice == {m: 0 for m in h.arbitrary}
    assert _differ(s, h, s.equations("chetaev"), c.choice) < 1e-20
