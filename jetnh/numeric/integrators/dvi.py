"""Discrete vakonomic integrator (midpoint rule): a variational integrator for vakonomic
dynamics.

The discrete vakonomic principle of Benito & Martin de Diego (2005): the discrete action
of the extended Lagrangian ``L + lambda_a f^a`` with the constraints imposed in discrete
form,

    S_d = sum_k [ L_d(q_k, q_k+1) + lambda_k+1/2 . phi_d(q_k, q_k+1) ],
    L_d  = h L(t + h/2, (q_k + q_k+1)/2, (q_k+1 - q_k)/h),
    phi_d = h f(t + h/2, (q_k + q_k+1)/2, (q_k+1 - q_k)/h),

is stationary for variations of the interior q_k and of every multiplier
lambda_k+1/2 (one per step, living at the midpoint).  With the discrete momenta
``p_k = -D1 (L_d + lambda phi_d)(q_k, q_k+1) = D2 (L_d + lambda phi_d)(q_k-1, q_k)`` one
step maps (q_k, p_k) to (q_k+1, p_k+1, lambda_k+1/2):

    p_k   = L_v - h/2 L_q + lambda.(f_v - h/2 f_q)       (n equations, at the midpoint)
    0     = f(midpoint)                                  (k equations)
    p_k+1 = L_v + h/2 L_q + lambda.(f_v + h/2 f_q)

solved by Newton's method with the exact Jacobian (generated symbolically,
``codegen.generate_dla(kind="vakonomic")``).  It is the midpoint variational integrator
of the extended Lagrangian with the multipliers as (discrete) coordinates, as in
Colombo, Martin de Diego & Zuccalli (2010, 2013) for optimal control.

- Order 2; symmetric; a variational integrator, so the discrete flow preserves the
  (pre)symplectic form of the extended system and, for autonomous L and f, shows no
  secular energy drift; the constraints hold exactly (to the Newton tolerance) at the
  midpoints, and to O(h^2) at the nodes.
- Initial momentum from the continuous initial state: p_0 = dL/dqdot + lambda(0) df/dqdot.
- Node values for output: q_k; the velocity (q_k+1 - q_k-1)/(2h) averaged from the two
  neighbouring midpoint velocities and lambda_k = (lambda_k-1/2 + lambda_k+1/2)/2 (both
  O(h^2)); at the last node, one extra step provides the right neighbour.

References: I. Benito, D. Martin de Diego, "Discrete vakonomic mechanics", J. Math. Phys.
46 (2005) 083521; L. Colombo, D. Martin de Diego, M. Zuccalli, "Optimal control of
underactuated mechanical systems: a geometrical approach", J. Math. Phys. 51 (2010)
083519; L. Colombo, F. Jimenez, D. Martin de Diego, "Discrete second-order Euler-Poincare
equations. Applications to optimal control", Int. J. Geom. Methods Mod. Phys. 9 (2012);
J. E. Marsden, M. West, "Discrete mechanics and variational integrators", Acta Numerica
10 (2001) 357-514.
"""

import numpy as np

from ._common import (ENDPOINTS, FINISHED, NONFINITE, NOT_CONVERGED, all_finite, compiled,
                      f8, i8, jit, solve_linear, store)
from .dla import LEGENDRE, MOMENTUM, NODAL, STEP

ORDER = 2


@jit
def _newton(step_residual, t, h, q, pk, z, p, G, Jm, dz, n, m, tol, max_iter, stats):
    """Solve the step equations for z = (q1, lambda) from the predictor in z."""
    for it in range(max_iter):
        step_residual(t, h, q, pk, z, p, G, Jm)
        stats[1] += 1
        for i in range(m):
            G[i] = -G[i]
        if not solve_linear(Jm, G, dz):
            return False
        size = 0.0
        scale = 0.0
        for i in range(m):
            z[i] += dz[i]
            if i < n:
                size = max(size, abs(dz[i]))
                scale = max(scale, abs(z[i]))
        if not all_finite(z):
            return False
        if size <= tol * (1.0 + scale):
            return True
    return False


