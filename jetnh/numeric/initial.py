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

import numpy as np


def dependent(hol, system, t, y, p) -> tuple[int, ...]:
    """The indices of the coordinates that follow from the holonomic constraints at
    (t, y) in the split's chart: the split's dependent coordinates first, then the
    others from the last, each taken while dg/dq over them stays of full rank (the
    order of ``holonomic.completion_coordinates``); ``()`` without holonomic
    constraints.  ``hol``: the compiled holonomic kernel (``kernels.calls.Kernel``)."""
    m = len(system.holonomic)
    if not m:
        return ()
    return _chosen(_evaluate(hol, m, len(system.J.q), t, y, p)[1], system)


def _evaluate(hol, m, nq, t, y, p):
    """``(g, G = dg/dq, dg/dp or None)`` of ``hol`` at (t, y, p)."""
    out = np.empty(hol.sizes[2])
    hol(float(t), np.ascontiguousarray(y, dtype=float), np.ascontiguousarray(p, dtype=float),
        out)
    G = out[m:m + m * nq].reshape(m, nq)
    rest = out[m + m * nq:]
    return out[:m], G, rest.reshape(m, -1) if rest.size else None


def _chosen(G, system) -> tuple[int, ...]:
    m, nq = G.shape
    order = list(system.dep_index) + [j for j in range(nq - 1, -1, -1)
                                      if j not in system.dep_index]
    if not np.all(np.isfinite(G)):
        return tuple(order[:m])
    cols: list[int] = []
    for j in order:
        if np.linalg.matrix_rank(G[:, cols + [j]]) == len(cols) + 1:
            cols.append(j)
        if len(cols) == m:
            break
    return tuple(cols)


def sensitivities(sens, system, t0, y0, p) -> np.ndarray:
    """S(t0) (module docstring) flattened row-major, for the state ``y0`` (one state or
    rows of states) with the parameters ``p`` (one row, or one per row of ``y0``);
    ``sens``: the kernels of the run with sensitivities (its layout, its ``hol``)."""
    lay = sens.layout
    n, cols = lay.n_state, lay.sensitivity_columns
    y0 = np.asarray(y0, dtype=float)
    eye = np.eye(n, cols).ravel()
    m = len(system.holonomic)
    if not m:
        return np.broadcast_to(eye, y0.shape[:-1] + (n * cols,))
    rows = y0.reshape(-1, y0.shape[-1])
    P = np.atleast_2d(np.asarray(p, dtype=float))
    P = np.broadcast_to(P, (rows.shape[0], P.shape[1]))
    nq = len(system.J.q)
    out = np.empty((rows.shape[0], n, cols))
    for r in range(rows.shape[0]):
        _, G, dgdp = _evaluate(sens.hol, m, nq, t0, rows[r], P[r])
        S = out[r]
        S[:] = eye.reshape(n, cols)
        dep = list(_chosen(G, system))
        if len(dep) < m:        # singular at the start: the run itself says so
            continue
        ind = [j for j in range(nq) if j not in dep]
        rhs = np.zeros((m, cols))
        rhs[:, ind] = G[:, ind]
        if dgdp is not None:
            rhs[:, n:] = dgdp
        S[dep, :] = -np.linalg.solve(G[:, dep], rhs)
    return out.reshape(y0.shape[:-1] + (n * cols,))


def check_column(scene, to, t0, y0, p):
    """Refuse ``to`` as a column of sensitivities when it is a coordinate that follows
    from the holonomic constraints at (t0, y0) with the runtime parameters ``p``
    (``holonomic.completion_coordinates``, the chart of ``sensitivities``): its column
    is zero, it is no initial value of its own."""
    from ..errors import JetnhError
    from ..mechanics import holonomic

    system = scene.system
    if not system.holonomic or to not in {q.name for q in system.J.q}:
        return
    point = scene._holonomic_point(dict(zip(scene.state_names, np.asarray(y0).tolist())),
                                   float(t0), dict(zip(scene.runtime_params,
                                                       np.asarray(p).tolist())))
    try:
        followers = {q.name for q in holonomic.completion_coordinates(system, point)}
    except JetnhError:          # singular there: the run has said so
        return
    if to in followers:
        free = [q.name for q in system.J.q if q.name not in followers]
        raise JetnhError(
            f"sensitivity to {to!r}: on the holonomic constraints g = 0, "
            f"{', '.join(sorted(followers))} follow(s) from {', '.join(free)} at the start "
            f"(the split's chart), so {to!r} has no initial value of its own; "
            f"differentiate by {', '.join(free)} (their columns move {to!r} along g = 0)")
