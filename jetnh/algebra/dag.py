"""Expressions as shared graphs: size, free symbols, atoms, substitution, derivatives and
numeric evaluation in time linear in the number of *distinct* subexpressions.

Solved equations share their subexpressions (the accelerations of a chain of k
constraints nest k solves), so as trees they are exponentially larger than as graphs.
sympy's ``free_symbols``, ``atoms``, ``has`` and ``xreplace`` walk the tree; these walk
the graph once, remembering every node they have seen (by identity).

``sympy_object`` is the one door from a user's value into sympy (never from a string).
"""

from __future__ import annotations

import contextlib
import functools
import gc
import hashlib
import operator

import mpmath
import sympy as sp
from sympy.core.basic import Basic, _cmp_name, _get_postprocessors
from sympy.core.function import ArgumentIndexError
from sympy.core.mul import _keep_coeff
from sympy.core.parameters import global_parameters
from sympy.functions.elementary.exponential import ExpBase

from ..errors import ArgumentError, JetSpaceError


def sympy_object(expr) -> sp.Basic:
    """A sympy object from a user's value, never from a string (sympify would execute
    it); anything else that is not one is a ``JetSpaceError``."""
    if isinstance(expr, str):
        raise JetSpaceError(
            f"got the string {expr!r}; jetnh never parses strings here (that would execute "
            "code). Build expressions from the Symbols of the jet space (J.q, J.qd, ...)")
    try:
        return sp.sympify(expr, strict=True)
    except (sp.SympifyError, TypeError) as exc:
        raise JetSpaceError(f"{expr!r} is not a sympy expression: {exc}") from None


@contextlib.contextmanager
def collector_paused():
    """Python's cyclic garbage collector paused inside the block (as it was after):
    building a graph of millions of sympy objects (acyclic: reference counting frees
    them) otherwise sets off full collections that walk every live object, again and
    again -- a fifth of a large derivation's time.  Cyclic garbage made inside is
    collected after the block."""
    was = gc.isenabled()
    gc.disable()
    try:
        yield
    finally:
        if was:
            gc.enable()


def _roots(expr) -> list:
    """``expr`` (a Basic, a number or a list of them) as a list of sympy objects, each
    converted once: the walks key their results by the identity of these objects."""
    return [sp.sympify(e, strict=True)
            for e in (expr if isinstance(expr, (list, tuple)) else [expr])]


def nodes(expr, cap: int | None = None) -> list:
    """The distinct subexpressions of ``expr`` (a Basic or a list of them), children
    before parents (at most ``cap``)."""
    order, seen, stack = [], set(), [(e, False) for e in reversed(_roots(expr))]
    while stack:
        e, expanded = stack.pop()
        if expanded:
            order.append(e)
            if cap is not None and len(order) >= cap:
                break
            continue
        if id(e) in seen:
            continue
        seen.add(id(e))
        stack.append((e, True))
        stack.extend((a, False) for a in e.args if id(a) not in seen)
    return order


def fingerprint(expr) -> str:
    """A hash (hex) of the structure of ``expr`` (a Basic or a list of them): each distinct
    subtree numbered once, by its head and its children's numbers, symbols by their
    names and assumptions -- equal expressions give equal fingerprints whatever their
    sharing, and the tree is never flattened (``srepr`` would be)."""
    roots = _roots(expr)
    number: dict = {}           # token -> its number, in the order first met
    of: dict = {}               # id(node) -> its number
    h = hashlib.sha256()
    for e in nodes(roots):
        token = (("atom", sp.srepr(e)) if not e.args else
                 (type(e).__name__, tuple(of[id(a)] for a in e.args)))
        if token not in number:
            number[token] = len(number)
            h.update(repr(token).encode() + b"\0")
        of[id(e)] = number[token]
    h.update(repr(tuple(of[id(e)] for e in roots)).encode())
    return h.hexdigest()


