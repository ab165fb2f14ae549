"""Holonomic constraints g(t, q) = 0 at a configuration: residual, Jacobian, completion,
tangent space.

A ``System`` keeps its constraints without velocities in ``system.holonomic`` and uses
their time derivatives D g in its equations; those hold g constant, not zero.  This module
is what the numerics need to put and keep a configuration on g = 0:

- ``residual(system, point)``: the values g_i at a point (t, q, parameters);
- ``jacobian(system)``: dg_i/dq^s (m x n, sympy) and ``jacobian_at`` its numbers;
- ``bound(system, point)``: the largest ``|g_i|`` accepted as "on g = 0" there, relative to
  the constraint's own scale at the point (``sizes``: the size of the terms that make up
  g_i, and the rounding of the coordinates and t through dg_i), never to the number 1:
  the same configuration in other units gets the same verdict;
- ``check(system, point, complete)``: refuse a configuration off g = 0 (with the residual
  and the fix), or complete it by Newton's method in chosen coordinates
  (``completion_coordinates``: by default the split's dependent coordinates that make
  dg/dq^alpha regular there);
- ``tangent_basis(system, point)``: an orthonormal basis of the tangent space
  ker dg/dq of {g = 0} at q, and ``independent_coordinates``: coordinates whose values
  parametrise {g = 0} near q (what a linearization perturbs).

Values are computed on the shared graph at 30 digits (``dag.evaluate``).
"""

from __future__ import annotations

import numpy as np
import sympy as sp

from ..algebra import dag
from ..errors import ConstraintError

#: the largest ``|g_i|`` accepted as "on g = 0", relative to the size of g_i's terms at
#: the point (``sizes``)
TOLERANCE = 1e-9
#: ... and relative to the rounding of the point through g_i,
#: ``sum_s |dg_i/dq^s| |q^s| + |dg_i/dt| |t|`` (a zero of sin q at q = pi, whose terms
#: are themselves rounding)
ROUNDING = 1e-14
#: the ``|g_i|`` a completion converges to, relative to the same sizes
CONVERGED = 1e-15
#: Newton iterations of a completion
MAX_ITERATIONS = 50


def jacobian(system) -> sp.Matrix:
    """dg_i/dq^s, m x n (rows: ``system.holonomic``, columns: ``J.q``)."""
    J = system.J
    return sp.Matrix(len(system.holonomic), J.n,
                     lambda i, s: dag.diff(system.holonomic[i], J.q[s]))


def _symbols(system, point) -> dict:
    """``point`` keyed by Symbol (names of t, coordinates and parameters accepted)."""
    J = system.J
    by_name = {s.name: s for s in (J.t, *J.q, *system.parameters)}
    return {by_name.get(k, k) if isinstance(k, str) else k: v for k, v in point.items()}


def _floats(exprs, point) -> np.ndarray:
    try:
        vals = dag.evaluate(list(exprs), point)
    except (ZeroDivisionError, ValueError) as exc:
        raise ConstraintError(
            f"the holonomic constraints cannot be evaluated at the initial configuration "
            f"({exc}); give every coordinate and parameter a value where they are defined"
        ) from None
    out = np.array([complex(v).real if complex(v).imag == 0 else np.nan for v in vals],
                   dtype=float)
    return out


def residual(system, point) -> np.ndarray:
    """g_i at ``point`` (t, the coordinates and the parameters, keyed by Symbol or name;
    the same for every function here)."""
    return _floats(system.holonomic, _symbols(system, point))


def jacobian_at(system, point) -> np.ndarray:
    """dg_i/dq^s at ``point`` (an m x n array)."""
    m, n = len(system.holonomic), system.J.n
    return _floats(list(jacobian(system)), _symbols(system, point)).reshape(m, n)


def magnitude(expr, memo: dict | None = None):
    """The size of the terms that make up ``expr`` (a nonnegative expression): the sum
    of the terms' absolute values for a sum, through products and positive constant
    powers factor by factor, ``Abs`` of any other node (a function, a division).  A
    residual small against it is zero to that relative precision, whatever the units;
    a sum inside a term counts by its value (a difference of large numbers that
    cancels to a small factor does not make the term large)."""
    memo = {} if memo is None else memo
    for e in dag.nodes(expr):
        if e in memo:
            continue
        if e.is_Add:
            memo[e] = sp.Add(*[sp.Abs(a, evaluate=False) for a in e.args],
                             evaluate=False)
        elif e.is_Mul:
            memo[e] = sp.Mul(*[_factor(a, memo) for a in e.args], evaluate=False)
        elif e.is_Pow and e.exp.is_Number and e.exp > 0:
            memo[e] = sp.Pow(_factor(e.base, memo), e.exp, evaluate=False)
        else:
            memo[e] = sp.Abs(e, evaluate=False)
    return memo[expr]


