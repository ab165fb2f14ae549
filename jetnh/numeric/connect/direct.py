"""A direct route towards the least-action motion of a vakonomic two-point problem: the
action minimised over a family of paths that meet the constraints, for a guess that
shooting then polishes (``solve.least_action``'s first restart, where the first answer
has conjugate times and so is no minimizer).

The family: each independent coordinate the straight line between its ends plus
``MODES`` sine modes (zero at both ends); the dependent coordinates integrated from the
constraints qdot^a = phi^a by the trapezoid rule on ``STEPS`` steps -- where phi does
not depend on them --, their ends equality constraints; the action by Simpson's rule;
scipy's SLSQP.  Its value bounds the least action from above (up to quadrature).  Where
L and the constraints do not depend on the dependent coordinates either, the composite
momenta P_a = d(L + lambda f)/dqdot^a are constant along an extremal and equal the
derivatives of the least action by the dependent ends, i.e. SLSQP's multipliers of those
ends: the multipliers at t0 solve (df/dqdot_dep)^T lambda = P - dL/dqdot_dep there.
"""

from __future__ import annotations

import numpy as np

#: sine modes per independent coordinate, quadrature steps
MODES, STEPS = 10, 400
#: SLSQP iterations
MAX_ITER = 300


def guess(search):
    """The unknowns (independent velocities, multipliers at t0) of the best path of the
    family for ``search``'s problem (every coordinate named in its end), or None where
    the problem is not of the kind above or SLSQP does not converge."""
    from scipy.optimize import approx_fprime, minimize

    from ...algebra import dag

    scene = search.scene
    system = scene.system
    J = system.J
    dep = list(system.dependent)
    ind = [J.split(v)[0] for v in system.independent_velocities]
    phi = [system.phi[v] for v in system.dependent_velocities]
    cyclic = not any(q in e.free_symbols for q in dep
                     for e in (system.L, *system.constraints, *phi))
    names = [q.name for q in J.q]
    if not cyclic or sorted(search.end_names) != sorted(names):
        return None
    start = dict(zip(scene.state_names, search.y0))
    end = dict(zip(search.end_names, search.target))
    t0, t1 = search.span
    t = np.linspace(t0, t1, STEPS + 1)
    T = t1 - t0
    k = np.arange(1, MODES + 1)
    sine = np.sin(np.pi * np.outer((t - t0) / T, k))
    dsine = np.pi / T * k * np.cos(np.pi * np.outer((t - t0) / T, k))
    params = {s: scene.params[s.name] for s in system.parameters}

    def path(z):
        Z = z.reshape(len(ind), MODES)
        point = {J.t: t, **params}
        for j, q in enumerate(ind):
            a, b = start[q.name], end[q.name]
            point[q] = a + (b - a) * (t - t0) / T + sine @ Z[j]
            point[J.jet(q, 1)] = (b - a) / T + dsine @ Z[j]
        for q, v, e in zip(dep, system.dependent_velocities,
                           dag.evaluate_numpy(phi, point)):
            e = np.broadcast_to(e, t.shape)
            point[v] = e
            point[q] = start[q.name] + np.concatenate(
                [[0.0], np.cumsum(0.5 * (e[1:] + e[:-1]) * np.diff(t))])
        return point

    w = np.full(STEPS + 1, 2.0)
    w[1::2], w[0], w[-1] = 4.0, 1.0, 1.0
    w *= T / STEPS / 3.0

    def action(z):
        (L,) = dag.evaluate_numpy([system.L], path(z))
        return float(w @ np.broadcast_to(L, w.shape))

    def ends(z):
        p = path(z)
        return np.array([p[q][-1] - end[q.name] for q in dep])

    with np.errstate(all="ignore"):
        r = minimize(action, np.zeros(len(ind) * MODES), method="SLSQP",
                     constraints=[{"type": "eq", "fun": ends}],
                     options={"maxiter": MAX_ITER, "ftol": 1e-12})
        if not r.success or not np.isfinite(r.fun):
            return None
        grad = approx_fprime(r.x, action, 1e-7)
        G = np.array([approx_fprime(r.x, lambda z, i=i: ends(z)[i], 1e-7)
                      for i in range(len(dep))]).reshape(len(dep), r.x.size)
    first = {s: (v[0] if np.ndim(v) else v) for s, v in path(r.x).items()}
    lam = []
    if dep:                                 # else no constraints, no multipliers
        P = np.linalg.lstsq(G.T, grad, rcond=None)[0]
        qd_dep = [J.jet(q, 1) for q in dep]
        cache = {}
        vals = dag.evaluate_numpy(
            [dag.diff(e, v, cache=cache) for e in (system.L, *system.constraints)
             for v in qd_dep], first)
        vals = np.array([float(v) for v in vals]).reshape(-1, len(dep))
        dL, A = vals[0], vals[1:]
        try:
            lam = np.linalg.solve(A.T, P - dL)
        except np.linalg.LinAlgError:
            return None
    u = np.array([float(first[v]) for v in system.independent_velocities] + list(lam))
    return u if len(u) == len(search.unknowns) and np.all(np.isfinite(u)) else None
