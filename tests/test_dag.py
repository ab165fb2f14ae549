"""Tests of jetnh.algebra.dag: graph walks agree with sympy's tree walks, and stay linear on
expressions whose tree is exponential."""

from __future__ import annotations

import pickle

import numpy as np
import pytest
import sympy as sp
from hypothesis import given, strategies as st

import jetnh.strategies as jst
from jetnh.algebra import dag


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
    for what in ((sp.sin,), (sp.exp, sp.Pow), (J.t,), (J.q[0], sp.I)):
        assert dag.has(e, *what) == e.has(*what)
    rule = {s: sp.Integer(i + 2) for i, s in enumerate(sorted(e.free_symbols, key=str))}
    assert dag.xreplace(e, rule) == e.xreplace(rule)
    point = {s: sp.Float(0.3 + 0.17 * i, 30) for i, s in enumerate(sorted(e.free_symbols, key=str))}
    ref = complex(e.xreplace(point).evalf(30))
    assert abs(complex(dag.evaluate(e, point)) - ref) <= 1e-25 * max(1.0, abs(ref))
    arrays = {s: [float(v), float(v) / 2] for s, v in point.items()}
    half = complex(e.xreplace({s: v / 2 for s, v in point.items()}).evalf(30))
    got = np.broadcast_to(dag.evaluate_numpy([e], arrays)[0], (2,))     # a constant: a scalar
    assert abs(got[0] - ref) <= 1e-12 * max(1.0, abs(ref))
    assert abs(got[1] - half) <= 1e-12 * max(1.0, abs(half))
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


@given(expressions(), st.integers(0, 3))
def test_a_memo_carries_a_substitution_over_calls(case, split):
    """xreplace over several calls sharing a memo (and canon) gives what one call over
    all of them gives, and what sympy gives; parts met again are the same objects."""
    J, e = case
    parts = [e, *e.args[:split], e + J.t]
    rule = {s: sp.Symbol(f"r_{s}") for s in e.free_symbols}
    rule.update({J.t: sp.Integer(2)})
    memo, canon = {}, {}
    one_by_one = [dag.xreplace(x, rule, canon, memo) for x in parts]
    assert one_by_one == dag.xreplace(parts, rule) == [x.xreplace(rule) for x in parts]
    assert dag.xreplace(e, rule, canon, memo) is one_by_one[0]


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


# ------------------------------------------------------------------------ derivatives
def _close(a, b, point, dps=40):
    """a and b agree at ``point`` to ``dps - 10`` digits (evaluated on their graphs)."""
    va, vb = dag.evaluate([a, b], point, dps=dps)
    return abs(va - vb) <= sp.Float(10) ** (10 - dps) * max(1, abs(vb))


@st.composite
def nested(draw):
    """A random expression and a chain of products and sums nested on it: a graph whose
    parts are shared by several parents (its tree grows exponentially with the depth)."""
    J = draw(jst.jet_spaces(min_n=1, max_n=3))
    parts = [draw(jst.jet_expressions(J, order=1, max_depth=2)) for _ in range(2)]
    for op in draw(st.lists(st.sampled_from("+*/s"), min_size=0, max_size=5)):
        a, b = parts[-1], parts[-2]
        parts.append({"+": lambda: a + b, "*": lambda: a * b, "/": lambda: a / (2 + b**2),
                      "s": lambda: sp.sin(a) * b}[op]())
    return J, parts[-1]


@given(nested(), st.data())
def test_diff_agrees_with_sympy_at_random_points(case, data):
    """dag.diff = sympy.diff (first and second derivatives), at random points, 40 digits."""
    J, e = case
    syms = sorted(dag.free_symbols(e) | {J.t, J.qd[0]}, key=lambda s: s.name)
    x, y = data.draw(st.sampled_from(syms)), data.draw(st.sampled_from(syms))
    point = {s: sp.Rational(data.draw(st.integers(11, 97)), 37) for s in syms}
    cache: dict = {}
    d1 = dag.diff(e, x, cache=cache)
    assert _close(d1, sp.diff(e, x), point)
    assert _close(dag.diff(e, x, y, cache=cache), sp.diff(e, x, y), point)
    assert dag.diff(e, x, cache=cache) is d1                  # from the cache
    jac = dag.jacobian([e, x * e], [x, y])
    assert _close(jac[1, 0], e + x * d1, point)


@given(nested())
def test_a_shared_cache_gives_the_same_derivatives(case):
    """With a cache shared by every symbol, subexpressions without the symbol are not
    walked: the derivatives are the very expressions of separate calls, zero where the
    symbol is absent."""
    J, e = case
    cache: dict = {}
    for x in (J.t, *J.q, *J.qd, sp.Symbol("absent")):
        d = dag.diff(e, x, cache=cache)
        assert d == dag.diff(e, x) and d.args == dag.diff(e, x).args
        if x not in dag.free_symbols(e):
            assert d is sp.S.Zero


