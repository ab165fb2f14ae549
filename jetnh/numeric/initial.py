"""The initial sensitivities S(t0) = d y(t0) / d(y0, p) of a run with sensitivities.

Without holonomic constraints S(t0) = (I | 0): each initial state varies alone, the
runtime parameters do not move it.  With holonomic constraints g(t, q, p) = 0 the
configuration cannot vary alone: a start is on g = 0 (the scene refuses or completes
one off it), so d/dq^s(t0) is a derivative along g = 0 in a chart.  The chart is the
split's, as ``mechanics.holonomic.completion_coordinates`` and ``linearize`` take it:
the dependent coordinates q^D are the split's dependent coordinates over which dg/dq is
regular at the start, the others q^I parametrise g = 0 near it, and q^D follows them
(and the parameters g depends on) by the implicit function theorem::

    dq^D/dq^I = -(dg/dq^D)^{-1} dg/dq^I,    dq^D/dp = -(dg/dq^D)^{-1} dg/dp,

so that G S(t0) + dg/dp = 0 holds at t0 as it does at every later time.  The column of
a dependent coordinate is zero (q^D(t0) follows from g, it is no initial value of its
own: ``Trajectory.sensitivity`` refuses it).  The states after the coordinates (the
independent velocities, the multipliers) keep the identity: the dependent velocities
are no states but solve the constraints at every state, so they follow the coordinates
through the equations themselves.
"""

from __future__ import annotations

import functools
import math

import numpy as np

#: the unit roundoff of float64
_EPS = 2.220446049250313e-16


def _evaluate(hol, m, nq, t, rows, p):
    """``(G = dg/dq [rows, m, nq], dg/dp [rows, m, n_p] or None)`` of ``hol`` at each
    of the ``rows`` of states (time ``t``; ``p`` one row of parameters or one per row)."""
    P = np.atleast_2d(np.asarray(p, dtype=float))
    P = np.ascontiguousarray(np.broadcast_to(P, (rows.shape[0], P.shape[1])))
    rows = np.ascontiguousarray(rows, dtype=float)
    out = np.empty((rows.shape[0], hol.sizes[2]))
    for r in range(rows.shape[0]):
        hol(float(t), rows[r], P[r], out[r])
    G = out[:, m:m + m * nq].reshape(-1, m, nq)
    rest = out[:, m + m * nq:]
    return G, rest.reshape(rows.shape[0], m, -1) if rest.shape[1] else None


def _chosen(G, system):
    """``(dep [rows, m], ok [rows])``: per row of ``G`` (dg/dq, [rows, m, nq]) the
    coordinates taken in the order of ``holonomic.completion_coordinates`` (the
    split's dependent coordinates first, then the others from the last) while dg/dq
    over them keeps full rank (Gaussian elimination: a column is taken where it has an
    entry above ``max(m, nq) * eps * max |dg/dq|`` outside the rows the columns taken
    before pivot on); ``ok`` False where fewer than m are found (singular, not
    finite)."""
    R, m, nq = G.shape
    order = list(system.dep_index) + [j for j in range(nq - 1, -1, -1)
                                      if j not in system.dep_index]
    dep = np.zeros((R, m), dtype=np.int64)
    ok = np.zeros(R, dtype=bool)
    for r in range(R):
        A = G[r].tolist()
        flat = [abs(v) for row in A for v in row]
        big = max(flat, default=0.0)
        if big == 0.0 or not all(map(math.isfinite, flat)):
            continue
        tol = max(m, nq) * _EPS * big
        free, k = list(range(m)), 0
        for j in order:
            i = max(free, key=lambda i: abs(A[i][j]))
            if abs(A[i][j]) <= tol:
                continue
            free.remove(i)
            for i2 in free:             # eliminate column j below the pivot row i
                f = A[i2][j] / A[i][j]
                A[i2] = [a - f * b for a, b in zip(A[i2], A[i])]
            dep[r, k] = j
            k += 1
            if k == m:
                ok[r] = True
                break
    return dep, ok


@functools.lru_cache(maxsize=64)
def _identity(n, cols) -> np.ndarray:
    """(I | 0) (n x ``cols``) flattened row-major, read-only: made once per shape (numpy's
    ``eye`` and ``broadcast_to`` cost microseconds a run)."""
    flat = np.eye(n, cols).ravel()
    flat.setflags(write=False)
    return flat


def sensitivities(sens, system, t0, y0, p) -> np.ndarray:
    """S(t0) (module docstring) flattened row-major, for the state ``y0`` (one state or
    rows of states) with the parameters ``p`` (one row, or one per row of ``y0``);
    ``sens``: the kernels of the run with sensitivities (its layout, its ``hol``).
    Rows where dg/dq is singular or not finite keep (I | 0): their runs stop there."""
    lay = sens.layout
    n, cols = lay.n_state, lay.sensitivity_columns
    y0 = np.asarray(y0, dtype=float)
    m = len(system.holonomic)
    if not m:
        flat = _identity(n, cols)
        return flat if y0.ndim == 1 else np.broadcast_to(flat, y0.shape[:-1] + flat.shape)
    eye = np.eye(n, cols)
    rows = y0.reshape(-1, y0.shape[-1])
    nq = len(system.J.q)
    G, dgdp = _evaluate(sens.hol, m, nq, t0, rows, p)
    dep, ok = _chosen(G, system)
    out = np.repeat(eye[None], rows.shape[0], axis=0)
    if ok.any():
        G, dep = G[ok], dep[ok]
        R = np.arange(G.shape[0])[:, None]
        rhs = np.zeros((G.shape[0], m, cols))
        rhs[:, :, :nq] = G
        rhs[R, :, dep] = 0.0                  # the dependent coordinates' own columns
        if dgdp is not None:
            rhs[:, :, n:] = dgdp[ok]
        GD = np.take_along_axis(G, dep[:, None, :], axis=2)
        S = out[ok]
        S[R, dep, :] = -np.linalg.solve(GD, rhs)
        out[ok] = S
    return out.reshape(y0.shape[:-1] + (n * cols,))


def followers(scene, t0, y0, p) -> frozenset:
    """The names of the coordinates that follow from the holonomic constraints at (t0,
    y0) with the runtime parameters ``p`` (``holonomic.completion_coordinates``, the
    rule of ``sensitivities``' chart, on the graph); empty without holonomic
    constraints or where dg/dq is singular there."""
    from ..errors import JetnhError
    from ..mechanics import holonomic

    system = scene.system
    if not system.holonomic:
        return frozenset()
    point = scene._holonomic_point(dict(zip(scene.state_names, np.asarray(y0).tolist())),
                                   float(t0), dict(zip(scene.runtime_params,
                                                       np.asarray(p).tolist())))
    try:
        return frozenset(q.name for q in holonomic.completion_coordinates(system, point))
    except JetnhError:          # singular there: the run has said so
        return frozenset()


def check_column(scene, to, follow):
    """Refuse ``to`` as a column of sensitivities where it is among the coordinates
    ``follow`` (``followers``): its column is zero, it is no initial value of its own."""
    from ..errors import JetnhError

    if to in follow:
        free = [q.name for q in scene.system.J.q if q.name not in follow]
        dep = [q.name for q in scene.system.J.q if q.name in follow]
        raise JetnhError(
            f"sensitivity to {to!r}: on the holonomic constraints g = 0, {', '.join(dep)} "
            f"follow{'s' if len(dep) == 1 else ''} from {', '.join(free)} at the start "
            f"(the split's chart), so {to!r} has no initial value of its own; "
            f"differentiate by {', '.join(free)} (whose columns move {to!r} along g = 0)")
