"""Property tests on the broader random systems of jetnh.strategies: implicit affine
constraints A(q) qdot + b, constraints nonlinear in the dependent velocity, full
configuration-dependent mass matrices, more coordinates.  Two routes each: jetnh's
Chetaev accelerations against sympy.physics.mechanics.LagrangesMethod, every
principle's accelerations against the differentiated constraints and its own
multiplier-form rows, and compare() against the same facts."""

from __future__ import annotations

import random

from hypothesis import given, settings, strategies as st

import jetnh as jn
import jetnh.strategies as jst
from jetnh.mechanics.system import System
from numbers30 import f30, num
from test_crosscheck_mechanics import assert_accelerations_match, lagranges_method_accelerations

TOL = 1e-18
randoms = st.randoms(use_true_random=False)

implicit_affine = jst.constrained_systems(min_n=3, max_n=5, affine=True, implicit=True,
                                          mass=None)
implicit_nonlinear = jst.constrained_systems(min_n=2, max_n=4, affine=False, implicit=True,
                                             mass=None)


def _state(system: System, rnd: random.Random, extra=()) -> dict:
    J = system.J
    vals = {s: f30(rnd.uniform(-1, 1)) for s in (J.t,) + J.q + system.independent_velocities
            + tuple(extra)}
    vals.update({v: num(phi, vals) for v, phi in system.phi.items()})
    return vals


@settings(max_examples=8)
@given(implicit_affine, randoms)
def test_chetaev_matches_lagranges_method_on_implicit_affine_systems_with_full_mass(
        case, rnd):
    J, L, constraints, dependent = case
    system = System(J, L, constraints, dependent=dependent)
    ref = lagranges_method_accelerations(J, L, constraints)
    assert_accelerations_match(system, ref, rnd)


@settings(max_examples=8)
@given(st.one_of(implicit_affine, implicit_nonlinear), randoms)
def test_every_principle_keeps_the_constraints_and_its_rows(case, rnd):
    J, L, constraints, dependent = case
    system = System(J, L, constraints, dependent=dependent)
    Df = [J.D(f) for f in system.constraints]
    for principle in ("chetaev", "vakonomic", "suslov"):
        eom = system.equations(principle, "multiplier")
        acc = eom.accelerations()
        vals = _state(system, rnd, extra=eom.multipliers)
        vals.update({a: num(e, vals) for a, e in acc.items()})
        for e in Df:
            assert abs(num(e, vals)) <= TOL * 10
        if principle == "vakonomic":              # (15) holds on its accelerations
            for e in eom.expressions:
                assert abs(num(e, vals)) <= TOL * 100


@settings(max_examples=6)
@given(st.one_of(implicit_affine, implicit_nonlinear))
def test_compare_vakonomic_and_holder_on_broad_systems(case):
    J, L, constraints, dependent = case
    system = System(J, L, constraints, dependent=dependent)
    c = jn.compare(system, "vakonomic", "holder")
    assert c.identical                            # (22): the same equations
    assert not c.singular or all(f.free_symbols for f in c.singular)
