"""Shared form (jetnh.algebra.shared): named intermediate quantities stand for the expressions
exactly, every line is short, and the whole is linear in the shared size."""

import json
import random

import mpmath
import pytest
import sympy as sp
from hypothesis import given
from hypothesis import strategies as st

import jetnh as jn
import jetnh.strategies as jst
from jetnh.algebra import dag
from jetnh import models
from jetnh.algebra.shared import INLINE_MAX, shared_form, tree_size


def _values(form, point, dps=30):
    """The rows' values computed through the named quantities, in order."""
    pt = dict(point)
    for name, e in form.where:
        pt[name] = dag.evaluate(e, pt, dps=dps)
    return dag.evaluate(form.expressions(), pt, dps=dps)


def _point(exprs, seed=0):
    rng = random.Random(seed)
    return {s: mpmath.mpf(rng.uniform(0.3, 1.3)) for s in dag.free_symbols(exprs)}


@pytest.fixture(scope="module")
def trailer_acc():
    return models.get("n_trailer", N=6).equations("vakonomic").accelerations()


def test_named_quantities_stand_for_the_accelerations(trailer_acc):
    exprs = list(trailer_acc.values())
    form = shared_form(list(trailer_acc.items()))
    assert form.where and [r[0] for r in form.rows] == list(trailer_acc)
    pt = _point(exprs)
    for a, b in zip(_values(form, pt), dag.evaluate(exprs, pt)):
        assert abs(a - b) <= 1e-25 * (1 + abs(b))
    # each name is defined before it is used, and every line is short
    defined = set()
    for name, e in form.where:
        assert {s for s in dag.free_symbols(e) if s.name.startswith("u_")} <= defined
        defined.add(name)
    assert all(tree_size([e], 10**6) <= INLINE_MAX or e.is_Add for _, e in form.where)
    # linear: no more names than distinct subexpressions
    assert len(form.where) <= dag.size(exprs)


def test_an_exponential_tree_gets_a_linear_form():
    x, y = sp.symbols("x y")
    e = x
    for _ in range(60):                      # a tree of ~2^60 nodes, a graph of 120
        e = sp.Mul(e, sp.Add(e, y, evaluate=False), evaluate=False)
    form = shared_form([("f", e)])
    assert 20 <= len(form.where) <= 130
    assert len(form.text()) < 10_000
    pt = {x: mpmath.mpf("1.0000001"), y: mpmath.mpf("0.5")}
    assert mpmath.almosteq(_values(form, pt)[0], dag.evaluate(e, pt), 1e-20)


def test_equal_subexpressions_built_apart_get_one_name():
    """Two principles' equations hold equal subexpressions as distinct objects; each gets
    one name, and equal rows print alike (a 2^60-node tree built twice: no tree is
    ever compared)."""
    x, y = sp.symbols("x y")

    def build():
        e = x
        for _ in range(60):
            e = sp.Mul(e, sp.Add(e, y, evaluate=False), evaluate=False)
        return e

    e1 = build()
    sp.core.cache.clear_cache()              # else sympy's cache hands out the same objects
    e2 = build()
    apart = e1 is not e2 and e1.args[0] is not e2.args[0]
    assert apart                             # (no tree in an assert: pytest would print it)
    one = len(shared_form([("f", e1)]).where)
    F = sp.Function("F")
    two = shared_form([("f", e1), ("g", e2), ("h", sp.Add(F(e2), y, evaluate=False))])
    rows = [str(r[1]) for r in two.rows]
    # the same names as one tree alone, plus the whole tree (used in h too)
    assert len(two.where) == one + 1 and rows[0] == rows[1] and rows[2] == f"y + F({rows[0]})"
    pt = {x: mpmath.mpf("1.0000001"), y: mpmath.mpf("0.5")}
    a, b = _values(shared_form([("f", e1), ("g", e2)]), pt)
    close = a == b and mpmath.almosteq(a, dag.evaluate(e2, pt), 1e-20)
    assert close


def test_small_results_are_shown_flat_and_names_avoid_the_symbols():
    u1, x = sp.symbols("u_1 x")
    form = shared_form([("f", x**2 + 1)])
    assert form.where == [] and form.text() == "  f = x**2 + 1"
    big = sp.Add(*[sp.sin(x + i) * (x + u1) ** i for i in range(300)])
    form = shared_form([("g", big), ("h", big * x)])
    assert form.where and not any(n.name.startswith("u_") for n, _ in form.where)


@pytest.mark.parametrize("budget", [500, 3_000, 20_000])
def test_every_format_stays_within_its_budget_and_counts_what_it_leaves_out(
        trailer_acc, budget):
    form = shared_form(["accelerations"] + list(trailer_acc.items()))
    full = form.text()
    assert len(full) > 20_000
    for text in (form.text(budget), form.latex(budget=budget),
                 json.dumps(form.as_dict(budget))):
        assert len(text) <= budget + 300
    assert "more named quantities" in form.text(budget)
    data = form.as_dict(budget)
    kept = len(data.get("accelerations", {})) + len(data["where"])
    assert kept + data["omitted"]["rows"] + data["omitted"]["where"] == (
        len(trailer_acc) + len(form.where))
    whole = form.as_dict()
    assert "omitted" not in whole and len(whole["where"]) == len(form.where)
    assert list(whole["accelerations"]) == [str(q) for q in trailer_acc]


@given(jst.jet_spaces(min_n=2, max_n=3).flatmap(
    lambda J: st.lists(jst.jet_expressions(J, max_depth=3), min_size=1, max_size=3)))
def test_random_expressions_keep_their_values(exprs):
    # chained so that they share parts, and small limits so that names appear
    chain = [exprs[0]]
    for e in exprs[1:]:
        chain.append(e * chain[-1] + chain[-1] ** 2)
    form = shared_form([(f"e{i}", e) for i, e in enumerate(chain)], flat_max=0,
                       inline_max=6, shared_min=3)
    pt = _point(chain, seed=1)
    for a, b in zip(_values(form, pt), dag.evaluate(chain, pt)):
        assert abs(a - b) <= 1e-20 * (1 + abs(b))


def test_equations_str_latex_and_displays_use_the_shared_form():
    eom = models.get("n_trailer", N=8).equations("vakonomic")
    text, tex = str(eom), eom.latex()
    assert len(text) <= 21_000 and "more named quantities" in text
    assert r"\text{where}" in tex and "more" not in tex      # latex() is complete
    assert len(tex) < 500_000
    c = jn.compare(models.get("n_trailer", N=3), "vakonomic", "suslov")
    assert len(c._repr_latex_()) <= 20_000 and "Delta_" in c._repr_html_()