def test_diff_is_sympy_diff_on_small_expressions():
    """The same rules as sympy: on tree-shaped input the very same expressions."""
    x, y = sp.symbols("x y")
    f = sp.Function("f")
    for e in (x**2 * sp.sin(x * y), sp.exp(x) / (1 + y * x) ** sp.Rational(3, 2), x**y,
              sp.atan2(y, x) * sp.Abs(x), f(x, x * y), sp.sqrt(1 + sp.cos(x) ** 2) / y):
        assert dag.diff(e, x) == sp.diff(e, x)
        assert dag.diff(e, x, y) == sp.diff(sp.diff(e, x), y)
    assert dag.diff(x * y, sp.Symbol("z")) == 0
    with pytest.raises(TypeError, match="Symbols"):
        dag.diff(x, f(x))


def test_diff_of_nested_expression_stays_shared():
    """x_k = cos(t) x_(k-1) + sin(t) x_(k-2), 60 deep: ~1.6^60 tree nodes.  Its derivative
    is a graph of size linear in k (sympy.diff would walk the tree), and its value at a
    point is the derivative of the recursion, computed by dual numbers."""
    t, a, b = sp.symbols("t a b")
    xs = [a, b]
    for _ in range(60):
        xs.append(sp.cos(t) * xs[-1] + sp.sin(t) * xs[-2])
    d = dag.diff(xs[-1], t)
    assert dag.size(d) < 20 * dag.size(xs[-1])
    at = {a: sp.Rational(1, 2), b: sp.Rational(1, 4), t: sp.Rational(1, 3)}
    import mpmath
    with mpmath.workdps(40):
        c, s = mpmath.cos(mpmath.mpf(1) / 3), mpmath.sin(mpmath.mpf(1) / 3)
        v = [(mpmath.mpf(1) / 2, 0), (mpmath.mpf(1) / 4, 0)]     # (value, d/dt)
        for _ in range(60):
            (u, du), (w, dw) = v[-1], v[-2]
            v.append((c * u + s * w, -s * u + c * du + c * w + s * dw))
        assert abs(dag.evaluate(d, at, dps=40) - v[-1][1]) < 1e-30 * abs(v[-1][1])


def test_numbers_among_the_roots_and_missing_symbols():
    """Plain numbers are roots like any other; a symbol without a value is named, with
    the fix, by a JetnhError that is still a ValueError."""
    from jetnh.errors import ArgumentError, JetnhError

    x, y = sp.symbols("x y")
    assert dag.evaluate([x + 1, 2.5], {x: 1}) == [2, 2.5]
    assert dag.evaluate(3, {}) == 3
    assert list(dag.evaluate_numpy([x, 3], {x: [1.0, 2.0]})[0]) == [1.0, 2.0]
    assert dag.xreplace([x, 2.5], {x: y}) == [y, sp.Float(2.5)]
    assert dag.tree_size([x + y, 2.5]) == 4
    for call in (lambda: dag.evaluate([x + y, 2.5], {x: 1}),
                 lambda: dag.evaluate_numpy(x * y, {x: 1.0})):
        with pytest.raises(ArgumentError, match=r"no value for y in the point.*give every") as err:
            call()
        assert isinstance(err.value, JetnhError) and isinstance(err.value, ValueError)
    with pytest.raises(ArgumentError, match=r"no value for x, y in the point"):
        dag.evaluate(sp.sin(x) + y, {})


@given(expressions(), expressions())
def test_fingerprint_is_structural_equality(a, b):
    """Equal expressions (however shared) have one fingerprint; different ones differ
    (sympy's canonical trees decide what is equal, as srepr did)."""
    (_, ea), (_, eb) = a, b
    rebuilt = pickle.loads(pickle.dumps(ea))       # new objects, other sharing
    assert dag.fingerprint(ea) == dag.fingerprint(rebuilt)
    assert (dag.fingerprint(ea) == dag.fingerprint(eb)) == (sp.srepr(ea) == sp.srepr(eb))
    assert dag.fingerprint([ea, eb]) != dag.fingerprint([eb, ea]) or \
        sp.srepr(ea) == sp.srepr(eb)


def test_fingerprint_sees_assumptions_sharing_and_order():
    x, y = sp.symbols("x y")
    xp = sp.Symbol("x", positive=True)
    assert dag.fingerprint(sp.cos(x) + y) != dag.fingerprint(sp.cos(xp) + y)
    shared = sp.cos(x) ** 2
    assert dag.fingerprint(shared * shared + 1) == dag.fingerprint(
        sp.cos(x) ** 2 * sp.cos(x) ** 2 + 1)
    assert dag.fingerprint([x, y]) != dag.fingerprint([y, x])
    assert dag.fingerprint([x - y]) != dag.fingerprint([y - x])


