"""Singular sets of solved equations: the quantities whose vanishing makes an expression
divide by zero or leave its domain (denominators, square-root and log arguments, ...).

``bases`` and ``factors`` are what the code generator compiles as singularity indicators;
``singular_set`` is the readable form ``compare`` reports: the factors on the
constraints, small ones factored, those that cannot vanish dropped, repeats removed.

What "cannot vanish" means here: every symbol (time, coordinates, velocities,
multipliers, parameters) is taken to be real, and a symbol that is itself in the set is
taken to be nonzero (the set is a union: off it, that symbol is nonzero).  A factor is
dropped when sympy's assumptions then prove it nonzero (a nonzero number, exp(u),
1 + u^2, a^2 + b^2 when a is in the set; sin(u)^2 + cos(u)^2, after the one rewrite
sin(u)^2 -> 1 - cos(u)^2 of small factors); a symbol keeps a sign it was declared with
(``Symbol("m", positive=True)``: m = 0 is never in the set).  Nothing else is dropped, a
parameter (m) or a sum of parameters (I1 + R^2) included.  Small factors are factored;
larger sums (up to ``_TERMS_MAX`` tree nodes) have their terms' common factors drawn out
(``factor_terms``), never a full factorization.
"""

from __future__ import annotations

import sympy as sp

from . import dag

_FACTOR_MAX = 400        # tree nodes up to which a factor is factored and tested for sign
_FACTOR_GENERATORS = 3   # functions and roots up to which a factor is factored
_TERMS_MAX = 4_000       # tree nodes up to which a larger sum's common factors are drawn out
_POLY_GENS, _POLY_DEGREE, _POLY_TERMS = 12, 10, 24  # ... and its size as a polynomial
_LABEL_MAX = 400         # tree nodes up to which an expression is printed in full


def bases(expr) -> list:
    """The quantities whose vanishing makes ``expr`` singular or undefined: bases of
    negative and fractional powers, arguments of log, cos of tan/sec arguments, sin of
    cot/csc arguments, 1 - u^2 of asin/acos arguments (in the order met; shared
    subexpressions are visited once)."""
    out, seen, stack = [], set(), [sp.sympify(expr, strict=True)]
    while stack:
        e = stack.pop()
        if id(e) in seen or e.is_Atom:      # by identity: equal trees never compared
            continue
        seen.add(id(e))
        if e.is_Pow:
            b, x = e.as_base_exp()
            if x.is_number and (x.is_negative or not x.is_integer):
                out.append(b)
        elif isinstance(e, sp.log):
            out.append(e.args[0])
        elif isinstance(e, (sp.tan, sp.sec)):
            out.append(sp.cos(e.args[0]))
        elif isinstance(e, (sp.cot, sp.csc)):
            out.append(sp.sin(e.args[0]))
        elif isinstance(e, (sp.asin, sp.acos, sp.atanh)):
            out.append(1 - e.args[0] ** 2)
        stack.extend(reversed(e.args))
    return out


def factors(b) -> list:
    """``b`` split into the factors whose vanishing makes it vanish, without numbers,
    positive integer powers or (for a factor of at most ``_FACTOR_MAX`` tree nodes) an
    overall sign."""
    out = []
    for f in sp.Mul.make_args(b):
        while f.is_Pow and f.exp.is_Integer and f.exp > 0:
            f = f.base
        if f.is_number:
            continue
        # sympy decides the sign on the tree: only for a small one
        if tree_size(f, _FACTOR_MAX) <= _FACTOR_MAX and f.could_extract_minus_sign():
            f = -f
        out.append(f)
    return out


def tree_size(e, limit: int) -> int:
    """The number of nodes of ``e`` as a tree, counted up to ``limit + 1`` (a nested
    expression's tree can be exponentially larger than its graph)."""
    count, stack = 0, [e]
    while stack and count <= limit:
        count += 1
        stack.extend(stack.pop().args)
    return count


def label(e, limit: int = _LABEL_MAX) -> str:
    """``e`` as text: in full when its tree is short, else by its shared size and its
    symbols (never flattened)."""
    if tree_size(e, limit) > limit:
        syms = sorted(s.name for s in dag.free_symbols(e))
        return (f"<a nested expression of {dag.size(e)} distinct subexpressions in "
                + ", ".join(syms[:12]) + (", ..." if len(syms) > 12 else "") + ">")
    return sp.sstr(e)


