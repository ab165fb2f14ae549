"""Whether a split is regular at a given point, and whether the point is on the constraints.

A split (the dependent velocities qdot^alpha) is a chart of the constraint manifold
f(t, q, qdot) = 0; at a point its measure is m = det(A_alpha)^2 / det(A A^T), A =
df/dqdot (``atlas.split_measure_of``).  A run switches split where m falls to the edge of
the chart, eps = 1/(4N) over the N splits (``atlas``), and one that starts past the edge
starts in the split of largest measure.  Two thresholds decide how a given point is taken:

- past the edge (m < eps) the dependent velocities given with the point are checked
  against f = 0 itself (``on_constraints``), not against phi^alpha = A_alpha^-1 (...),
  whose conditioning is about 1/sqrt(m);
- there, the split is singular where the constraints no longer determine the dependent
  velocities in floats: a change of one rounding unit in a coordinate, an independent
  velocity or a parameter moves the terms that make phi^alpha (``terms``) by more than
  the consistency tolerance ``tol`` of their size -- ``determined``.  That is the
  conditioning of phi at the point in the numbers given (near th = pi/2, cos th is
  known only to about 1e-16 absolute; near x = 0, x itself is known to 1e-16 relative,
  and y/x is fine).  A point there without its dependent velocities is refused
  (``singular``): give them too, or choose another split.

Every test of given velocities against the constraints is relative to the size of the
terms that make the value tested, never to the number 1, so that its verdict is the
same in every unit of length and of time (``agree``, ``on_constraints``, ``determined``):
phi^alpha = -A_alpha^-1 (sum_s A_s qdot^s + b), s the independent velocities, b = f - A
qdot the part of f without velocities; its terms are the columns of that sum, carried
each through A_alpha^-1 (for affine constraints phi = Phi qdot + phi0: Phi_s qdot^s and
phi0).  Below the smallest normal float nothing is a size: a point at rest requires the
constraints' value itself.
"""

from __future__ import annotations

import math
from itertools import combinations

import numpy as np

from ..algebra import dag
from ..errors import ConstraintError

#: the unit roundoff of float64
ROUNDOFF = float(np.finfo(float).eps) / 2
#: the smallest normal float64: the floor of every size (module docstring)
TINY = float(np.finfo(float).tiny)

_EDGES: dict = {}


def edge(system) -> float:
    """The edge of every chart of ``system`` (``atlas``: 1/(4N), N the splits whose minor
    is not identically zero); at most 1/4, so a measure >= 1/4 is never past it.  With
    more than ``atlas.MAX_K`` constraints runs keep their split and N is taken as every
    choice of k coordinates (telling the identically-zero minors apart would take a
    rank test for each of them: 47 905 for the 64-trailer)."""
    found = _EDGES.get(system)
    if found is None:
        from .atlas import MAX_K, splits

        if len(_EDGES) > 256:
            _EDGES.pop(next(iter(_EDGES)))
        count = (len(splits(system)) if system.k <= MAX_K
                 else math.comb(system.J.n, system.k))
        found = _EDGES[system] = 1.0 / (4 * count)
    return found


def past_edge(system, m: float) -> bool:
    """Whether the measure ``m`` of ``system``'s split lies past the edge of its chart
    (without counting the splits where ``m`` >= 1/4, above every edge)."""
    return m < 0.25 and m < edge(system)


def _point(system, t, coordinates: dict, velocities: dict, params: dict) -> dict:
    J = system.J
    point = {J.t: t}
    point.update((q, coordinates[q.name]) for q in J.q)
    point.update((v, velocities.get(v.name, np.nan)) for v in J.qd)
    point.update((s, params[s.name]) for s in system.parameters)
    return point


def _nudged(point: dict, inputs) -> dict:
    """``point`` (Symbol -> number or array) with a leading axis of len(``inputs``) + 1
    rows: row 0 the point, row i + 1 with ``inputs[i]`` moved by one rounding unit
    (``np.spacing``)."""
    rows = len(inputs) + 1
    shape = np.broadcast_shapes(*(np.shape(v) for v in point.values()))
    out = {s: np.array(np.broadcast_to(np.asarray(v, dtype=float), (rows,) + shape))
           for s, v in point.items()}
    for i, s in enumerate(inputs):
        out[s][i + 1] += np.spacing(out[s][i + 1])
    return out