_ATOMS = [sp.Integer(2), sp.Integer(-1), sp.Rational(1, 3), sp.Float(0.1), sp.Float(1.0),
          sp.S.Zero, sp.S.One, sp.pi, sp.E, sp.I, sp.sqrt(2), sp.oo, sp.zoo]


@st.composite
def children(draw):
    """Children for a sum or product: parts of random expressions, numbers, and their
    sums, products, powers and exponentials (so terms and bases repeat now and then)."""
    J = draw(jst.jet_spaces(min_n=1, max_n=3))
    pool = [draw(jst.jet_expressions(J, order=1, max_depth=2)) for _ in range(3)]
    pool += [a for e in pool for a in e.args] + list(J.q) + _ATOMS
    pick = st.sampled_from(pool)
    out = []
    for kind in draw(st.lists(st.sampled_from("a+*^e-"), min_size=0, max_size=6)):
        a, b = draw(pick), draw(pick)
        out.append({"a": lambda: a, "+": lambda: a + b, "*": lambda: a * b,
                    "^": lambda: a ** draw(st.sampled_from([2, -1, sp.Rational(1, 2), b])),
                    "e": lambda: sp.exp(a), "-": lambda: -a}[kind]())
    return out


@given(children(), st.sampled_from([sp.Add, sp.Mul]))
def test_build_is_sympys_constructor(args, head):
    """``build`` makes the object sympy's constructor makes, children in the same order,
    also where it leaves the work to sympy (numbers, repeated terms, nested sums ...)."""
    want = head(*args)
    got = dag.build(head, args)
    assert type(got) is type(want)
    assert got == want
    assert got.args == want.args


_RATIONALS = [sp.Integer(2), sp.Integer(-1), sp.Rational(1, 2), sp.Rational(-3, 2), sp.S.Zero,
              sp.S.One]


@given(children(), st.sampled_from(_RATIONALS), st.booleans())
def test_build_distributes_a_number_over_a_sum_as_sympy_does(args, number, one):
    """A rational number times a sum is the sum of the products, built as sympy builds
    it (``Mul.flatten`` distributes; ``build`` makes the same sum itself), ones among the
    factors or not."""
    total = sp.Add(*args)
    factors = [number, sp.S.One, total] if one else [total, number]
    want, got = sp.Mul(*factors), dag.build(sp.Mul, factors)
    assert type(got) is type(want)
    assert got == want
    assert got.args == want.args


@given(children(), st.sampled_from(_RATIONALS))
def test_build_power_of_a_sum_is_sympys(args, exponent):
    """A sum to a rational power is the object sympy makes, also a sum of two terms with
    I or an infinity (which sympy may rewrite)."""
    x = sp.Symbol("x")
    for base in (sp.Add(*args), sp.oo + sp.I * x, sp.I * sp.oo + x, x + sp.I):
        want, got = sp.Pow(base, exponent), dag.build(sp.Pow, [base, exponent])
        assert type(got) is type(want)
        assert got == want
        assert got.args == want.args


def test_collector_paused_restores_the_collector():
    """The garbage collector is off inside ``collector_paused`` (nested too) and as it was
    after, also after an error."""
    import gc

    assert gc.isenabled()
    with pytest.raises(KeyError), dag.collector_paused():
        with dag.collector_paused():
            assert not gc.isenabled()
        assert not gc.isenabled()
        raise KeyError
    assert gc.isenabled()


@pytest.mark.parametrize("number", [2.0, 3, -0.5])
def test_build_takes_python_numbers_as_sympy_does(number):
    """A rule of Python floats in ``xreplace`` hands them to ``build``: sympy converts
    them (it raised AttributeError on float.is_Number)."""
    x, y = sp.symbols("x y")
    for head in (sp.Add, sp.Mul):
        assert dag.build(head, [x, number]) == head(x, number)
    assert dag.xreplace(x * y + y, {x: number}) == (x * y + y).xreplace({x: number})


def test_size_counts_equal_parts_once():
    """Equal subexpressions held by distinct objects count once (the size does not depend
    on how the graph was built); the cap stops the count."""
    x, y = sp.symbols("x y")
    a, b = x + y, sp.Add._from_args((x, y))
    assert a is not b and a == b
    e = sp.Mul._from_args((a, sp.Basic.__new__(sp.sin, b)))
    assert len(dag.nodes(e)) == 6 and dag.size(e) == 5      # x, y, x + y, sin, the product
    assert dag.size(e, cap=2) == 2