def size(expr, cap: int | None = None) -> int:
    """The number of distinct subexpressions (counted up to ``cap``): equal ones count
    once, however many objects hold them, so the count does not depend on how the graph
    was built (sympy's constructor cache, ``build``)."""
    number: dict = {}           # (head, children's numbers) or atom -> its number
    of: dict = {}               # id(node) -> its number
    stack = [(e, False) for e in reversed(_roots(expr))]
    while stack:
        e, expanded = stack.pop()
        if id(e) in of:
            continue
        if not expanded and e.args:
            stack.append((e, True))
            stack.extend((a, False) for a in e.args if id(a) not in of)
            continue
        key = (type(e), e) if not e.args else (e.func, tuple(of[id(a)] for a in e.args))
        of[id(e)] = number.setdefault(key, len(number))
        if cap is not None and len(number) >= cap:
            break
    return len(number)


def tree_size(expr, cap: int | None = None) -> int:
    """The number of nodes of ``expr`` (a Basic or a list) as a tree -- what a tree walk
    (``sympy.cse``, printing) visits -- counted on the graph; ``cap + 1`` once above
    ``cap``."""
    count: dict = {}
    roots = _roots(expr)
    for e in nodes(roots):
        n = 1 + sum(count[id(a)] for a in e.args)
        count[id(e)] = n if cap is None else min(n, cap + 1)
    total = sum(count[id(e)] for e in roots)
    return total if cap is None else min(total, cap + 1)


def free_symbols(expr) -> set:
    """The free symbols (Symbols among the atoms; no bound variables are expected)."""
    return {e for e in nodes(expr) if isinstance(e, sp.Symbol)}


def atoms(expr, *types) -> set:
    """The subexpressions that are instances of ``types``."""
    return {e for e in nodes(expr) if isinstance(e, types)}


def has(expr, *what) -> bool:
    """``expr.has(*what)`` for types and objects (no patterns), on the graph."""
    types = tuple(w for w in what if isinstance(w, type))
    objs = {w for w in what if not isinstance(w, type)}
    seen, stack = set(), _roots(expr)      # stops at the first one found
    while stack:
        e = stack.pop()
        if id(e) in seen:
            continue
        if isinstance(e, types) or e in objs:
            return True
        seen.add(id(e))
        stack.extend(a for a in e.args if id(a) not in seen)
    return False


def build(head, args):
    """``head(*args)`` (a sympy head and its children), with sums and products whose
    children combine with nothing put together directly: sympy's ``flatten`` there only
    sorts the children (``Basic.compare``) after checking every pair of them for terms
    or powers to merge, which costs most of rebuilding a large graph (a substitution, a
    conversion from symengine, a matrix product).  The result is the object sympy
    builds, arguments in the same order; a nested sum or product is taken apart as
    sympy's ``flatten`` does, and any child that could combine or expand (a number
    beyond rational coefficients, a repeated term or base, a power of a number, an
    exponential, anything non-commutative or unusual, a Python number that sympy would
    convert: ``xreplace`` with a rule of floats) leaves it to sympy.  Likewise a rational
    number times a sum, which sympy distributes (``_distributed``: the sum of the
    products is built here), and a sum to a rational power, which sympy leaves as it is
    after costly questions (``_plain_power``)."""
    out = _direct(head, args)
    return head(*args) if out is None else out


def _direct(head, args):
    """``build(head, args)`` where it does not leave the work to sympy, else None."""
    if not global_parameters.evaluate:
        return None
    if head is sp.Add:
        kept = _add_terms(args)
    elif head is sp.Mul:
        kept = _mul_factors(args)
        if kept is None:
            terms = _distributed(args)
            if terms is not None:
                return build(sp.Add, terms)
    elif head is sp.Pow and _plain_power(*args):
        return sp.Pow(*args, evaluate=False)
    else:
        return None
    if kept is None:
        return None
    coeff, rest = kept
    if not rest:
        return head.identity if coeff is None else coeff
    if coeff is None and len(rest) == 1:
        return rest[0]
    rest.sort(key=_SORT_KEY)
    if coeff is not None:
        rest.insert(0, coeff)
    obj = head._from_args(rest, True)
    return head._exec_constructor_postprocessors(obj) if _postprocessed(head, rest) else obj


def mul(a, b):
    """``a * b`` for sympy expressions: the object sympy's operator makes (``build``
    where it applies)."""
    if not (a.is_Number and b.is_Number):
        out = _direct(sp.Mul, (a, b))
        if out is not None:
            return out
    return a * b


def add(a, b):
    """``a + b`` for sympy expressions (as ``mul``)."""
    if not (a.is_Number and b.is_Number):
        out = _direct(sp.Add, (a, b))
        if out is not None:
            return out
    return a + b


