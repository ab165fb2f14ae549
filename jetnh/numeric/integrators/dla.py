"""Discrete Lagrange-d'Alembert integrator (midpoint rule) for Chetaev dynamics.

The nonholonomic integrator of Cortes & Martinez (2001) in the form of McLachlan &
Perlmutter (2006), with the midpoint discrete Lagrangian
``L_d(q0, q1) = h L(t + h/2, (q0 + q1)/2, (q1 - q0)/h)``, the discrete constraint
imposed at the midpoint, ``f(t + h/2, (q0 + q1)/2, (q1 - q0)/h) = 0``, and the Chetaev
reaction forces ``lambda_a df^a/dqdot`` evaluated there and split equally between the two
ends.  One step maps (q_k, p_k) to (q_k+1, p_k+1):

    p_k   = -D1 L_d(q_k, q_k+1) - h/2 lambda.A      (n equations)
    0     = f(midpoint)                             (k equations)   -> q_k+1, lambda
    p_k+1 =  D2 L_d(q_k, q_k+1) + h/2 lambda.A

solved by Newton's method with the exact Jacobian (generated symbolically).

- Order 2; symmetric (time-reversible), which is what gives nonholonomic integrators
  their good long-time behaviour (Modin & Verdier 2020); for L = T - V with constraints
  linear in the velocities the energy error stays bounded and the constraint residual
  at the nodes is O(h^2) and does not drift.
- Works for any Lagrangian and any (also nonlinear) constraints; cost per step: a Newton
  solve in n + k unknowns.
- Option ``project``: the node velocity of every step is projected onto the constraint
  set (nearest point in the kinetic metric, Gauss-Newton) and the momentum recomputed
  from it, so that the nodes satisfy the constraints to the Newton tolerance.  The
  projection is not symmetric, so the method is no longer time-reversible; its order and
  long-run behaviour are measured in tests/test_numeric_discrete.py.
- Node velocities (for output and diagnostics) by the inverse Legendre transform
  p = dL/dqdot(q, v), also by Newton.

References: J. Cortes, S. Martinez, "Non-holonomic integrators", Nonlinearity 14 (2001)
1365-1392; R. McLachlan, M. Perlmutter, "Integrators for nonholonomic mechanical
systems", J. Nonlinear Sci. 16 (2006) 283-328; K. Modin, O. Verdier, "What makes
nonholonomic integrators work?", Numer. Math. 145 (2020) 405-435.
"""


import numba
import numpy as np

from ._common import (
    ENDPOINTS, FINISHED, NONFINITE, NOT_CONVERGED, all_finite, compiled, f8, i8,
    solve_linear, store)

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


@numba.njit(cache=True, error_model="numpy", nogil=True)
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


def _solve(step_residual, momentum, legendre, nodal, constraint_jac, t0, t_end, q0, v0, p,
           n_steps, k, tol, max_iter, mode, project):
    """``n_steps`` steps from (q0, v0); with ``project`` the node velocity of every step
    is projected onto the constraints (``project_velocity``) and the momentum recomputed
    from it before the next step.

    Returns ``(status, ts, ys, n_out, stats, t, y)`` with rows
    ``ys = (q (n), v (n), f (k), E)`` and ``stats = [steps, Newton iterations, 0]``.
    """
    n = q0.shape[0]
    m = n + k
    h = (t_end - t0) / n_steps
    width = 2 * n + k + 1
    q = q0.copy()
    v = v0.copy()
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
    nod = np.empty(k + 1)
    fk = np.empty(k)
    Ak = np.empty((k, n))
    W = np.empty((n, max(k, 1)))
    S = np.empty((max(n, k), max(n, k)))
    mu = np.empty(max(n, k))
    rhs_p = np.empty(max(n, k))
    stats = np.zeros(3, dtype=np.int64)
    cap = 2 if mode == ENDPOINTS else n_steps + 1
    ts = np.empty(cap)
    ys = np.empty((cap, width))
    n_out = np.int64(0)
    legendre(t0, q, v, p, pk, M)
    t = t0
    nodal(t, q, v, p, nod)
    for i in range(n):
        row[i] = q[i]
        row[n + i] = v[i]
    for a in range(k + 1):
        row[2 * n + a] = nod[a]
    ts, ys, n_out = store(ts, ys, n_out, t, row)
    for i in range(n):
        z[i] = q[i] + h * v[i]
    for a in range(k):
        z[n + a] = 0.0
    status = FINISHED
    for step in range(n_steps):
        converged = False
        for it in range(max_iter):
            step_residual(t, h, q, pk, z, p, G, Jm)
            stats[1] += 1
            for i in range(m):
                G[i] = -G[i]
            if not solve_linear(Jm, G, dz):
                break
            size = 0.0
            scale = 0.0
            for i in range(m):
                z[i] += dz[i]
                if i < n:
                    size = max(size, abs(dz[i]))
                    scale = max(scale, abs(z[i]))
            if not all_finite(z):
                break
            if size <= tol * (1.0 + scale):
                converged = True
                break
        if not converged:
            status = NOT_CONVERGED if all_finite(z) else NONFINITE
            break
        momentum(t, h, q, z, p, pnew)
        for i in range(n):
            vbar = (z[i] - q[i]) / h
            v[i] = vbar
            q[i] = z[i]
            pk[i] = pnew[i]
            z[i] = q[i] + h * vbar           # predictor for the next step
        t = t0 + (step + 1) * h
        if not _inverse_legendre(legendre, t, q, pk, v, p, work, M, rhs_n, dv, tol, max_iter):
            status = NOT_CONVERGED
            break
        if project:
            if not project_velocity(constraint_jac, legendre, t, q, v, p, tol, max_iter, fk,
                                    Ak, M, W, S, work, rhs_p, mu):
                status = NOT_CONVERGED
                break
            legendre(t, q, v, p, pk, M)
        if not (all_finite(q) and all_finite(pk)):
            status = NONFINITE
            break
        stats[0] += 1
        if mode != ENDPOINTS or step == n_steps - 1:
            nodal(t, q, v, p, nod)
            for i in range(n):
                row[i] = q[i]
                row[n + i] = v[i]
            for a in range(k + 1):
                row[2 * n + a] = nod[a]
            ts, ys, n_out = store(ts, ys, n_out, t, row)
    y = np.empty(2 * n)
    for i in range(n):
        y[i] = q[i]
        y[n + i] = v[i]
    return status, ts, ys, n_out, stats, t, y


ARGS = (STEP, MOMENTUM, LEGENDRE, NODAL, LEGENDRE, f8, f8, f8[::1], f8[::1], f8[::1], i8, i8,
        f8, i8, i8, numba.types.boolean)
_inverse_legendre = numba.njit(cache=True, error_model="numpy", nogil=True)(_inverse_legendre)


def solver():
    """The compiled ``solve(step_residual, momentum, legendre, nodal, constraint_jac, t0,
    t_end, q0, v0, p, n_steps, k, tol, max_iter, mode, project)``."""
    return compiled(_solve, ARGS)
