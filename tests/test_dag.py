"""Tests of jetnh.dag: graph walks agree with sympy's tree walks, and stay linear on
expressions whose tree is exponential."""

from __future__ import annotations

import sympy as sp
from hypothesis import given, strategies as st

import jetnh.strategies as jst
from jetnh import dag


@st.composite
def expressions(draw):
    J = draw(jst.jet_spaces(min_n=1, max_n=3))
    return J, draw(jst.jet_expressions(J, order=1))


@given(expressions())
def test_walks_agree_with_sympy(case):
    J, e = case
    assert dag.free_symbols(e) == e.free_symbols
    assert dag.atoms(e, sp.Symbol) == e.atoms(sp.Symbol)
    assert dag.atoms(e, sp.sin, sp.cos) == e.atoms(sp.sin, sp.cos)
    rule = {s: sp.Integer(i + 2) for i, s in enumerate(sorted(e.free_symbols, key=str))}
    assert dag.xreplace(e, rule) == e.xreplace(rule)
    point = {s: sp.Float(0.3 + 0.17 * i, 30) for i, s in enumerate(sorted(e.free_symbols, key=str))}
    ref = complex(e.xreplace(point).evalf(30))
    assert abs(complex(dag.evaluate(e, point)) - ref) <= 1e-25 * max(1.0, abs(ref))
    tree = list(sp.preorder_traversal(e))        # equal nodes may be distinct objects
    assert len(set(tree)) <= dag.size(e) <= len(tree)


def test_nested_expression_of_exponential_tree_size():
    """x_k = cos(t) * x_(k-1) + sin(t) * x_(k-2): a tree of ~1.6^k nodes, a graph of ~6k."""
    t, a, b = sp.symbols("t a b")
    xs = [a, b]
    for _ in range(60):
        xs.append(sp.cos(t) * xs[-1] + sp.sin(t) * xs[-2])
    e = xs[-1]
    assert dag.size(e) < 500
    assert dag.free_symbols(e) == {t, a, b}
    v = dag.xreplace(e, {a: sp.Integer(0), b: sp.Integer(1), t: sp.Integer(0)})
    assert v == 1                               # at t = 0 every x_k is x_(k-1), so b
    at = {a: 0.5, b: 0.25, t: sp.Rational(1, 3)}
    assert abs(dag.evaluate(xs[12], at) - xs[12].xreplace(at).evalf(30)) < 1e-25


def test_substitution_makes_equal_results_one_object():
    """Two chains of exponential tree size in different symbols, made equal by the rule:
    the rebuilt chain is the other chain's object at every level (so sympy never compares
    them as trees: their difference cancels at once), also across calls sharing ``canon``."""
    t, a, b, c, d = sp.symbols("t a b c d")

    def chain(u, v, n=40):
        xs = [u, v]
        for _ in range(n):
            xs.append(sp.cos(t) * xs[-1] + sp.sin(t) * xs[-2])
        return xs

    xs, ys = chain(a, b), chain(c, d)
    rule = {c: a, d: b}
    x, y = dag.xreplace([xs[-1], ys[-1]], rule)
    assert x is xs[-1] and y is xs[-1]
    assert dag.xreplace(xs[-1] - ys[-1], rule) == 0
    canon: dict = {}
    first = dag.xreplace(xs[-1], {a: c}, canon)
    again = dag.xreplace(ys[-1], {d: b}, canon)
    assert first is again and first is not xs[-1]
    assert dag.free_symbols(first) == {t, c, b}


def test_tree_size_counts_the_tree_on_the_graph():
    """tree_size is what a tree walk visits (sympy's preorder_traversal), counted in time
    linear in the graph, and capped."""
    x, y = sp.symbols("x y")
    e = x + y
    for _ in range(4):
        e = sp.sin(e) * e + e**2
    assert dag.tree_size(e) == sum(1 for _ in sp.preorder_traversal(e))
    assert dag.tree_size([e, x]) == dag.tree_size(e) + 1
    deep = x + y
    for _ in range(60):                    # 3^60 tree nodes
        deep = sp.sin(deep) * deep + deep**2
    assert dag.tree_size(deep, cap=10**6) == 10**6 + 1