def sub(a, b):
    """``a - b`` for sympy expressions, i.e. ``a + (-b)`` (as ``mul``)."""
    if not (a.is_Number and b.is_Number):
        out = _direct(sp.Add, (a, -b))
        if out is not None:
            return out
    return a - b


def div(a, b):
    """``a / b`` for sympy expressions, i.e. ``a * b**-1`` (as ``mul``)."""
    if not a.is_Number:
        out = _direct(sp.Mul, (a, sp.Pow(b, sp.S.NegativeOne)))
        if out is not None:
            return out
    return a / b


#: (head, type of a child) -> whether sympy has constructor postprocessors for them
#: (``_postprocessed``), and the registry's size they were looked up at
_POST: dict = {}
_POST_AT = [-1]


def _postprocessed(head, args) -> bool:
    """Whether sympy's constructor would run a postprocessor on ``head(*args)`` (some
    child's type registers one for ``head``): looked up once per (head, type), not
    through sympy's cache for every child of every node."""
    registry = Basic._constructor_postprocessor_mapping
    if _POST_AT[0] != len(registry):
        _POST.clear()
        _POST_AT[0] = len(registry)
    for a in args:
        key = (head, type(a))
        found = _POST.get(key)
        if found is None:
            found = _POST[key] = bool(_get_postprocessors(head.__name__, type(a)))
        if found:
            return True
    return False


#: (class, class) -> the order of their names in ``Basic.compare`` (``_compare``)
_CLASS_ORDER: dict = {}
#: class -> whether it keeps ``Basic.compare`` (``_compare``)
_PLAIN: dict = {}


def _compare(a, b) -> int:
    """``Basic.compare(a, b)``, sympy's canonical order of a sum's terms and a product's
    factors, the same answer for every pair: the order of two classes is looked up
    (not found by name in sympy's list each time), the contents compared in a loop."""
    if a is b:
        return 0
    ta, tb = type(a), type(b)
    if ta is not tb:
        c = _CLASS_ORDER.get((ta, tb))
        if c is None:
            c = _CLASS_ORDER[ta, tb] = _cmp_name(ta, tb)
        if c:
            return c
    st, ot = a._hashable_content(), b._hashable_content()
    if len(st) != len(ot):
        return 1 if len(st) > len(ot) else -1
    for x, y in zip(st, ot):
        if x is y:
            continue
        if isinstance(x, Basic):
            plain = _PLAIN.get(type(x))
            if plain is None:
                plain = _PLAIN[type(x)] = type(x).compare is Basic.compare
            c = _compare(x, y) if plain else x.compare(y)     # FiniteSet: its own
        elif isinstance(x, frozenset):
            c = Basic(*x).compare(Basic(*y) if isinstance(y, frozenset) else y)
        else:
            c = (x > y) - (x < y)
        if c:
            return c
    return 0


_SORT_KEY = functools.cmp_to_key(_compare)


def _combined(coeff, a, op):
    """The number ``coeff op a`` of ``_add_terms`` / ``_mul_factors`` (``a`` alone where
    ``coeff`` is None): two rational numbers combined; None where sympy must combine them
    (a float, an infinity, a zero ``a``)."""
    if not a.is_finite or a.is_zero:
        return None
    if coeff is None:
        return a
    return op(coeff, a) if coeff.is_Rational and a.is_Rational else None


def _add_terms(args):
    """The number and the other children of ``Add(*args)`` (unsorted) when no two terms
    combine (``build``), else None.  A nested sum's terms come after the other children,
    as in ``Add.flatten``; rational numbers are added up."""
    coeff, rest, terms, nested = None, [], set(), []
    for seq in (args, nested):
        for a in seq:
            if a is sp.S.Zero:
                continue
            if not isinstance(a, sp.Basic):     # a Python number: sympy converts it
                return None
            if a.is_Number:
                coeff = _combined(coeff, a, operator.add)
                if coeff is None:
                    return None
                continue
            if not a.is_commutative:
                return None
            if a.is_Add:
                nested.extend(a.args)
                continue
            if a.is_Mul:         # the term without its number (``as_coeff_Mul``), as
                fs = a.args      # its factors: no product is built to be compared
                if not fs[0].is_Number:
                    s = fs
                elif len(fs) > 2:
                    s = fs[1:]
                else:
                    s = fs[1]
                    if fs[0] is not sp.S.One and not _plain(s):
                        return None
            elif a.is_Symbol or a.is_NumberSymbol or isinstance(a, sp.Function) or (
                    a.is_Pow and not a.base.is_Number):
                s = a
            else:
                return None
            if s in terms:
                return None
            terms.add(s)
            rest.append(a)
    return (None if coeff is not None and coeff.is_zero else coeff), rest


