"""Discrete Lagrange-d'Alembert integrator (midpoint rule) for Chetaev dynamics.

The nonholonomic integrator of Cortes & Martinez (2001) in the form of McLachlan &
Perlmutter (2006), with the midpoint discrete Lagrangian
``L_d(q0, q1) = h L(t + h/2, (q0 + q1)/2, (q1 - q0)/h)``, the discrete constraint
imposed at the midpoint, ``f(t + h/2, (q0 + q1)/2, (q1 - q0)/h) = 0``, and the Chetaev
reaction forces ``lambda_a df^a/dqdot`` evaluated there and split equally between the two
ends.  One step maps (q_k, p_k) to (q_k+1, p_k+1)::

    p_k   = -D1 L_d(q_k, q_k+1) - h/2 lambda.A      (n equations)
    0     = f(midpoint)                             (k equations)   -> q_k+1, lambda
    p_k+1 =  D2 L_d(q_k, q_k+1) + h/2 lambda.A

solved by Newton's method with the exact Jacobian (generated symbolically), for the
increment q_k+1 - q_k (so that far from the origin the velocity loses no digits).

- Order 2; symmetric (time-reversible), which is what gives nonholonomic integrators
  their good long-time behaviour (Modin & Verdier 2020); for L = T - V with constraints
  linear in the velocities the energy error stays bounded and the constraint residual
  at the nodes is O(h^2) and does not drift.
- Works for any Lagrangian and any (also nonlinear) constraints; cost per step: a Newton
  solve in n + k unknowns.
- Option ``project``: the node velocity of every step is projected onto the constraint
  set (nearest point in the kinetic metric, Gauss-Newton) and the momentum recomputed
  from it, so that the nodes satisfy the constraints to the Newton tolerance; with
  holonomic constraints g(t, q) = 0 the node's coordinates are moved onto g = 0 first
  (``projection.onto``, the continuous methods' projection of a step).  The
  projection is not symmetric, so the method is no longer time-reversible; its order and
  long-run behaviour are measured in tests/test_numeric_discrete.py.
- Node velocities (for output and diagnostics) by the inverse Legendre transform
  p = dL/dqdot(q, v), also by Newton.  The step itself needs only (q, p), and p carries
  an O(h^2) error across the constraints that M^-1 (M = d^2L/dqdot^2) amplifies: for a
  Lagrangian degenerate or nearly so off the constraints but regular on them (the
  Chaplygin sleigh with I -> 0, where M is singular and K = I + m a^2 is not) the node
  velocity is instead the constrained transform p + mu.A = dL/dqdot, f = 0
  (``constrained_legendre``; well conditioned where the constrained motion is regular).
  The scene chooses it for the whole run where ||M^-1|| exceeds 100 ||S^-1||, S = [[M,
  A^T], [A, 0]] at the initial node, and the loop falls back to it wherever the plain
  transform fails to converge.
- Holonomic constraints g(t, q) = 0 enter as their derivative D g, imposed at the
  midpoint like every constraint: g(q_k) stays exact where g is quadratic (the midpoint
  rule integrates its linear gradient exactly), else it changes by O(h^3) a step.
  Without ``project`` the nodes are not projected onto g = 0 (an orthogonal projection
  is not symmetric and would cost the method its reversibility, HLW V.4); a run whose
  nodes leave g = 0 says how far (``numeric.drift``: a ``JetnhWarning``,
  ``holonomic_residual_max``).
- Singular configurations: the singularity indicators of the constraints and the
  Lagrangian as written (``codegen.discrete_indicators``; not the split: the step never
  solves for the dependent velocities) are checked at every node; the run stops at the
  last regular node, as the Runge-Kutta methods do.  A Newton failure next to a vanishing
  indicator, or where ``[[d^2L/dqdot^2, A^T], [A, 0]]`` is singular, is a singular stop
  too (``Scene._explain_discrete``).

References: J. Cortes, S. Martinez, "Non-holonomic integrators", Nonlinearity 14 (2001)
1365-1392; R. McLachlan, M. Perlmutter, "Integrators for nonholonomic mechanical
systems", J. Nonlinear Sci. 16 (2006) 283-328; K. Modin, O. Verdier, "What makes
nonholonomic integrators work?", Numer. Math. 145 (2020) 405-435.
"""


import math

import numba
import numpy as np

from ._common import (
    ENDPOINTS, EVENT, FINISHED, NONFINITE, NOT_CONVERGED, RHS, SINGULAR, STOPPED, all_finite,
    compiled, copy_into, f8, i8, jit, solve_linear, store)