def _solve(step_residual, momentum, legendre, nodal, t0, t_end, q0, v0, lam0, p, n_steps,
           tol, max_iter, mode):
    """``n_steps`` steps from (q0, v0, lambda0).

    Returns ``(status, ts, ys, n_out, stats, t, y)`` with rows
    ``ys = (q (n), v (n), lambda (k), f (k), E)`` at the nodes and
    ``stats = [steps, Newton iterations, 0]``.
    """
    n = q0.shape[0]
    k = lam0.shape[0]
    m = n + k
    h = (t_end - t0) / n_steps
    width = 2 * n + 2 * k + 1
    ql = np.empty(m)                 # (q, lambda) for the node kernels
    for i in range(n):
        ql[i] = q0[i]
    for a in range(k):
        ql[n + a] = lam0[a]
    q = q0.copy()
    v = v0.copy()
    pk = np.empty(n)
    M = np.empty((n, n))
    z = np.empty(m)
    G = np.empty(m)
    Jm = np.empty((m, m))
    dz = np.empty(m)
    row = np.empty(width)
    nod = np.empty(k + 1)
    q_prev = q0.copy()               # q_k-1
    lam_prev = lam0.copy()           # lambda_k-1/2 (lambda(0) before the first step)
    stats = np.zeros(3, dtype=np.int64)
    cap = 2 if mode == ENDPOINTS else n_steps + 1
    ts = np.empty(cap)
    ys = np.empty((cap, width))
    n_out = np.int64(0)
    legendre(t0, ql, v, p, pk, M)
    # the initial node: exact velocity and multiplier
    nodal(t0, ql, v, p, nod)
    for i in range(n):
        row[i] = q[i]
        row[n + i] = v[i]
    for a in range(k):
        row[2 * n + a] = lam0[a]
    for a in range(k + 1):
        row[2 * n + k + a] = nod[a]
    ts, ys, n_out = store(ts, ys, n_out, t0, row)
    for i in range(n):
        z[i] = q[i] + h * v[i]
    for a in range(k):
        z[n + a] = lam0[a]
    status = FINISHED
    t = t0
    for step in range(n_steps + 1):          # the extra step gives the last node's right side
        if not _newton(step_residual, t, h, q, pk, z, p, G, Jm, dz, n, m, tol, max_iter,
                       stats):
            if step == n_steps:              # extra step failed: one-sided last node
                for i in range(n):
                    z[i] = 2.0 * q[i] - q_prev[i]
                for a in range(k):
                    z[n + a] = lam_prev[a]
            else:
                status = NOT_CONVERGED if all_finite(z) else NONFINITE
                break
        if step > 0:
            # node k = step: neighbours q_prev (k-1), z (k+1); lambda_prev (k-1/2), z[n:]
            for i in range(n):
                v[i] = (z[i] - q_prev[i]) / (2.0 * h)
                ql[i] = q[i]
            for a in range(k):
                ql[n + a] = 0.5 * (lam_prev[a] + z[n + a])
            if mode != ENDPOINTS or step == n_steps:
                nodal(t, ql, v, p, nod)
                for i in range(n):
                    row[i] = q[i]
                    row[n + i] = v[i]
                for a in range(k):
                    row[2 * n + a] = ql[n + a]
                for a in range(k + 1):
                    row[2 * n + k + a] = nod[a]
                ts, ys, n_out = store(ts, ys, n_out, t, row)
        if step == n_steps:
            break
        momentum(t, h, q, z, p, pk)
        for i in range(n):
            q_prev[i] = q[i]
            q[i] = z[i]
            z[i] = q[i] + (q[i] - q_prev[i])     # predictor for the next step
        for a in range(k):
            lam_prev[a] = z[n + a]
        t = t0 + (step + 1) * h
        if not (all_finite(q) and all_finite(pk)):
            status = NONFINITE
            break
        stats[0] += 1
    y = np.empty(2 * n + k)
    for i in range(n):
        y[i] = q[i]
        y[n + i] = v[i]
    for a in range(k):
        y[2 * n + a] = lam_prev[a]
    return status, ts, ys, n_out, stats, t, y


ARGS = (STEP, MOMENTUM, LEGENDRE, NODAL, f8, f8, f8[::1], f8[::1], f8[::1], f8[::1], i8, f8,
        i8, i8)


def solver():
    """The compiled ``solve(step_residual, momentum, legendre, nodal, t0, t_end, q0, v0,
    lam0, p, n_steps, tol, max_iter, mode)``."""
    return compiled(_solve, ARGS)