def _mul_factors(args):
    """The number and the other children of ``Mul(*args)`` (unsorted) when no two
    factors combine (``build``), else None.  A nested product's factors come after the
    other children, as in ``Mul.flatten`` (not beside a lone rational number, sympy's
    two-argument rule); rational numbers are multiplied."""
    coeff, rest, bases, nested = None, [], set(), []
    for seq in (args, nested):
        for a in seq:
            if a is sp.S.One:
                continue
            if not isinstance(a, sp.Basic):     # a Python number: sympy converts it
                return None
            if a.is_Number:
                coeff = _combined(coeff, a, operator.mul)
                if coeff is None:
                    return None
                continue
            if not a.is_commutative:
                return None
            if a.is_Pow:
                b = a.base
                if b.is_Number:
                    return None
            elif a.is_Mul:
                if not nested and _two_rational(args):
                    return None
                nested.extend(a.args)
                continue
            elif a.is_Symbol or a.is_NumberSymbol or a.is_Add or (
                    isinstance(a, sp.Function) and not isinstance(a, ExpBase)):
                b = a
            else:
                return None
            if b in bases:
                return None
            bases.add(b)
            rest.append(a)
    if coeff is sp.S.One:
        coeff = None
    if coeff is not None and len(rest) == 1 and rest[0].is_Add:
        return None                     # a number times a sum is distributed
    return coeff, rest


def _two_rational(args) -> bool:
    """Whether ``Mul.flatten``'s rule for two children (ones aside) applies: a rational
    number and a number times a sum, which it leaves unevaluated."""
    rest = [a for a in args if a is not sp.S.One]
    if len(rest) != 2 or not all(isinstance(a, sp.Basic) for a in rest):
        return False
    a, b = rest
    if b.is_Rational:
        a, b = b, a
    return a.is_Rational and b.as_coeff_Mul()[1].is_Add


def _distributed(args):
    """The terms of ``Mul(*args)`` when sympy distributes a rational number over a sum
    (``Mul.flatten``: two factors besides ones, a rational and a sum with coefficient
    one), each the number times a term (``_keep_coeff``, as sympy), else None: the sum
    of them is then built as any other (``build``), not by ``Add.flatten``."""
    rest = [a for a in args if a is not sp.S.One]
    if len(rest) != 2 or not all(isinstance(a, sp.Basic) for a in rest):
        return None
    a, b = rest
    if b.is_Rational:
        a, b = b, a
    if not a.is_Rational or a.is_zero:
        return None
    r, b = b.as_coeff_Mul()
    if r is not sp.S.One or not b.is_Add or not global_parameters.distribute or (
            not b.is_commutative):
        return None
    return [_keep_coeff(a, t) for t in b.args]


def _plain_power(base, exp) -> bool:
    """Whether sympy leaves ``base**exp`` as it is (``Pow.__new__``): a sum not a
    number to a rational power but 0 and 1, which ``Add._eval_power`` rewrites only for
    two terms, one infinite, the other a multiple of I -- whose asking (``is_infinite``
    of each term, an assumptions query through the whole term) is what costs: with no
    I in the sum it is not asked."""
    return (isinstance(base, sp.Add) and isinstance(exp, sp.Rational)
            and exp is not sp.S.Zero and exp is not sp.S.One and not base.is_number
            and (len(base.args) != 2 or not has(base, sp.I)))


def _plain(e) -> bool:
    """``e`` is a symbol, a function or a power of something not a number."""
    return e.is_Symbol or (e.is_Pow and not e.base.is_Number) or (
        isinstance(e, sp.Function) and not isinstance(e, ExpBase))


#: the key in ``xreplace``'s ``canon`` of the nodes it built, by head and children
_BUILT = object()


