"""Tests of jetnh.mechanics.accelerations: the parts of [F] and D F taken by symengine against
sympy's own Euler operator and total derivative, and the block solve on a long chain
against sympy.physics.mechanics."""

from __future__ import annotations

import random

import pytest
import sympy as sp
from hypothesis import given, strategies as st

import jetnh.strategies as jst
from jetnh import JetSpace, models
from jetnh.mechanics.accelerations import euler_parts
from jetnh.algebra import dag
from jetnh.algebra.zero import vanishes


@st.composite
def expressions(draw):
    J = draw(jst.jet_spaces(min_n=1, max_n=4))
    F = draw(st.one_of(jst.lagrangians(J), jst.jet_expressions(J, order=1)))
    return J, F


@given(expressions(), st.data())
def test_shared_conversions_give_the_same_parts_as_one_objects(case, data):
    """Parts converted with one memo (``cached_parts``: a system's Lagrangian and
    constraints) are those converted apart; equal parts of two calls are one object."""
    J, F = case
    G = data.draw(jst.jet_expressions(J, order=1))
    memo: dict = {}
    for H in (F, G, F + G):
        shared, apart = euler_parts(J, H, converted=memo), euler_parts(J, H)
        assert shared.p == apart.p and shared.H == apart.H and shared.r == apart.r
        assert shared.v == apart.v
    again = euler_parts(J, F, converted=memo)
    assert all(a is b for a, b in zip(again.p, euler_parts(J, F, converted=memo).p))


def test_shared_conversions_keep_each_calls_symbols():
    """A symbol of the same name with other assumptions is not taken from the memo."""
    J = JetSpace("x")
    xd = J.qd[0]
    memo: dict = {}
    positive, plain = sp.Symbol("m", positive=True), sp.Symbol("m")
    assert euler_parts(J, positive * xd**2 / 2, converted=memo).p[0].has(positive)
    p = euler_parts(J, plain * xd**2 / 2, converted=memo).p[0]
    assert p.has(plain) and not p.has(positive)


@given(expressions())
def test_parts_reassemble_the_euler_operator_and_the_total_derivative(case):
    J, F = case
    parts = euler_parts(J, F)
    qdd = sp.Matrix(J.qdd)
    for s, e in enumerate(J.euler(F)):
        assert vanishes(parts.r[s] - (parts.H * qdd)[s] - e), (F, s)
    assert vanishes(parts.v + sp.Add(*[p * a for p, a in zip(parts.p, J.qdd)]) - J.D(F))
    assert parts.H == parts.H.T


def test_parts_keep_the_symbols_assumptions_and_undefined_functions():
    J = JetSpace("x y")
    x, y = J.q
    xd, yd = J.qd
    m = sp.Symbol("m", positive=True)
    parts = euler_parts(J, m * (xd**2 + yd**2) / 2 - m * y)
    assert parts.H == sp.Matrix([[m, 0], [0, m]]) and parts.r[1] == -m
    g = sp.Function("g")
    parts = euler_parts(J, g(x, xd))                 # jetnh.mechanics.proof's generic functions
    assert parts.p[0] == sp.diff(g(x, xd), xd)


@given(expressions())
def test_parts_are_symengines_own_conversion_shared(case):
    """The Euler parts converted once per distinct subexpression are, entry by entry,
    the same expressions as symengine's own (tree-walking) conversion; without ``rest``
    r is left out and p, H, v are unchanged."""
    import symengine as se

    from jetnh.mechanics.accelerations import _parts

    J, F = case
    if F.has(sp.Function("f")) or not F.free_symbols:
        return
    n = J.n
    syms = [se.Symbol(v.name) for v in (J.t, *J.q, *J.qd)]
    p, H, r, v = _parts(se.sympify(F), syms[0], syms[1:n + 1], syms[n + 1:], True, True,
                        se.Integer(0), se.Add)
    fix = {sp.Symbol(s.name): s for s in F.free_symbols | {J.t, *J.q, *J.qd}}
    own = [sp.sympify(e).xreplace(fix) for e in [*p, *[x for row in H for x in row], *r, v]]
    parts = euler_parts(J, F)
    got = [*parts.p, *parts.H, *parts.r, parts.v]
    assert got == own and all(a.args == b.args for a, b in zip(got, own))
    lean = euler_parts(J, F, rest=False)
    assert lean.r is None and lean.p == parts.p and lean.H == parts.H and lean.v == parts.v


@given(expressions())
def test_derivatives_taken_together_are_symengines_one_by_one(case):
    """The momenta's derivatives by one symbol in one walk (``_together``) are the very
    symengine expressions of one diff per momentum, by every symbol."""
    import symengine as se

    from jetnh.mechanics.accelerations import _together

    J, F = case
    if F.has(sp.Function("f")):
        return
    syms = [se.Symbol(v.name) for v in (J.t, *J.q, *J.qd)]
    Fs = se.sympify(F)
    p = [Fs.diff(v) for v in syms[J.n + 1:]] + [Fs, se.Integer(0), syms[0]]
    for x in syms:
        assert _together(p, x) == [e.diff(x) for e in p]