def _rounding(point: dict, system) -> dict:
    """``_nudged`` in t, every coordinate and every parameter: the rounding of a point
    whose velocities are known (``agree``, ``on_constraints``)."""
    return _nudged(point, [system.J.t, *system.J.q, *system.parameters])


def _spread(rows) -> np.ndarray:
    """sum_i |row i + 1 - row 0| / 2 over the rows of ``_nudged``: how far the value
    may move when each input is known to half a rounding unit (a float stands for the
    numbers that round to it); a non-finite change counts as none."""
    with np.errstate(invalid="ignore"):
        moved = np.abs(rows[1:] - rows[0])
    return 0.5 * np.where(np.isfinite(moved), moved, 0.0).sum(axis=0)


def _phis(system, point: dict) -> np.ndarray:
    """phi^alpha ([..., k]) at ``point`` (Symbol -> number or array) in floats."""
    shape = np.broadcast_shapes(*(np.shape(v) for v in point.values()))
    values = dag.evaluate_numpy([system.phi[v] for v in system.dependent_velocities],
                                point)
    return np.stack([np.broadcast_to(np.asarray(x, dtype=float), shape) for x in values],
                    axis=-1)


def _velocities(system, point: dict) -> np.ndarray:
    """Every velocity ([..., n]) at ``point`` (Symbol -> number or array)."""
    return np.stack(np.broadcast_arrays(*[np.asarray(point[v], dtype=float)
                                          for v in system.J.qd]), axis=-1)


def phi(system, t, coordinates: dict, velocities: dict, params: dict) -> dict:
    """The dependent velocities phi^alpha at a point given by name (floats, on the
    shared graph; NaN or infinite where phi is undefined)."""
    vs = system.dependent_velocities
    values = dag.evaluate_numpy([system.phi[v] for v in vs],
                                _point(system, t, coordinates, velocities, params))
    return {v.name: float(x) for v, x in zip(vs, values)}


def determined(system, t, coordinates: dict, velocities: dict, params: dict, tol: float):
    """``(ok, why, finite)``: whether the terms that make phi^alpha at the point
    (``terms``, at ``velocities``) move by at most ``tol`` of their size when any one
    coordinate, independent velocity or parameter changes by one rounding unit
    (``np.spacing``), all the changes evaluated at once on the graph; ``why`` names the
    input that moves them most, and by how much; ``finite``: phi^alpha is.  (The terms,
    not phi alone: where they cancel, phi = 0 may stay 0 while A_alpha, known to less
    than its size, changes sign; where the terms are not finite, as where f is not
    affine in qdot and A = 0, phi itself.)  An input that is exactly 0 is taken as
    exact: its rounding unit, the smallest subnormal, is no relative error (at rest,
    x_t = 0, phi is its velocity-free part however large the factor of x_t)."""
    inputs = [*system.J.q, *system.independent_velocities, *system.parameters]
    given = _point(system, t, coordinates, velocities, params)
    exact = np.array([bool(np.all(np.asarray(given[s]) == 0.0)) for s in inputs])
    point = _nudged(given, inputs)
    x = _phis(system, point)
    A, f = _at(system, point)
    M = terms(system, A, f, _velocities(system, point))
    worst, why = 0.0, ""
    for a, v in enumerate(system.dependent_velocities):
        if not math.isfinite(x[0, a]):
            return False, f"{v.name} is {x[0, a]}", False
        size = float(np.abs(M[0, a]).sum())
        made = "the terms that make it"
        with np.errstate(invalid="ignore", over="ignore", divide="ignore"):
            if math.isfinite(size):
                moved = np.abs(M[1:, a] - M[0, a]).sum(axis=-1) / max(size, TINY)
            else:   # no finite terms (A = 0 where f is not affine in qdot): phi itself
                size, made = abs(x[0, a]), "it"
                moved = np.abs(x[1:, a] - x[0, a]) / max(size, TINY)
        moved = np.where(exact, 0.0, np.where(np.isfinite(moved), moved, np.inf))
        if moved.size and moved.max() > worst:
            i = int(np.argmax(moved))
            worst = float(moved.max())
            why = (f"one rounding unit in {inputs[i].name} moves {v.name} = {x[0, a]:.6g} "
                   f"by {abs(x[i + 1, a] - x[0, a]):.3g} and {made} (of size {size:.3g}) "
                   f"by {worst * max(size, TINY):.3g}")
    return worst <= tol, why, True