def xreplace(expr, rule: dict, canon: dict | None = None, memo: dict | None = None):
    """``expr.xreplace(rule)``, rebuilding each distinct subexpression once; ``expr``
    may be a list, whose shared parts are then rebuilt once for all (a list returned).

    Equal results are made one object (hash-consed, children first): the substitution
    can make distinct subexpressions equal (parameters set to the same number), and
    sympy compares equal, non-identical objects by walking their trees -- exponentially
    long for nested solves -- whenever it meets them in a cache or a sum's terms.
    ``canon`` (object -> itself) carries the one objects over several calls (results of
    one call equal to those of another are then the same object too), and the node
    built from each head and canonical children (distinct nodes that become equal are
    built once).  ``memo`` (a dict, filled here) carries the results themselves over
    several calls by the same rule (or rules that agree on every symbol both reach): a
    subexpression met again is not walked or rebuilt again."""
    canon = {} if canon is None else canon
    memo = {} if memo is None else memo     # id(node) -> (node, result, rule reaches it)
    built = canon.setdefault(_BUILT, {})    # (head, ids of canonical children) -> node
    roots = _roots(expr)
    stack = [(e, False) for e in reversed(roots)]
    while stack:
        e, expanded = stack.pop()
        if id(e) in memo:
            continue
        if not expanded and e.args and e not in rule:
            stack.append((e, True))
            stack.extend((a, False) for a in e.args if id(a) not in memo)
            continue
        reached = False
        if e in rule:
            new, reached = rule[e], True
        elif e.args:
            done = [memo[id(a)] for a in e.args]
            args = tuple(d[1] for d in done)
            if any(d[2] for d in done):
                reached = True
                key = (e.func, *map(id, args))      # children: canon's objects
                new = built.get(key)
                if new is None:
                    new = build(e.func, args)
                    new = built[key] = canon.setdefault(new, new)
            elif all(a is b for a, b in zip(args, e.args)):
                new = e
            elif isinstance(e, (sp.Add, sp.Mul)):   # equal children made one: no rewrite
                new = e.func._from_args(args, e.is_commutative)
            else:
                new = e.func(*args)
        else:
            new = e
        memo[id(e)] = (e, canon.setdefault(new, new), reached)
    out = [memo[id(e)][1] for e in roots]
    return out if isinstance(expr, (list, tuple)) else out[0]


def diff(expr, *symbols, cache: dict | None = None):
    """``sympy.diff(expr, *symbols)`` (successive first derivatives by Symbols), each
    distinct subexpression differentiated once: sympy's rules (sum, product, power and
    chain rule through ``fdiff``) applied children first, so the result shares the
    subexpressions of ``expr`` and of the derivatives of its parts; never flattened or
    simplified.  Subexpressions whose derivative sympy defines otherwise (``Abs``,
    ``Piecewise``, ``Derivative``, ...) are passed to ``sympy.diff``.

    ``cache`` (a dict, filled here) carries the derivatives of subexpressions over several
    calls, e.g. by every symbol of one expression (``jacobian``, the total derivative);
    with it (or several symbols) the symbols below each subexpression are remembered
    too, and a subexpression without the symbol is not walked."""
    prune = cache is not None or len(symbols) > 1
    cache = {} if cache is None else cache
    expr = sp.sympify(expr, strict=True)
    for x in symbols:
        if not isinstance(x, sp.Symbol):
            raise TypeError(f"dag.diff differentiates by Symbols, not {x!r}")
        expr = _diff(expr, x, cache, prune)
    return expr


def jacobian(exprs, symbols, cache: dict | None = None) -> sp.Matrix:
    """The matrix d exprs[i] / d symbols[j] (``diff``; one cache for all entries)."""
    cache = {} if cache is None else cache
    exprs = [sp.sympify(e, strict=True) for e in exprs]
    return sp.Matrix(len(exprs), len(symbols),
                     lambda i, j: _diff(exprs[i], symbols[j], cache, True))


#: the key, beside a node's id, of its free symbols in ``diff``'s cache
_FREE = object()