from ._events import node_events_start, node_terminal
from .newton import solve_step
from .projection import onto, workspace

ORDER = 2

STEP = numba.types.FunctionType(numba.types.void(f8, f8, f8[::1], f8[::1], f8[::1], f8[::1],
                                                 f8[::1], f8[:, ::1]))
MOMENTUM = numba.types.FunctionType(numba.types.void(f8, f8, f8[::1], f8[::1], f8[::1],
                                                     f8[::1]))
LEGENDRE = numba.types.FunctionType(numba.types.void(f8, f8[::1], f8[::1], f8[::1], f8[::1],
                                                     f8[:, ::1]))
NODAL = numba.types.FunctionType(numba.types.void(f8, f8[::1], f8[::1], f8[::1], f8[::1]))


def _inverse_legendre(legendre, t, q, p_target, v, p, work, M, rhs, dv, tol, max_iter):
    """Solve dL/dqdot(t, q, v) = p_target for v (Newton from the given v)."""
    n = q.shape[0]
    for it in range(max_iter):
        legendre(t, q, v, p, work, M)
        for i in range(n):
            rhs[i] = p_target[i] - work[i]
        if not solve_linear(M, rhs, dv):
            return False
        size = 0.0
        scale = 0.0
        for i in range(n):
            v[i] += dv[i]
            size = max(size, abs(dv[i]))
            scale = max(scale, abs(v[i]))
        if size <= tol * (1.0 + scale):
            return True
    return False


@jit
def constrained_legendre(legendre, constraint_jac, t, q, p_target, v, p, tol, max_iter, M,
                         work, f, A, S, rhs, sol, mu):
    """Solve dL/dqdot(t, q, v) = p_target + A^T mu, f(t, q, v) = 0 for (v, mu), A =
    df/dqdot: the node velocity on the constraints when d^2L/dqdot^2 alone cannot be
    inverted (a Lagrangian degenerate off the constraints, regular on them).  Newton
    with the matrix [[M, -A^T], [A, 0]] (the constraints' curvature left out)."""
    n = v.shape[0]
    k = f.shape[0]
    for a in range(k):
        mu[a] = 0.0
    for it in range(max_iter):
        legendre(t, q, v, p, work, M)
        constraint_jac(t, q, v, p, f, A)
        for i in range(n):
            acc = p_target[i] - work[i]
            for a in range(k):
                acc += A[a, i] * mu[a]
            rhs[i] = acc
            for j in range(n):
                S[i, j] = M[i, j]
            for a in range(k):
                S[i, n + a] = -A[a, i]
                S[n + a, i] = A[a, i]
        for a in range(k):
            rhs[n + a] = -f[a]
            for b in range(k):
                S[n + a, n + b] = 0.0
        if not solve_linear(S, rhs, sol):
            return False
        size = 0.0
        scale = 0.0
        for i in range(n):
            v[i] += sol[i]
            size = max(size, abs(sol[i]))
            scale = max(scale, abs(v[i]))
        for a in range(k):
            mu[a] += sol[n + a]
        if not all_finite(v):
            return False
        if size <= tol * (1.0 + scale):
            return True
    return False


@jit
def project_velocity(constraint_jac, legendre, t, q, v, p, tol, max_iter, f, A, M, W, S,
                     work, rhs, mu):
    """Move v to the nearest point (in the metric of M = d^2F/dqdot^2) of the constraint
    set f(t, q, v) = 0, by Gauss-Newton: v -= M^-1 A^T (A M^-1 A^T)^-1 f.  Returns False
    if a linear solve fails or it does not converge."""
    n = v.shape[0]
    k = f.shape[0]
    if k == 0:
        return True
    for it in range(max_iter):
        constraint_jac(t, q, v, p, f, A)
        size = 0.0
        scale = 0.0
        for a in range(k):
            size = max(size, abs(f[a]))
        for i in range(n):
            scale = max(scale, abs(v[i]))
        if size <= tol * (1.0 + scale):
            return True
        legendre(t, q, v, p, work, M)
        for a in range(k):                       # W[:, a] = M^-1 A[a]
            for i in range(n):
                for j in range(n):
                    S[i, j] = M[i, j]
                rhs[i] = A[a, i]
            if not solve_linear(S[:n, :n], rhs, mu):
                return False
            for i in range(n):
                W[i, a] = mu[i]
        for a in range(k):                       # S = A W
            for b in range(k):
                acc = 0.0
                for i in range(n):
                    acc += A[a, i] * W[i, b]
                S[a, b] = acc
            rhs[a] = f[a]
        if not solve_linear(S[:k, :k], rhs[:k], mu[:k]):
            return False
        for i in range(n):
            acc = 0.0
            for a in range(k):
                acc += W[i, a] * mu[a]
            v[i] -= acc
    return False