def _split(b) -> list:
    """The factors of ``b``: small ones (a short tree, few functions and roots: the cost
    of factoring grows fast with them) through ``sp.factor``, poles included (where a
    factor's denominator vanishes the factor is undefined)."""
    out = []
    for f in factors(b):
        g = _pythagoras(f)
        if _factorable(g):
            try:
                g = sp.factor(g)
            except (sp.PolynomialError, NotImplementedError, ValueError, TypeError):
                pass
        elif g.is_Add and tree_size(g, _TERMS_MAX) <= _TERMS_MAX:
            g = sp.factor_terms(g)      # too large to factor: common factors of the terms
        for h in sp.Mul.make_args(g):
            if h.is_Pow and h.exp.is_number and h.exp.is_negative:
                out.extend(factors(h.base))
            else:
                out.extend(factors(h))
    return out


def _factorable(g) -> bool:
    """Whether ``g`` is small enough to factor: a sum with a short tree, few functions and
    roots, and as a polynomial few generators, terms and a low degree (the time of
    sympy's multivariate factoring, Wang's algorithm with random evaluation points, grows
    fast and unpredictably with these)."""
    if not g.is_Add or tree_size(g, _FACTOR_MAX) > _FACTOR_MAX or len(
            {e for e in dag.nodes(g) if isinstance(e, sp.Function) or (
                e.is_Pow and not e.exp.is_Integer)}) > _FACTOR_GENERATORS:
        return False
    try:
        p = sp.Poly(g)
    except (sp.PolynomialError, sp.GeneratorsNeeded):
        return False
    return (len(p.gens) <= _POLY_GENS and p.total_degree() <= _POLY_DEGREE
            and len(p.terms()) <= _POLY_TERMS)


def _pythagoras(f):
    """``f`` with sin(u)^2 replaced by 1 - cos(u)^2 and expanded, when that is shorter
    (sin^2 + cos^2 sums, common in the norms of constraint rows); only for small ``f``."""
    if tree_size(f, _FACTOR_MAX) > _FACTOR_MAX:
        return f
    squares = {g: 1 - sp.cos(g.base.args[0]) ** 2 for g in dag.nodes(f)
               if g.is_Pow and g.exp == 2 and isinstance(g.base, sp.sin)}
    if not squares:
        return f
    g = sp.expand(f.xreplace(squares))
    return g if tree_size(g, _FACTOR_MAX) < tree_size(f, _FACTOR_MAX) else f


def _nonzero(f, nonzero_symbols: set) -> bool:
    """Whether sympy's assumptions prove ``f`` nonzero for real symbols (those in
    ``nonzero_symbols`` also nonzero); only for small ``f``."""
    if tree_size(f, _FACTOR_MAX) > _FACTOR_MAX:
        return False
    real = {s: _real(s, s in nonzero_symbols) for s in f.free_symbols
            if isinstance(s, sp.Symbol)}
    return f.xreplace(real).is_zero is False


def _real(s, nonzero: bool):
    """``s`` as a real symbol that keeps its declared sign (``positive=True`` and the
    like), nonzero when ``nonzero``."""
    sign = ({"positive": True} if s.is_positive else {"negative": True} if s.is_negative
            else {"nonzero": True} if nonzero or s.is_nonzero else {})
    return sp.Dummy(s.name, real=True, **sign)


def singular_set(exprs, on=None) -> list:
    """Where ``exprs`` are singular or undefined: the factors of their ``bases``, with
    ``on`` (a substitution such as the explicit form of the constraints) applied first,
    small ones factored, those proven nonzero (module docstring) dropped and repeats
    (up to sign) removed; in the order met, shared structure kept."""
    found: list = []
    for e in exprs:
        found.extend(bases(e))
    # one object per distinct base (dag.xreplace hash-conses), each split once
    found = list({id(b): b for b in dag.xreplace(found, on or {})}.values())
    out, seen = [], set()
    for b in found:
        for f in _split(b):
            if f not in seen and not f.is_number:
                seen.add(f)
                out.append(f)
    syms = {f for f in out if isinstance(f, sp.Symbol)}
    return [f for f in out if not _nonzero(f, syms - {f})]
