"""Variation operators: identity (3) as derived, its reductions (6), (8), (10), and (11)."""

import random

import numpy as np
import sympy as sp
from hypothesis import given, settings

import jetnh.strategies as jst
from jetnh import JetSpace
from jetnh.mechanics.system import System
from jetnh.mechanics.equations import action_variation, chetaev_admissible, multiplier_symbols
from jetnh.algebra.zero import on_manifold_point, value, vanishes
from jetnh.models import rolling_disk
from jetnh.mechanics.variations import KINDS, defect, identity_residual, make, printed_identity_residual, reduced_identity_residual


def restricted(system, v):
    """The variation with eta restricted to the Chetaev subspace eta = P eta^mu."""
    return make(system, v.kind, eta=chetaev_admissible(system, v.eta))


@settings(max_examples=15)
@given(jst.systems(max_n=4))
def test_identity_holds_for_every_variation(s):
    for kind in KINDS:
        v = make(s, kind)
        for r in identity_residual(v):
            assert vanishes(r)


def test_printed_identity_3_fails_where_the_commutator_is_nonzero():
    s = rolling_disk()
    v = make(s, "suslov")
    assert any(c != 0 for c in v.c)
    assert all(vanishes(r) for r in identity_residual(v))
    assert not all(vanishes(r) for r in printed_identity_residual(v))
    # with c = 0 (Hoelder, vakonomic) the misprinted term is multiplied by zero
    assert all(vanishes(r) for r in printed_identity_residual(make(s, "holder")))


@settings(max_examples=10)
@given(jst.systems(max_n=4))
def test_action_variation_13_is_an_identity(s):
    lams = multiplier_symbols(s)
    for kind in ("free", "suslov"):
        v = make(s, kind, extra_fields=[m.name for m in lams])
        assert vanishes(action_variation(s, v, lams).residual())


@settings(max_examples=12)
@given(jst.systems(max_n=4))
def test_each_variation_meets_its_own_conditions(s):
    for kind in ("holder", "suslov"):
        v = restricted(s, make(s, kind))
        for name, res in v.residuals().items():
            assert all(vanishes(r) for r in res), (kind, name)
        assert all(vanishes(r) for r in reduced_identity_residual(v)), kind
    # vakonomic (6): the reduced residual is exactly delta f, so it vanishes iff delta_V f = 0
    v = make(s, "vakonomic")
    for r, df in zip(reduced_identity_residual(v), v.residuals()["delta f = 0"]):
        assert vanishes(r - df)


@settings(max_examples=12)
@given(jst.systems(max_n=4))
def test_variations_coincide_exactly_when_the_defect_11_vanishes(s):
    """On the Chetaev subspace: delta_H f = [f] eta and A_alpha c_S = [f] eta, so the
    Hoelder variation keeps f and the Suslov one commutes with d iff [f]_s eta^s = 0."""
    h = restricted(s, make(s, "holder"))
    su = restricted(s, make(s, "suslov"))
    dfe = defect(s, h.eta, h.J)
    for a, f in enumerate(s.constraints):
        assert vanishes(h.delta(f) - dfe[a])
    A = s.jacobian_dependent
    for a in range(s.k):
        Ac = sp.Add(*[A[a, b] * su.c[i] for b, i in enumerate(s.dep_index)])
        assert vanishes(Ac - dfe[a])
    # both sides of the line, at a random point: eta^mu in ker([f] P) gives zero defect
    ind_eta = [h.eta[i] for i in s.ind_index]
    syms = set().union(*(sp.sympify(d).free_symbols for d in dfe)) - set(ind_eta)
    pt = on_manifold_point(s, syms, random.Random(1))
    G = np.array([[value(sp.diff(d, e), pt).real for e in ind_eta] for d in dfe])
    _, sv, vt = np.linalg.svd(G)
    rank = int(np.sum(sv > 1e-10 * max(1.0, sv[0] if sv.size else 1.0)))
    if rank < len(ind_eta):                      # a nonzero eta with zero defect exists
        kernel = vt[rank]
        at = {**pt, **{e: sp.Float(x, 30) for e, x in zip(ind_eta, kernel)}}
        assert all(abs(value(d, at)) < 1e-9 for d in dfe)
        assert all(abs(value(c, at)) < 1e-9 for c in su.c)
    if rank:                                      # and one with nonzero defect
        at = {**pt, **{e: sp.Float(x, 30) for e, x in zip(ind_eta, vt[0])}}
        assert max(abs(value(d, at)) for d in dfe) > 1e-6
        assert max(abs(value(c, at)) for c in su.c) > 1e-9


def test_integrable_constraints_have_zero_defect():
    J = JetSpace("x y z")
    x, y, z = J.q
    g = y - x**2 + sp.sin(z) * J.t
    s = System(J, (J.qd[0]**2 + J.qd[1]**2 + J.qd[2]**2) / 2, [J.D(g)], [y])
    assert all(vanishes(d) for d in defect(s))


def test_defect_of_the_disk_is_nonzero_on_the_chetaev_subspace():
    s = rolling_disk()
    h = restricted(s, make(s, "holder"))
    assert not all(vanishes(d) for d in defect(s, h.eta, h.J))


def test_conditions_named_by_each_variation():
    s = rolling_disk()
    assert set(make(s, "free").conditions) == set()
    assert set(make(s, "vakonomic").conditions) == {"delta f = 0"}
    assert set(make(s, "holder").conditions) == {"Chetaev condition"}
    assert set(make(s, "suslov").conditions) == {"Chetaev condition", "delta f = 0"}
    assert all(c == 0 for c in make(s, "vakonomic").c)
    su = make(s, "suslov")
    assert all(su.c[i] == 0 for i in s.ind_index)
    assert any(su.c[i] != 0 for i in s.dep_index)