def _factor(e, memo):
    """A factor's size in ``magnitude``: its value's for a sum, its own otherwise."""
    return sp.Abs(e, evaluate=False) if e.is_Add else memo[e]


_SIZES: dict = {}


def _size_exprs(system) -> list:
    """The sizes of the constraints' terms (``magnitude``) and dg_i/dt (cached)."""
    key = tuple(system.holonomic)
    if key not in _SIZES:
        if len(_SIZES) > 256:
            _SIZES.clear()
        memo: dict = {}
        _SIZES[key] = ([magnitude(g, memo) for g in system.holonomic]
                       + [dag.diff(g, system.J.t) for g in system.holonomic])
    return _SIZES[key]


def sizes(system, point, G=None) -> tuple[np.ndarray, np.ndarray]:
    """``(terms, rounding)`` per constraint at ``point``: the size of the terms that make
    up g_i (``magnitude``) and ``sum_s |dg_i/dq^s| |q^s| + |dg_i/dt| |t|`` (``G``:
    dg/dq there, if known)."""
    point = _symbols(system, point)
    m, J = len(system.holonomic), system.J
    vals = _floats(_size_exprs(system), point)
    G = jacobian_at(system, point) if G is None else G
    q = np.array([abs(float(point.get(s, 0.0))) for s in J.q])
    t = abs(float(point.get(J.t, 0.0)))
    return vals[:m], np.abs(G) @ q + np.abs(vals[m:]) * t


def bound(system, point, tol: float = TOLERANCE, G=None) -> np.ndarray:
    """The largest ``|g_i|`` accepted as "on g = 0" at ``point``: ``tol`` times the size of
    g_i's terms plus ``ROUNDING`` times the rounding of the point through g_i
    (``sizes``; ``G``: dg/dq there, if known)."""
    terms, rounding = sizes(system, point, G)
    return tol * terms + ROUNDING * rounding


def bound_rows(system, point, tol: float = TOLERANCE) -> np.ndarray:
    """``bound`` at many points at once (an m x k array): ``point`` maps t, the
    coordinates and the parameters (Symbols or names) to numbers or arrays of k values;
    in double precision (numpy), where ``bound`` evaluates each point at 30 digits."""
    point = _symbols(system, point)
    m, J = len(system.holonomic), system.J
    with np.errstate(all="ignore"):
        vals = dag.evaluate_numpy(_size_exprs(system) + list(jacobian(system)), point)
    vals = np.array(np.broadcast_arrays(*vals), dtype=float)
    terms, dgdt, G = vals[:m], vals[m:2 * m], vals[2 * m:].reshape(m, J.n, -1)
    q = np.abs(np.array(np.broadcast_arrays(*[np.asarray(point.get(s, 0.0), dtype=float)
                                              for s in J.q]), dtype=float))
    t = np.abs(np.asarray(point.get(J.t, 0.0), dtype=float))
    rounding = np.einsum("ink,nk->ik", np.abs(G), np.broadcast_to(q, (J.n, G.shape[2])))
    return tol * np.abs(terms) + ROUNDING * (rounding + np.abs(dgdt) * t)


def _describe(system, g) -> str:
    return "; ".join(f"g{i + 1} = {e} is {v:.6g}" for i, (e, v) in
                     enumerate(zip(system.holonomic, g)))


def _rank_error(system, G, where):
    rank = np.linalg.matrix_rank(G) if np.all(np.isfinite(G)) else "undefined"
    return ConstraintError(
        f"the holonomic constraints {list(system.holonomic)} have a rank-deficient "
        f"Jacobian dg/dq (rank {rank} < {len(system.holonomic)}) {where}: they do not "
        "cut out a smooth configuration manifold there (a gradient vanishes, or the "
        "gradients are dependent). Start from another configuration, or remove a "
        "redundant constraint")