def at_point(system, t, coordinates: dict, velocities: dict, params: dict):
    """``(A, f)``: df/dqdot ([..., k, n]) and f ([..., k]) at the points given by name
    (numbers, or arrays of one length for several points; a missing or NaN velocity
    gives NaN), evaluated on the shared graph in floats."""
    return _at(system, _point(system, t, coordinates, velocities, params))


def _at(system, point: dict):
    """``at_point`` at ``point`` (Symbol -> number or array)."""
    k, n = system.k, system.J.n
    values = dag.evaluate_numpy(list(system.jacobian) + list(system.constraints), point)
    shape = np.broadcast_shapes(*(np.shape(v) for v in point.values()))
    A = np.empty(shape + (k, n))
    f = np.empty(shape + (k,))
    for i in range(k * n):
        A[..., i // n, i % n] = values[i]
    for a in range(k):
        f[..., a] = values[k * n + a]
    return A, f


def measure(system, A) -> np.ndarray:
    """The measure of ``system``'s own split at df/dqdot ``A`` ([..., k, n]); 0 where
    A is not finite or has rank < k."""
    from .atlas import split_measure_of

    with np.errstate(all="ignore"):
        return split_measure_of(A, list(system.dep_index))


def best(system, A) -> tuple[list[str], float]:
    """The split of largest measure at one point (A: k x n) among every choice of k
    coordinates (the first where several tie) and its measure (``atlas.measures_at``,
    as a run's atlas measures its charts)."""
    from .atlas import measures_at

    names = [q.name for q in system.J.q]
    choices = list(combinations(range(len(names)), system.k))
    m = measures_at(A, choices)
    i = max(range(len(m)), key=m.__getitem__)
    return [names[c] for c in choices[i]], m[i]


def terms(system, A, f, qd) -> np.ndarray:
    """The terms that make each phi^alpha ([..., k, n - k + 1]; phi^alpha is minus
    their sum) at the points where df/dqdot is ``A`` ([..., k, n]), f is ``f`` ([..., k])
    and the velocities are ``qd`` ([..., n]): A_alpha^-1 C, the columns of C being A_s
    qdot^s for each independent velocity s and b = f - A qdot (module docstring); for
    affine constraints Phi_s qdot^s and phi0, else the terms of f's linearization at the
    point.  NaN where A_alpha is singular or a value is not finite."""
    dep, ind = list(system.dep_index), list(system.ind_index)
    qd = np.asarray(qd, dtype=float)
    with np.errstate(all="ignore"):
        b = f - np.einsum("...as,...s->...a", A, qd)
        C = np.concatenate([A[..., ind] * qd[..., None, ind], b[..., None]], axis=-1)
        Aa = A[..., dep]
        try:
            return np.linalg.solve(Aa, C)
        except np.linalg.LinAlgError:           # one singular: each on its own
            flat, rows = Aa.reshape(-1, *Aa.shape[-2:]), C.reshape(-1, *C.shape[-2:])
            return np.array([_solved(a, c) for a, c in zip(flat, rows)]).reshape(C.shape)


def sizes(system, A, f, qd) -> np.ndarray:
    """The size of the terms that make each phi^alpha ([..., k]): sum_j |``terms``_j|
    (for affine constraints sum_s |Phi_s qdot^s| + |phi0|); NaN where they are."""
    return np.abs(terms(system, A, f, qd)).sum(axis=-1)


def _solved(a, c) -> np.ndarray:
    try:
        return np.linalg.solve(a, c)
    except np.linalg.LinAlgError:
        return np.full(c.shape, np.nan)


def agree(system, t, point: dict, given: dict, required: dict, params: dict,
          tol: float) -> dict:
    """Whether each given dependent velocity (``given``: name -> number or array, for
    several points) agrees with the constraints' value ``required[name]`` at ``point``
    (the coordinates and the independent velocities by name): |given - required| <= tol
    S + R, S the size of the terms that make it (``sizes``, at least ``TINY``), R the
    rounding of the point through phi (``_spread`` of ``_rounding``: how far half a
    rounding unit in t, each coordinate and each parameter moves it), so that the
    verdict is the same in every unit (name -> bool, or bool array).  S and R are
    evaluated only where |given - required| > tol |required| (S >= |required|)."""
    out = {name: abs(g - required[name]) <= tol * abs(required[name])
           for name, g in given.items()}
    if all(ok if type(ok) is bool else ok.all() for ok in out.values()):
        return out
    at = _point(system, t, point, {**point, **required}, params)
    rows = _rounding(at, system)
    A, f = _at(system, at)
    size = np.maximum(sizes(system, A, f, _velocities(system, at)), TINY)
    bound = tol * size + _spread(_phis(system, rows))
    with np.errstate(invalid="ignore"):
        for a, v in enumerate(system.dependent_velocities):
            if v.name in out:
                out[v.name] = out[v.name] | (np.abs(given[v.name] - required[v.name])
                                             <= bound[..., a])
    return out


def on_constraints(system, t, coordinates: dict, velocities: dict, params: dict,
                   tol: float) -> np.ndarray:
    """Whether f = 0 to ``tol`` relative at the points given by name (every velocity
    given): |f^a| <= tol (sum_s |A^a_s qdot^s| + |b^a|) + R^a, b = f - A qdot (the part
    without velocities; the sum at least ``TINY``), R the rounding of the point through
    f (``_spread`` of ``_rounding``) -- the consistency test ``agree`` carried to f, so
    that it does not divide by a singular A_alpha (at cos th = 6e-17, the rounding of th
    = pi/2, f = cos th Y_t is all rounding)."""
    at = _point(system, t, coordinates, velocities, params)
    A, f = _at(system, _rounding(at, system))
    qd = _velocities(system, at)
    b = f[0] - np.einsum("...as,...s->...a", A[0], qd)
    scale = np.maximum(np.abs(A[0] * qd[..., None, :]).sum(axis=-1) + np.abs(b), TINY)
    with np.errstate(invalid="ignore"):
        return (np.all(np.abs(f[0]) <= tol * scale + _spread(f), axis=-1)
                & np.all(np.isfinite(f[0]), axis=-1))


def singular(system, m: float, A, where: str, why: str, finite=True, give=True
             ) -> ConstraintError:
    """The error for a point without its dependent velocities where the split is
    singular (``determined`` fails: ``why`` and ``finite`` from it): the split, its
    measure and the fix (with ``give``: giving them too is one)."""
    own = [s.name for s in system.dependent]
    dep = ", ".join(v.name for v in system.dependent_velocities)
    split, mb = best(system, A) if np.all(np.isfinite(A)) else (None, 0.0)
    other = (f"choose dependent={split} (measure {mb:.3g} here)" if split and set(split) != set(own)
             else "choose another split with dependent=[...]")
    told = "do not determine" if finite else "give no finite value for"
    return ConstraintError(
        f"{where}: the split dependent={own} is singular at this configuration (its "
        f"measure det(A_alpha)^2/det(A A^T), A = df/dqdot, is {m:.3g}; {why}): the "
        f"constraints {told} {dep} there. "
        + (f"Give {dep} too (every velocity, on the constraints), or {other}" if give
           else f"{other[0].upper()}{other[1:]} (system.with_split), where they do"))


def off(system, f, where: str) -> ConstraintError:
    """The error for a point with every velocity given that is off f = 0."""
    told = "; ".join(f"f{a + 1} = {e} is {v:.6g}"
                     for a, (e, v) in enumerate(zip(system.constraints, np.ravel(f))))
    return ConstraintError(
        f"{where}: the point is off the constraints: {told} (should be 0); give velocities "
        "that satisfy them")
