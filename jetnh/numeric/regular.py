"""Whether a split is regular at a given point, and whether the point is on the constraints.

A split (the dependent velocities qdot^alpha) is a chart of the constraint manifold
f(t, q, qdot) = 0; at a point its measure is m = det(A_alpha)^2 / det(A A^T), A =
df/dqdot (``atlas.split_measure_of``).  A run switches split where m falls to the edge of
the chart, eps = 1/(4N) over the N splits (``atlas``), and one that starts past the edge
starts in the split of largest measure.  Two thresholds decide how a given point is taken:

- past the edge (m < eps) the dependent velocities given with the point are checked
  against f = 0 itself (``on_constraints``), not against phi^alpha = A_alpha^-1 (...),
  whose conditioning is about 1/sqrt(m);
- below ``singular_measure(tol)`` the constraints no longer determine the dependent
  velocities: phi^alpha carries a rounding error of about u / sqrt(m) relative (u the
  unit roundoff; a coordinate rounded by u moves A_alpha by u, relative u / sqrt(m)), more
  than the consistency tolerance ``tol``.  A point there without its dependent velocities
  is refused (``singular``): give them too, or choose another split.
"""

from __future__ import annotations

from itertools import combinations

import numpy as np

from ..algebra import dag
from ..errors import ConstraintError

#: the unit roundoff of float64
ROUNDOFF = float(np.finfo(float).eps) / 2

_EDGES: dict = {}


def singular_measure(tol: float) -> float:
    """The measure below which phi^alpha's rounding error (u / sqrt(m) relative) exceeds
    ``tol``: (u / tol)^2."""
    return (ROUNDOFF / tol) ** 2


def edge(system) -> float:
    """The edge of every chart of ``system`` (``atlas``: 1/(4N), N the splits whose minor
    is not identically zero); at most 1/4, so a measure >= 1/4 is never past it."""
    found = _EDGES.get(system)
    if found is None:
        from .atlas import splits

        if len(_EDGES) > 256:
            _EDGES.pop(next(iter(_EDGES)))
        found = _EDGES[system] = 1.0 / (4 * len(splits(system)))
    return found


def at_point(system, t, coordinates: dict, velocities: dict, params: dict):
    """``(A, f)``: df/dqdot ([..., k, n]) and f ([..., k]) at the points given by name
    (numbers, or arrays of one length for several points; a missing or NaN velocity
    gives NaN), evaluated on the shared graph in floats."""
    J = system.J
    point = {J.t: t}
    point.update((q, coordinates[q.name]) for q in J.q)
    point.update((v, velocities.get(v.name, np.nan)) for v in J.qd)
    point.update((s, params[s.name]) for s in system.parameters)
    k, n = system.k, J.n
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

    return split_measure_of(A, list(system.dep_index))


def best(system, A) -> tuple[list[str], float]:
    """The split of largest measure at one point (A: k x n) and its measure."""
    from .atlas import split_measure_of

    names = [q.name for q in system.J.q]
    top, where = -1.0, ()
    for cols in combinations(range(len(names)), system.k):
        m = float(split_measure_of(A, list(cols)))
        if m > top:
            top, where = m, cols
    return [names[c] for c in where], top


def on_constraints(A, f, qd, tol: float) -> np.ndarray:
    """Whether f = 0 to ``tol`` relative at the points (every velocity ``qd`` [..., n]
    given): |f^a| <= tol (sum_s |A^a_s| max(1, |qdot^s|) + |b^a|), b = f - A qdot (the
    part without velocities) -- the consistency test |qdot - phi| <= tol max(1, |phi|)
    carried to f, so that it does not divide by a singular A_alpha."""
    qd = np.asarray(qd, dtype=float)
    terms = np.abs(A) * np.maximum(1.0, np.abs(qd))[..., None, :]
    b = f - np.einsum("...as,...s->...a", A, qd)
    scale = terms.sum(axis=-1) + np.abs(b)
    with np.errstate(invalid="ignore"):
        return np.all(np.abs(f) <= tol * scale, axis=-1) & np.all(np.isfinite(f), axis=-1)


def singular(system, m: float, A, where: str, tol: float, give=True) -> ConstraintError:
    """The error for a point without its dependent velocities where the split is
    singular (m below ``singular_measure(tol)``): the split, its measure and the fix
    (with ``give``: giving them too is one)."""
    own = [s.name for s in system.dependent]
    dep = ", ".join(v.name for v in system.dependent_velocities)
    split, mb = best(system, A) if np.all(np.isfinite(A)) else (None, 0.0)
    other = (f"choose dependent={split} (measure {mb:.3g} here)" if split and split != own
             and mb > singular_measure(tol) else "choose another split with dependent=[...]")
    return ConstraintError(
        f"{where}: the split dependent={own} is singular at this configuration (its "
        f"measure det(A_alpha)^2/det(A A^T), A = df/dqdot, is {m:.3g}, below "
        f"{singular_measure(tol):.3g}): the constraints do not determine {dep} there. "
        + (f"Give {dep} too (every velocity, on the constraints), or {other}" if give
           else f"{other[0].upper()}{other[1:]} (system.with_split), where they do"))


def off(system, f, where: str) -> ConstraintError:
    """The error for a point with every velocity given that is off f = 0."""
    told = "; ".join(f"f{a + 1} = {e} is {v:.6g}"
                     for a, (e, v) in enumerate(zip(system.constraints, np.ravel(f))))
    return ConstraintError(
        f"{where}: the point is off the constraints: {told} (should be 0); give velocities "
        "that satisfy them")