def _symbols_below(expr, cache: dict) -> frozenset:
    """The Symbols in ``expr``, remembered for every subexpression in ``cache`` under
    (id(node), _FREE) -> (node, symbols)."""
    stack = [(expr, False)]
    while stack:
        e, expanded = stack.pop()
        key = (id(e), _FREE)
        if key in cache:
            continue
        if not expanded and e.args:
            stack.append((e, True))
            stack.extend((a, False) for a in e.args if (id(a), _FREE) not in cache)
            continue
        if isinstance(e, sp.Symbol) or not e.args:
            below = frozenset((e,)) if isinstance(e, sp.Symbol) else frozenset()
        else:                    # the largest child's set itself where it holds them all
            sets = [cache[(id(a), _FREE)][1] for a in e.args]
            big = max(sets, key=len)
            below = big if all(s <= big for s in sets) else big.union(*sets)
        cache[key] = (e, below)
    return cache[(id(expr), _FREE)][1]


def _diff(expr, x, cache: dict, prune: bool):
    """d expr / dx; ``cache``: (id(node), x) -> (node, derivative), the node kept alive
    so that its id is not reused.  With ``prune``, a subexpression without x is zero,
    not walked (``_symbols_below``: one walk, worth it when the cache serves several
    symbols)."""
    if prune:
        _symbols_below(expr, cache)
    stack = [(expr, False)]
    while stack:
        e, expanded = stack.pop()
        key = (id(e), x)
        if key in cache:
            continue
        if prune and x not in cache[(id(e), _FREE)][1]:
            cache[key] = (e, sp.S.Zero)
            continue
        if not expanded and e.args:
            stack.append((e, True))
            stack.extend((a, False) for a in e.args if (id(a), x) not in cache)
            continue
        cache[key] = (e, _rule(e, x, cache))
    return cache[(id(expr), x)][1]


def _rule(e, x, cache):
    """The derivative of node ``e`` from those of its children (all in ``cache``)."""
    if not e.args:
        return sp.S.One if e == x else sp.S.Zero
    ds = [cache[(id(a), x)][1] for a in e.args]
    if all(d is sp.S.Zero for d in ds):
        return sp.S.Zero
    if isinstance(e, sp.Add):
        return build(sp.Add, [d for d in ds if d is not sp.S.Zero])
    if isinstance(e, sp.Mul):
        args = list(e.args)
        return build(sp.Add, [build(sp.Mul, [*args[:i], d, *args[i + 1:]])
                              for i, d in enumerate(ds) if d is not sp.S.Zero])
    if isinstance(e, sp.Pow):         # a zero part is left out (0 * log(b) would ask
        (b, p), (db, dp) = e.args, ds  # whether log(b) is finite, walking b's tree)
        return mul(e, build(sp.Add, [*([mul(dp, sp.log(b))] if dp is not sp.S.Zero else []),
                                     *([div(mul(db, p), b)] if db is not sp.S.Zero else [])]))
    if isinstance(e, sp.Function) and type(e)._eval_derivative is sp.Function._eval_derivative:
        out = []
        for i, d in enumerate(ds, 1):
            if d is sp.S.Zero:
                continue
            try:
                df = e.fdiff(i)
            except ArgumentIndexError:
                df = sp.Function.fdiff(e, i)
            out.append(mul(df, d))
        return build(sp.Add, out)
    return sp.diff(e, x)


_SPECIAL = {"Abs": abs, "re": mpmath.re, "im": mpmath.im, "conjugate": mpmath.conj}


def _values(expr, leaf, add, mul, power, function):
    """The values of ``expr`` (a Basic or a list), each distinct subexpression computed
    once, children first: ``leaf(e)`` is the value of a given symbol or a number (None
    for any other node), the others come from their children's values by ``add(values)``,
    ``mul(values)``, ``power(base, exp)`` or ``function(node, values)``.  Raises
    ArgumentError (a ValueError) naming every symbol without a value."""
    roots = _roots(expr)
    val: dict = {}
    order = nodes(roots)
    missing = sorted({e for e in order if isinstance(e, sp.Symbol) and leaf(e) is None},
                     key=str)
    if missing:
        raise ArgumentError(
            f"no value for {', '.join(map(str, missing))} in the point: give every free "
            "symbol of the expression a value ({Symbol: number})")
    for e in order:
        v = leaf(e)
        if v is None:
            args = [val[id(a)] for a in e.args]
            if e.is_Add:
                v = add(args)
            elif e.is_Mul:
                v = mul(args)
            elif e.is_Pow:
                v = power(*args)
            elif isinstance(e, sp.Function):
                v = function(e, args)
            else:
                raise ValueError(f"cannot evaluate {e!r} numerically (no value given)")
        val[id(e)] = v
    out = [val[id(e)] for e in roots]
    return out if isinstance(expr, (list, tuple)) else out[0]


