"""Chetaev (Lagrange-d'Alembert) accelerations against sympy.physics.mechanics.

An independent route: ``LagrangesMethod(L, qs, nonhol_coneqs=f)`` with
``form_lagranges_equations()`` and ``rhs()`` solves the multiplier form
M q'' = F + A^T lambda together with D f = 0.  Its state is (q, q', lambda), so
``rhs()`` is (q', q'', lambda); only the accelerations are compared (the sign of the
multipliers differs between conventions, sympy#30215).

The comparison is numeric, at random states *on* the constraint manifold (independent
velocities drawn at random, dependent ones from ``System.phi``), in 30-digit arithmetic,
to relative 1e-10.
"""

from __future__ import annotations

import random

import pytest
import sympy as sp
from hypothesis import given, settings, strategies as st
from sympy.physics.mechanics import LagrangesMethod

import jetnh.strategies as jst
from jetnh import JetSpace, models
from jetnh.mechanics.system import System
from numbers30 import f30, num

RTOL = 1e-10

randoms = st.randoms(use_true_random=False)


# ------------------------------------------------------------------ helpers


def manifold_state(system: System, rnd: random.Random, params=None, lo=-1.0, hi=1.0) -> dict:
    """t, q and the independent velocities at random; dependent velocities from phi."""
    J = system.J
    vals = dict(params or {})
    vals[J.t] = f30(rnd.uniform(lo, hi))
    for s in J.q + system.independent_velocities:
        vals[s] = f30(rnd.uniform(lo, hi))
    for v, phi in system.phi.items():
        vals[v] = num(phi, vals)
    return vals


def lagranges_method_accelerations(J: JetSpace, L, constraints) -> dict:
    """q'' from sympy.physics.mechanics.LagrangesMethod, as jet expressions."""
    qs = [J.to_dynamic(q) for q in J.q]
    lm = LagrangesMethod(J.to_dynamic(L), qs,
                         nonhol_coneqs=[J.to_dynamic(f) for f in constraints])
    lm.form_lagranges_equations()
    rhs = lm.rhs()
    n, k = J.n, len(constraints)
    assert rhs.shape == (2 * n + k, 1)
    # the state is (q, q', lambda): the first n rows are the velocities themselves
    assert [J.from_dynamic(rhs[i]) for i in range(n)] == list(J.qd)
    return {J.qdd[s]: J.from_dynamic(rhs[n + s]) for s in range(n)}


def assert_accelerations_match(system: System, ref: dict, rnd: random.Random, points=2,
                               params=None):
    acc = system.equations("chetaev").accelerations()
    J = system.J
    assert set(J.qdd) <= set(acc)
    for _ in range(points):
        vals = manifold_state(system, rnd, params)
        for a in J.qdd:
            va, vb = num(acc[a], vals), num(ref[a], vals)
            scale = max(1, abs(va), abs(vb))
            assert abs(va - vb) <= RTOL * scale, f"{a}: jetnh {va} vs LagrangesMethod {vb}"


# ------------------------------------------------------------------ random systems
@given(jst.systems(min_n=2, max_n=4, affine=True), randoms)
def test_chetaev_matches_lagranges_method_on_random_affine_systems(system, rnd):
    J, L, constraints = system.J, system.L, system.given_constraints
    ref = lagranges_method_accelerations(J, L, constraints)
    assert_accelerations_match(system, ref, rnd)


@st.composite
def _mixed_affine_systems(draw):
    """Affine systems whose constraints are *implicit*: the explicit ones mixed by an
    invertible matrix with a configuration-dependent factor, so that df/dqdot^alpha != I."""
    J, L, constraints, dependent = draw(jst.constrained_systems(min_n=3, max_n=4, affine=True))
    k = len(constraints)
    c = draw(st.integers(-2, 2))
    M = sp.eye(k)
    for a in range(1, k):               # unit lower-triangular: invertible
        M[a, a - 1] = c
    factor = 1 + J.q[0] ** 2 / 2
    mixed = tuple(factor * e for e in (M * sp.Matrix(constraints)))
    return J, L, mixed, dependent


@settings(max_examples=10)
@given(_mixed_affine_systems(), randoms)
def test_chetaev_matches_lagranges_method_with_implicit_constraints(case, rnd):
    J, L, constraints, dependent = case
    system = System(J, L, constraints, dependent=dependent)
    ref = lagranges_method_accelerations(J, L, constraints)
    assert_accelerations_match(system, ref, rnd)


# ------------------------------------------------------------------ rolling disk
R, I1, I2 = sp.symbols("R I1 I2")     # the parameters of models.rolling_disk


def rolling_disk(dependent=("x", "y")):
    """The paper's Example 1 (the catalogue's): its J, L, constraints (40) and System."""
    system = models.rolling_disk().with_split(list(dependent))
    return system.J, system.L, system.given_constraints, system


@pytest.mark.parametrize("dependent", [("x", "y"), ("phi", "y")])
def test_chetaev_matches_lagranges_method_on_the_rolling_disk(dependent):
    J, L, cons, system = rolling_disk(dependent)
    ref = lagranges_method_accelerations(J, L, cons)
    rnd = random.Random(7)
    for _ in range(3):
        params = {R: f30(rnd.uniform(0.5, 2)), I1: f30(rnd.uniform(0.2, 1)),
                  I2: f30(rnd.uniform(0.2, 1))}
        assert_accelerations_match(system, ref, rnd, points=2, params=params)


def test_rolling_disk_chetaev_accelerations_in_closed_form():
    """Both routes give phi'' = psi'' = 0, x'' = -R phi' psi' sin psi, y'' = R phi' psi' cos psi."""
    J, L, cons, system = rolling_disk()
    x, y, phi, psi = J.q
    phid, psid = J.qd[2], J.qd[3]
    expected = {J.qdd[0]: -R * phid * psid * sp.sin(psi), J.qdd[1]: R * phid * psid * sp.cos(psi),
                J.qdd[2]: 0, J.qdd[3]: 0}
    acc = system.equations("chetaev").accelerations()
    ref = lagranges_method_accelerations(J, L, cons)
    for a, e in expected.items():
        assert sp.simplify(system.on_constraints(acc[a]) - e) == 0
        assert sp.simplify(system.on_constraints(ref[a]) - e) == 0
