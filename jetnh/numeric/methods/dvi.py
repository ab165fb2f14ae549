"""Discrete vakonomic integrator (midpoint rule): a variational integrator for vakonomic
dynamics.

The discrete vakonomic principle of Benito & Martin de Diego (2005): the discrete action
of the extended Lagrangian ``L + lambda_a f^a`` with the constraints imposed in discrete
form::

    S_d = sum_k [ L_d(q_k, q_k+1) + lambda_k+1/2 . phi_d(q_k, q_k+1) ],
    L_d  = h L(t + h/2, (q_k + q_k+1)/2, (q_k+1 - q_k)/h),
    phi_d = h f(t + h/2, (q_k + q_k+1)/2, (q_k+1 - q_k)/h),

is stationary for variations of the interior q_k and of every multiplier
lambda_k+1/2 (one per step, living at the midpoint).  With the discrete momenta
``p_k = -D1 (L_d + lambda phi_d)(q_k, q_k+1) = D2 (L_d + lambda phi_d)(q_k-1, q_k)`` one
step maps (q_k, p_k) to (q_k+1, p_k+1, lambda_k+1/2)::

    p_k   = L_v - h/2 L_q + lambda.(f_v - h/2 f_q)       (n equations, at the midpoint)
    0     = f(midpoint)                                  (k equations)
    p_k+1 = L_v + h/2 L_q + lambda.(f_v + h/2 f_q)

solved by Newton's method with the exact Jacobian (generated symbolically,
``codegen.generate_dla(kind="vakonomic")``) for the increment q_k+1 - q_k.  It is the
midpoint variational integrator of the extended Lagrangian with the multipliers as
(discrete) coordinates, as in Colombo, Martin de Diego & Zuccalli (2010, 2013) for
optimal control.

- Order 2; symmetric; a variational integrator, so the discrete flow preserves the
  (pre)symplectic form of the extended system and, for autonomous L and f, shows no
  secular energy drift; the constraints hold exactly (to the Newton tolerance) at the
  midpoints, and to O(h^2) at the nodes.
- Holonomic constraints g(t, q) = 0 enter as their derivative D g at the midpoints, as
  in ``dla``: g(q_k) exact where g is quadratic, else O(h^3) a step.  The nodes are not
  projected onto g = 0 (a projection is not symplectic, HLW IV.4 and VI): a run whose
  nodes leave g = 0 says how far (``numeric.drift``).
- Initial momentum from the continuous initial state: p_0 = dL/dqdot + lambda(0) df/dqdot.
- Node values for output: q_k; the velocity (q_k+1 - q_k-1)/(2h) averaged from the two
  neighbouring midpoint velocities and lambda_k = (lambda_k-1/2 + lambda_k+1/2)/2 (both
  O(h^2)); at the last node, one extra step provides the right neighbour.
- Singular configurations: the node indicators of ``dla`` (constraints and Lagrangian as
  written), checked at every node; the run stops at the last regular node.

References: I. Benito, D. Martin de Diego, "Discrete vakonomic mechanics", J. Math. Phys.
46 (2005) 083521; L. Colombo, D. Martin de Diego, M. Zuccalli, "Optimal control of
underactuated mechanical systems: a geometrical approach", J. Math. Phys. 51 (2010)
083519; L. Colombo, F. Jimenez, D. Martin de Diego, "Discrete second-order Euler-Poincare
equations. Applications to optimal control", Int. J. Geom. Methods Mod. Phys. 9 (2012);
J. E. Marsden, M. West, "Discrete mechanics and variational integrators", Acta Numerica
10 (2001) 357-514.
"""

import numpy as np

from ._common import (ENDPOINTS, EVENT, FINISHED, NONFINITE, NOT_CONVERGED, RHS, SINGULAR,
                      STOPPED, all_finite, compiled, f8, i8, jit, store)
from ._events import node_events_start, node_terminal
from .dla import LEGENDRE, MOMENTUM, NODAL, STEP, node_init, node_violated
from .newton import solve_step

ORDER = 2


@jit
def _store(nodal, ts, ys, n_out, t, ql, v, p, n, k, nod, row):
    """Append the row (q, v, lambda, nodal(t, (q, lambda), v)) of one node."""
    nodal(t, ql, v, p, nod)
    for i in range(n):
        row[i] = ql[i]
        row[n + i] = v[i]
    for a in range(k):
        row[2 * n + a] = ql[n + a]
    for a in range(nod.shape[0]):
        row[2 * n + k + a] = nod[a]
    return store(ts, ys, n_out, t, row)