def _exponent_check(log_size, dps: int):
    """OverflowError where a power or exponential would be e**log_size with |log_size|
    beyond 10**dps: its value has no correct digit at ``dps`` digits, and mpmath would
    take memory and time without bound to compute it (exp(exp(exp(exp(exp(1))))))."""
    if abs(log_size) > mpmath.mpf(10) ** dps:
        raise OverflowError(f"a value of size e**{mpmath.nstr(log_size, 3)} at {dps} digits")


def evaluate(expr, point: dict, dps: int = 30) -> list:
    """The values (mpmath numbers, ``dps`` digits) of ``expr`` (a Basic or a list) at
    ``point`` (Symbol -> number), each distinct subexpression computed once (functions
    mpmath lacks by sympy's evalf).  Raises ArgumentError (a ValueError) for a symbol
    without a value, OverflowError for a power or exponential beyond any number at
    ``dps`` digits (``_exponent_check``)."""
    with mpmath.workdps(dps):
        prec = mpmath.mp.prec

        def power(base, exp):
            if base != 0 and exp != 0:
                _exponent_check(mpmath.re(exp) * mpmath.log(abs(base)), dps)
            return mpmath.power(base, exp)
        given = {s: mpmath.mpmathify(v) if not isinstance(v, sp.Basic)
                 else _number(sp.sympify(v, strict=True), prec) for s, v in point.items()}

        def leaf(e):
            if e in given:
                return given[e]
            if e.is_Number or e.is_NumberSymbol or e is sp.I:
                return _number(e, prec)
            return None

        def function(e, args):
            if isinstance(e, sp.exp):
                _exponent_check(mpmath.re(args[0]), dps)
            f = _SPECIAL.get(type(e).__name__) or getattr(mpmath, type(e).__name__, None)
            return f(*args) if f else _number(e.func(*map(to_sympy, args)).evalf(dps), prec)

        return _values(expr, leaf, mpmath.fsum, mpmath.fprod, power, function)


#: (function class, number of arguments) -> its numpy function (``evaluate_numpy``):
#: lambdify of a head costs milliseconds (sympy evaluates e.g. cos of a Dummy)
_NUMPY_HEADS: dict = {}


def evaluate_numpy(expr, point: dict):
    """The values (numpy float arrays, broadcast) of ``expr`` (a Basic or a list) at
    ``point`` (Symbol -> number or array), each distinct subexpression computed once
    over all the points; a function node by ``lambdify`` of its head alone (applied to
    the values of its arguments), so the graph is never flattened.  Raises ArgumentError
    (a ValueError) for a symbol without a value."""
    import numpy as np

    heads = _NUMPY_HEADS

    def leaf(e):
        if e in point:
            return np.asarray(point[e], dtype=float)
        if e.is_Number or e.is_NumberSymbol:
            return np.float64(float(e))
        return None

    def function(e, args):
        key = (e.func, len(args))
        if key not in heads:
            xs = sp.symbols(f"a:{len(args)}", cls=sp.Dummy)
            heads[key] = sp.lambdify(xs, e.func(*xs), "numpy")
        return heads[key](*args)

    with np.errstate(all="ignore"):
        return _values(expr, leaf, sum,
                       lambda vs: np.prod(np.broadcast_arrays(*vs), axis=0), np.power,
                       function)


def to_sympy(v) -> sp.Expr:
    """An mpmath number as a sympy Float (or complex), keeping its precision."""
    if isinstance(v, mpmath.mpc):
        return sp.Float(v.real, mpmath.mp.dps) + sp.I * sp.Float(v.imag, mpmath.mp.dps)
    return sp.Float(v, mpmath.mp.dps)


def _number(e, prec: int):
    if e is sp.I:
        return mpmath.mpc(0, 1)
    if e.is_Float or e.is_Rational or e.is_NumberSymbol:
        return mpmath.mpf(e._as_mpf_val(prec))
    if not e.is_number:
        raise ValueError(f"cannot evaluate {e} numerically")
    re, im = e.as_real_imag()
    return mpmath.mpc(re._as_mpf_val(prec), im._as_mpf_val(prec))