@jit
def node_init(sing, n_sing, tol, t, q, v, p, g, sig, eps):
    """Signs and thresholds of the node indicators at the initial node (as
    ``_events.sing_init``); the index of one already zero or not finite there, else -1."""
    if n_sing == 0:
        return -1
    sing(t, q, v, p, g)
    for i in range(n_sing):
        if not math.isfinite(g[i]) or g[i] == 0.0:
            return i
        sig[i] = 1.0 if g[i] > 0.0 else -1.0
        eps[i] = tol * abs(g[i])
    return -1


@jit
def node_violated(sing, n_sing, t, q, v, p, g, sig, eps):
    """Index of the first node indicator at (t, q, v) that is not finite, has changed sign
    or has fallen below its threshold (``s_i g_i <= eps_i``), else -1."""
    if n_sing == 0:
        return -1
    sing(t, q, v, p, g)
    for i in range(n_sing):
        if not math.isfinite(g[i]) or sig[i] * g[i] <= eps[i]:
            return i
    return -1


@jit
def store_node(nodal, ts, ys, n_out, t, q, v, p, n, nod, row):
    """Append the row (q, v, nodal(t, q, v)) of one node."""
    nodal(t, q, v, p, nod)
    for i in range(n):
        row[i] = q[i]
        row[n + i] = v[i]
    for a in range(nod.shape[0]):
        row[2 * n + a] = nod[a]
    return store(ts, ys, n_out, t, row)