def completion_coordinates(system, point, coordinates=None) -> tuple:
    """The coordinates a completion solves for: ``coordinates`` (Symbols or names, one
    per holonomic constraint), or by default the split's dependent coordinates, then the
    others from the last, taken while dg/dq over them stays of full rank at ``point``."""
    J = system.J
    m = len(system.holonomic)
    G = jacobian_at(system, point)
    if not np.all(np.isfinite(G)) or np.linalg.matrix_rank(G) < m:
        raise _rank_error(system, G, "at the initial configuration")
    if coordinates is not None:
        by_name = {s.name: s for s in J.q}
        items = [coordinates] if isinstance(coordinates, (str, sp.Symbol)) else list(coordinates)
        chosen = []
        for c in items:
            name = c if isinstance(c, str) else getattr(c, "name", None)
            if name not in by_name:
                raise ConstraintError(
                    f"complete={coordinates!r}: {c!r} is not a coordinate; give coordinates "
                    f"of {[s.name for s in J.q]} (one per holonomic constraint, {m})")
            chosen.append(by_name[name])
        if len(set(chosen)) != m:
            raise ConstraintError(
                f"complete={coordinates!r}: give {m} distinct coordinate(s), one per "
                f"holonomic constraint")
        cols = [J.q.index(c) for c in chosen]
        if np.linalg.matrix_rank(G[:, cols]) < m:
            raise ConstraintError(
                f"the holonomic constraints cannot be solved for "
                f"{[c.name for c in chosen]} at the initial configuration (dg/dq over them is "
                "singular there); choose other coordinates, or complete=True")
        return tuple(chosen)
    order = list(system.dep_index) + [j for j in range(J.n - 1, -1, -1)
                                      if j not in system.dep_index]
    cols = []
    for j in order:
        if np.linalg.matrix_rank(G[:, cols + [j]]) == len(cols) + 1:
            cols.append(j)
        if len(cols) == m:
            break
    return tuple(J.q[j] for j in cols)


def check(system, point, complete=False, tol: float = TOLERANCE):
    """``(point, changed)``: ``point`` if g = 0 holds there (``|g_i| <= bound(system,
    point, tol)``: relative to the constraint's own scale, whatever the units), else
    with the coordinates of ``completion_coordinates`` solved by Newton's method when
    ``complete`` (True, or the coordinates), else a ``ConstraintError`` with the
    residual and the fix.  ``changed``: name -> (given,
    completed) of the coordinates moved."""
    if not system.holonomic:
        return point, {}
    J = system.J
    point = _symbols(system, point)
    g = residual(system, point)
    if not np.all(np.isfinite(g)):
        raise ConstraintError(
            f"the holonomic constraints are not real at the initial configuration "
            f"({_describe(system, g)}); give a configuration where they are defined")
    G = jacobian_at(system, point)
    if np.all(np.abs(g) <= bound(system, point, tol, G)):
        if not np.all(np.isfinite(G)) or np.linalg.matrix_rank(G) < len(g):
            raise _rank_error(system, G, "at the initial configuration")
        return point, {}
    if complete is False or complete is None:
        names = [c.name for c in completion_coordinates(system, point)]
        raise ConstraintError(
            f"the initial configuration is off the holonomic constraints: "
            f"{_describe(system, g)} (should be 0). Give coordinates with g = 0, or pass "
            f"complete=True to solve for {', '.join(names)} (complete=[...] names other "
            "coordinates)")
    coords = completion_coordinates(system, point,
                                    None if complete is True else complete)
    cols = [J.q.index(c) for c in coords]
    new = dict(point)
    polished = False
    for _ in range(MAX_ITERATIONS):
        g = residual(system, new)
        G = jacobian_at(system, new)
        if not (np.all(np.isfinite(g)) and np.all(np.isfinite(G))):
            break
        done = bool(np.all(np.abs(g) <= bound(system, new, CONVERGED, G)))
        if done and polished:
            changed = {c.name: (float(point[c]), float(new[c])) for c in coords}
            return new, changed
        A = G[:, cols]
        if np.linalg.matrix_rank(A) < len(cols):
            break
        step = np.linalg.solve(A, g)
        for c, d in zip(coords, step):
            new[c] = float(new[c]) - float(d)
        polished = done           # one Newton step more once converged: to roundoff
    raise ConstraintError(
        f"the initial configuration cannot be completed onto the holonomic constraints by "
        f"solving for {', '.join(c.name for c in coords)} (Newton's method from the given "
        f"values did not converge; at the start {_describe(system, residual(system, point))}). "
        "Give a configuration nearer g = 0, or name other coordinates with complete=[...]")


def tangent_basis(system, point) -> np.ndarray:
    """An orthonormal basis (columns, n x (n - m)) of the tangent space ker dg/dq of the
    configuration manifold g = 0 at ``point`` (all of R^n without holonomic constraints):
    the directions a perturbation of the configuration may take."""
    n = system.J.n
    if not system.holonomic:
        return np.eye(n)
    G = jacobian_at(system, point)
    m = G.shape[0]
    if not np.all(np.isfinite(G)) or np.linalg.matrix_rank(G) < m:
        raise _rank_error(system, G, "at this configuration")
    _, _, vt = np.linalg.svd(G)
    return np.ascontiguousarray(vt[m:].T)


def independent_coordinates(system, point) -> tuple:
    """Coordinates that parametrise g = 0 near ``point``: every coordinate but
    ``completion_coordinates`` (those follow from g = 0)."""
    dep = set(completion_coordinates(system, point))
    return tuple(q for q in system.J.q if q not in dep)