@given(children(), children())
def test_compare_is_sympys_order(left, right):
    """``_compare`` answers as ``Basic.compare`` for every pair (sums, products, powers,
    functions, numbers; a FiniteSet inside keeps its own order), so ``build`` sorts as
    sympy's constructor does."""
    pool = left + right + [sp.Tuple(*left[:2], sp.FiniteSet(*right[:2]))]
    for a in pool:
        for b in pool:
            assert dag._compare(a, b) == sp.Basic.compare(a, b)


class _Once(sp.Symbol):
    """A symbol whose products keep one of its kind (a constructor postprocessor)."""


def _keep_one(expr):
    kept = [a for a in expr.args if isinstance(a, _Once)]
    return sp.Mul._from_args([a for a in expr.args if not isinstance(a, _Once)] + kept[:1])


def test_build_runs_sympys_constructor_postprocessors():
    """A postprocessor a child's class registers (after ``build`` has met the head) is
    run by ``build`` as by sympy's constructor, and no longer once unregistered."""
    x, y = sp.symbols("x y")
    assert dag.build(sp.Mul, [x, y]) == x * y
    a, b = _Once("a"), _Once("b")
    sp.Basic._constructor_postprocessor_mapping[_Once] = {"Mul": [_keep_one]}
    try:
        want = sp.Mul(x, a, b)
        got = dag.build(sp.Mul, [x, a, b])
        assert len(want.args) == 2 and got == want and got.args == want.args
    finally:
        del sp.Basic._constructor_postprocessor_mapping[_Once]
    sp.core.cache.clear_cache()          # sympy's lookup of them is cached too
    assert dag.build(sp.Mul, [x, a, b]).args == sp.Mul(x, a, b).args == (x, a, b)


@st.composite
def nested_children(draw):
    """Children that are themselves sums and products (with rational and float
    coefficients, repeated terms now and then), as matrix products and solves make them."""
    x, y, z = sp.symbols("x y z")
    atoms = [x, y, z, sp.sin(x), sp.cos(y), x**2, 1 / z, sp.pi, sp.Rational(1, 2), sp.Integer(-3),
             sp.Float(0.25), sp.Integer(2)]
    pick = st.sampled_from(atoms)

    def part():
        head = draw(st.sampled_from([sp.Add, sp.Mul, None]))
        if head is None:
            return draw(pick)
        return head(*draw(st.lists(pick, min_size=2, max_size=4)))
    return [part() for _ in range(draw(st.integers(0, 5)))]


@given(nested_children(), st.sampled_from([sp.Add, sp.Mul]))
def test_build_takes_nested_sums_and_products_apart_as_sympy(args, head):
    """Sums of sums and products of products: ``build`` (taking the children apart
    itself where nothing combines) makes sympy's object, children in the same order."""
    want, got = head(*args), dag.build(head, args)
    assert type(got) is type(want)
    assert got == want
    assert got.args == want.args


@given(nested_children(), nested_children())
def test_arithmetic_is_sympys_operators(left, right):
    """``mul``, ``add``, ``sub`` and ``div`` make the objects of sympy's ``*``, ``+``, ``-``
    and ``/`` (the same children in the same order), numbers among the operands too."""
    for a in left + [sp.S.One, sp.S.Zero]:
        for b in right + [sp.S.One, sp.Integer(-1), sp.Rational(2, 3)]:
            for got, want in ((dag.mul(a, b), a * b), (dag.add(a, b), a + b),
                              (dag.sub(a, b), a - b), (dag.div(a, b), a / b)):
                assert type(got) is type(want)
                assert got == want
                assert got.args == want.args


def test_build_takes_apart_what_sympy_would_and_leaves_it_the_rest():
    """The rules taken one by one: nested products and sums are taken apart directly,
    their rational numbers combined; a rational beside a number times a sum (sympy's
    two-argument rule), a repeated base, a float beside a rational are left to sympy."""
    x, y, z = sp.symbols("x y z")
    assert dag._mul_factors((x, -2 * y * z)) is not None
    assert dag._mul_factors((-x, -2 * y * z))[0] == 2
    assert dag._mul_factors((sp.Integer(3), sp.Mul(2, x + y, evaluate=False))) is None
    assert dag._mul_factors((sp.Integer(3), 2 * x * y)) is not None
    assert dag._mul_factors((x, 2 * x * y)) is None
    assert dag._mul_factors((sp.Float(0.5) * x, 2 * y)) is None
    assert dag._add_terms((x + 1, y - 1)) == (None, [x, y])
    assert dag._add_terms((x + y, 2 * x)) is None
    for head, args in ((sp.Mul, (sp.Integer(3), sp.Mul(2, x + y, evaluate=False))),
                       (sp.Mul, (-x, -y)), (sp.Add, (x + 1, y - 1)),
                       (sp.Add, (x + y, 2 * z + sp.Float(0.5)))):
        assert dag.build(head, args).args == head(*args).args