def _solve(step_residual, momentum, legendre, nodal, constraint_jac, sing, uev, hol, t0,
           t_end, q0, v0, p, n_steps, k, tol, max_iter, mode, project, n_hol, hol_state,
           n_sing, sing_tol, n_int, constrained, cols, ev_dir, ev_max, halt):
    """``n_steps`` steps from (q0, v0); with ``project`` the coordinates of every node
    are moved onto the ``n_hol`` holonomic constraints (``projection.onto`` with the
    continuous kernel ``hol`` on ``hol_state``, a state of the continuous scene whose
    coordinates are the node's), then its velocity onto the constraints
    (``project_velocity``) and the momentum recomputed from them before the next step.  Node velocities by the inverse Legendre transform, or
    (``constrained``, or where that fails) by ``constrained_legendre``.  The ``n_sing``
    node indicators (``sing``) are checked at every node: where one is not finite, changes
    sign or falls below ``sing_tol`` of its initial size, the run stops at the last regular
    node with status SINGULAR.  The user events ``uev`` (directions ``ev_dir``, terminal
    counts ``ev_max``; none if empty) are evaluated at every node on the state
    ``row[cols]``: the run ends with status EVENT at the node after a terminal one
    (``_events.node_terminal``).

    Returns ``(status, ts, ys, n_out, stats, t, y, sing_index, t_prev, y_prev)`` with rows
    ``ys = (q (n), v (n), f (k), E, integrals (n_int))``, ``stats = [steps, Newton
    iterations, 0]``, the last regular node ``(t, y = (q, v))`` and the one before it.
    """
    n = q0.shape[0]
    m = n + k
    h = (t_end - t0) / n_steps
    width = 2 * n + k + 1 + n_int
    q = q0.copy()
    v = v0.copy()
    q_old = q0.copy()
    v_old = v0.copy()
    pk = np.empty(n)
    pnew = np.empty(n)
    M = np.empty((n, n))
    work = np.empty(n)
    rhs_n = np.empty(n)
    dv = np.empty(n)
    z = np.empty(m)
    G = np.empty(m)
    Jm = np.empty((m, m))
    dz = np.empty(m)
    row = np.empty(width)
    nod = np.empty(k + 1 + n_int)
    fk = np.empty(k)
    Ak = np.empty((k, n))
    W = np.empty((n, max(k, 1)))
    S = np.empty((max(n, k), max(n, k)))
    mu = np.empty(max(n, k))
    rhs_p = np.empty(max(n, k))
    g = np.empty(max(n_sing, 1))
    sig = np.empty(max(n_sing, 1))
    eps = np.empty(max(n_sing, 1))
    v_try = np.empty(n)
    Sm = np.empty((m, m))
    rhs_m = np.empty(m)
    sol_m = np.empty(m)
    stats = np.zeros(3, dtype=np.int64)
    hw = workspace(n_hol, n, 0)
    cap = 2 if mode == ENDPOINTS else n_steps + 1
    ts = np.empty(cap)
    ys = np.empty((cap, width))
    n_out = np.int64(0)
    legendre(t0, q, v, p, pk, M)
    t = t0
    t_old = t0
    ts, ys, n_out = store_node(nodal, ts, ys, n_out, t, q, v, p, n, nod, row)
    ystate, gu_old, gu_new, counts = node_events_start(uev, t, row, cols, p,
                                                       ev_dir.shape[0])
    sing_index = node_init(sing, n_sing, sing_tol, t, q, v, p, g, sig, eps)
    status = FINISHED if sing_index < 0 else SINGULAR
    for i in range(n):
        z[i] = h * v[i]                      # z = (q_k+1 - q_k, lambda)
    for a in range(k):
        z[n + a] = 0.0
    for step in range(n_steps if status == FINISHED else 0):
        if halt[0] != 0:
            status = STOPPED
            break
        converged = solve_step(step_residual, t, h, q, pk, z, p, G, Jm, dz, n, m, tol,
                               max_iter, stats)
        if not converged:
            status = NOT_CONVERGED if all_finite(z) else NONFINITE
            break
        for i in range(n):
            q_old[i] = q[i]
            v_old[i] = v[i]
        t_old = t
        momentum(t, h, q, z, p, pnew)
        for i in range(n):
            v[i] = z[i] / h                  # z[i] stays: the predictor of the next step
            q[i] += z[i]
            pk[i] = pnew[i]
        t = t0 + (step + 1) * h
        if project and n_hol > 0:
            for i in range(n):
                hol_state[i] = q[i]
            onto(hol, n_hol, n, 0, t, hol_state, p, hw)
            for i in range(n):
                q[i] = hol_state[i]
        copy_into(v_try, v)
        if not constrained and _inverse_legendre(legendre, t, q, pk, v_try, p, work, M, rhs_n,
                                                 dv, tol, max_iter):
            copy_into(v, v_try)
        elif not constrained_legendre(legendre, constraint_jac, t, q, pk, v, p, tol, max_iter,
                                      M, work, fk, Ak, Sm, rhs_m, sol_m, mu):
            status = NOT_CONVERGED
        if status != FINISHED:
            pass
        elif project and not project_velocity(constraint_jac, legendre, t, q, v, p, tol,
                                               max_iter, fk, Ak, M, W, S, work, rhs_p, mu):
            status = NOT_CONVERGED
        elif not (all_finite(q) and all_finite(v) and all_finite(pk)):
            status = NONFINITE
        else:
            sing_index = node_violated(sing, n_sing, t, q, v, p, g, sig, eps)
            if sing_index >= 0:
                status = SINGULAR
        if status != FINISHED:               # back to the last regular node
            t = t_old
            for i in range(n):
                q[i] = q_old[i]
                v[i] = v_old[i]
            break
        if project:
            legendre(t, q, v, p, pk, M)
        stats[0] += 1
        if mode != ENDPOINTS or step == n_steps - 1:
            ts, ys, n_out = store_node(nodal, ts, ys, n_out, t, q, v, p, n, nod, row)
        if node_terminal(uev, t, row, cols, p, ystate, gu_old, gu_new, ev_dir, ev_max,
                         counts, step == 0):
            status = EVENT
            break
    if mode == ENDPOINTS and status != FINISHED and stats[0] > 0:
        ts, ys, n_out = store_node(nodal, ts, ys, n_out, t, q, v, p, n, nod, row)
    y = np.empty(2 * n)
    y_prev = np.empty(2 * n)
    for i in range(n):
        y[i] = q[i]
        y[n + i] = v[i]
        y_prev[i] = q_old[i]
        y_prev[n + i] = v_old[i]
    return status, ts, ys, n_out, stats, t, y, sing_index, t_old, y_prev


ARGS = (STEP, MOMENTUM, LEGENDRE, NODAL, LEGENDRE, NODAL, RHS, RHS, f8, f8, f8[::1],
        f8[::1], f8[::1], i8, i8, f8, i8, i8, numba.types.boolean, i8, f8[::1], i8, f8, i8,
        numba.types.boolean, i8[::1], i8[::1], i8[::1], i8[::1])
_inverse_legendre = jit(_inverse_legendre)


def solver():
    """The compiled ``solve(step_residual, momentum, legendre, nodal, constraint_jac, sing,
    uev, hol, t0, t_end, q0, v0, p, n_steps, k, tol, max_iter, mode, project, n_hol,
    hol_state, n_sing, sing_tol, n_int, constrained, cols, ev_dir, ev_max, halt)``; ``halt[0]`` nonzero stops before
    the next step (STOPPED)."""
    return compiled(_solve, ARGS)