def _solve(step_residual, momentum, legendre, nodal, sing, uev, t0, t_end, q0, v0, lam0, p,
           n_steps, tol, max_iter, mode, n_sing, sing_tol, n_int, cols, ev_dir, ev_max, halt):
    """``n_steps`` steps from (q0, v0, lambda0).

    Returns ``(status, ts, ys, n_out, stats, t, y, sing_index, t_prev, y_prev)`` with rows
    ``ys = (q (n), v (n), lambda (k), f (k), E, integrals (n_int))`` at the nodes,
    ``stats = [steps, Newton iterations, 0]``, and the last regular node ``(t, y = (q, v,
    lambda))`` and the one before it.  The node indicators (``sing``, as in ``dla``) are
    checked at every node; the run stops at the last regular node (status SINGULAR).  User
    events as in ``dla``: a terminal one ends the run at the node after it (status EVENT).
    """
    n = q0.shape[0]
    k = lam0.shape[0]
    m = n + k
    h = (t_end - t0) / n_steps
    width = 2 * n + 2 * k + 1 + n_int
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
    nod = np.empty(k + 1 + n_int)
    dq_prev = np.zeros(n)            # q_k - q_k-1
    lam_prev = lam0.copy()           # lambda_k-1/2 (lambda(0) before the first step)
    g = np.empty(max(n_sing, 1))
    sig = np.empty(max(n_sing, 1))
    eps = np.empty(max(n_sing, 1))
    last = np.empty(2 * n + k)       # the last regular node (q, v, lambda) and the one before
    before = np.empty(2 * n + k)
    stats = np.zeros(3, dtype=np.int64)
    cap = 2 if mode == ENDPOINTS else n_steps + 1
    ts = np.empty(cap)
    ys = np.empty((cap, width))
    n_out = np.int64(0)
    legendre(t0, ql, v, p, pk, M)
    # the initial node: exact velocity and multiplier
    ts, ys, n_out = _store(nodal, ts, ys, n_out, t0, ql, v, p, n, k, nod, row)
    ystate, gu_old, gu_new, counts = node_events_start(uev, t0, row, cols, p,
                                                       ev_dir.shape[0])
    _pack(ql, v, n, k, last)
    _pack(ql, v, n, k, before)
    t_last = t0
    t_before = t0
    sing_index = node_init(sing, n_sing, sing_tol, t0, ql, v, p, g, sig, eps)
    status = FINISHED if sing_index < 0 else SINGULAR
    for i in range(n):
        z[i] = h * v[i]                  # z = (q_k+1 - q_k, lambda_k+1/2)
    for a in range(k):
        z[n + a] = lam0[a]
    t = t0
    # the extra step gives the last node's right side
    for step in range(n_steps + 1 if status == FINISHED else 0):
        if halt[0] != 0:
            status = STOPPED
            break
        if not solve_step(step_residual, t, h, q, pk, z, p, G, Jm, dz, n, m, tol, max_iter,
                       stats):
            if step == n_steps:              # extra step failed: one-sided last node
                for i in range(n):
                    z[i] = dq_prev[i]
                for a in range(k):
                    z[n + a] = lam_prev[a]
            else:
                status = NOT_CONVERGED if all_finite(z) else NONFINITE
                break
        if step > 0:
            # node k = step: q_k+1 - q_k-1 = z + dq_prev; lambda_prev (k-1/2), z[n:]
            for i in range(n):
                v[i] = (z[i] + dq_prev[i]) / (2.0 * h)
                ql[i] = q[i]
            for a in range(k):
                ql[n + a] = 0.5 * (lam_prev[a] + z[n + a])
            sing_index = node_violated(sing, n_sing, t, ql, v, p, g, sig, eps)
            if sing_index >= 0:
                status = SINGULAR
                break
            for i in range(2 * n + k):
                before[i] = last[i]
            _pack(ql, v, n, k, last)
            t_before = t_last
            t_last = t
            if mode != ENDPOINTS or step == n_steps:
                ts, ys, n_out = _store(nodal, ts, ys, n_out, t, ql, v, p, n, k, nod, row)
            if node_terminal(uev, t, row, cols, p, ystate, gu_old, gu_new, ev_dir, ev_max,
                             counts, step == 1):
                status = EVENT
                break
        if step == n_steps:
            break
        momentum(t, h, q, z, p, pk)
        for i in range(n):
            dq_prev[i] = z[i]                    # z[i] stays: the predictor of the next step
            q[i] += z[i]
        for a in range(k):
            lam_prev[a] = z[n + a]
        t = t0 + (step + 1) * h
        if not (all_finite(q) and all_finite(pk)):
            status = NONFINITE
            break
        stats[0] += 1
    if mode == ENDPOINTS and status != FINISHED and t_last != t0:
        for i in range(n):
            ql[i] = last[i]
            v[i] = last[n + i]
        for a in range(k):
            ql[n + a] = last[2 * n + a]
        ts, ys, n_out = _store(nodal, ts, ys, n_out, t_last, ql, v, p, n, k, nod, row)
    return status, ts, ys, n_out, stats, t_last, last, sing_index, t_before, before


@jit
def _pack(ql, v, n, k, out):
    """out = (q, v, lambda) from ql = (q, lambda) and v."""
    for i in range(n):
        out[i] = ql[i]
        out[n + i] = v[i]
    for a in range(k):
        out[2 * n + a] = ql[n + a]


ARGS = (STEP, MOMENTUM, LEGENDRE, NODAL, NODAL, RHS, f8, f8, f8[::1], f8[::1], f8[::1],
        f8[::1], i8, f8, i8, i8, i8, f8, i8, i8[::1], i8[::1], i8[::1], i8[::1])


def solver():
    """The compiled ``solve(step_residual, momentum, legendre, nodal, sing, uev, t0, t_end,
    q0, v0, lam0, p, n_steps, tol, max_iter, mode, n_sing, sing_tol, n_int, cols, ev_dir,
    ev_max, halt)``; ``halt[0]`` nonzero stops before the next step (STOPPED)."""
    return compiled(_solve, ARGS)