def test_shared_parts_of_a_chain_are_converted_once():
    """The 6-trailer's Lagrangian: its parts are symengine's own conversion's, with no
    more distinct objects (that conversion walks the tree, meeting shared parts again)."""
    import symengine as se

    system = models.get("n_trailer", N=6)
    parts = euler_parts(system.J, system.L)
    roots = [*parts.p, *parts.H, *parts.r, parts.v]
    own = [sp.sympify(se.sympify(e)) for e in roots]
    assert own == roots
    assert dag.size(roots) <= dag.size(own)


def test_chain_accelerations_match_lagranges_method_and_stay_shared():
    """The car with 5 trailers: every principle's q'' through the block solve; Chetaev's
    against LagrangesMethod at a random state on the constraints; the solved
    expressions are a DAG of modest size (the tree would be exponential)."""
    from sympy.physics.mechanics import LagrangesMethod

    system = models.get("n_trailer", N=5)
    J = system.J
    acc = system.equations("chetaev").accelerations()
    lm = LagrangesMethod(J.to_dynamic(system.L), [J.to_dynamic(q) for q in J.q],
                         nonhol_coneqs=[J.to_dynamic(f) for f in system.constraints])
    lm.form_lagranges_equations()
    rnd = random.Random(3)
    vals = {s: sp.Float(rnd.uniform(0.2, 1.2), 30)
            for s in (J.t, *J.q, *system.independent_velocities, *system.parameters)}
    A = system.jacobian_dependent.xreplace(vals)
    rest = sp.Matrix(system.constraints).xreplace({**vals, **{v: 0 for v in system.dependent_velocities}})
    vals.update(zip(system.dependent_velocities, A.LUsolve(-rest)))
    mass, forcing = (J.from_dynamic(lm.mass_matrix_full), J.from_dynamic(lm.forcing_full))
    ref = mass.xreplace(vals).LUsolve(forcing.xreplace(vals))
    for s, a in enumerate(J.qdd):
        assert abs(acc[a].xreplace(vals).evalf(30) - ref[J.n + s]) < 1e-20 * (1 + abs(ref[J.n + s]))
    assert max(dag.size(e) for e in acc.values()) < 5000
    for principle in ("vakonomic", "holder", "suslov"):
        out = system.equations(principle).accelerations()
        assert set(J.qdd) <= set(out)


@pytest.mark.parametrize("form", ["explicit", "reduced", "embedded"])
def test_explicit_forms_rates_are_those_of_the_explicit_multipliers(form):
    """Vakonomic explicit forms: (17)/(18)/(20) vanish on the accelerations and rates of
    the explicit constraints' multipliers (the rates through (D A_dep)^T kappa)."""
    system = models.get("n_trailer", N=1)
    eom = system.equations("vakonomic", form)
    acc = eom.accelerations()
    for e in eom.expressions:
        assert vanishes(system.on_constraints(e.xreplace(acc)), system), (form, e)


def test_a_derivation_does_no_more_work_after_another_one(monkeypatch):
    """sympy's construction cache must not mix equal-but-distinct copies of an earlier
    derivation's nodes into a later one: comparing them walks trees, not the graph (it
    made the second N = 16 trailer derivation in a process ten times slower).  Counted in
    calls of Basic.__eq__, not timed."""
    from sympy.core.basic import Basic

    calls = [0]
    original = Basic.__eq__

    def counting(a, b):
        calls[0] += 1
        return original(a, b)

    monkeypatch.setattr(Basic, "__eq__", counting)
    work = []
    for principle in ("vakonomic", "chetaev", "vakonomic"):
        system = models.get("n_trailer", N=6)
        calls[0] = 0
        system.equations(principle).accelerations()
        work.append(calls[0])
    assert work[2] <= 1.2 * work[0], work


def test_accelerations_are_read_only_and_their_repr_keeps_to_the_budget():
    """A small system's accelerations print in full; a long chain's (exponentially large
    as trees) print as sizes within the text budget, without walking a tree."""
    from jetnh.display import TEXT_BUDGET
    from jetnh.errors import FrozenError

    knife = models.get("knife_edge")
    acc = knife.equations("chetaev").accelerations()
    x_tt = knife.J.qdd[0]
    assert f"x_tt: {acc[x_tt]}" in repr(acc) and str(acc) == repr(acc)
    assert acc == dict(acc)
    with pytest.raises(FrozenError):
        acc[x_tt] = 0
    chain = models.get("n_trailer", N=6).equations("suslov").accelerations()
    text = repr(chain)
    assert len(text) <= TEXT_BUDGET and "distinct parts in" in text
    assert text.count(": <expression of ") + text.count("_tt: ") >= len(chain) - 1
    import pickle

    assert pickle.loads(pickle.dumps(acc)) == acc
