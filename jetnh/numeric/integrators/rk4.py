"""The classical fourth-order Runge-Kutta method with a fixed step.

- Order 4; four right-hand-side evaluations per step; no error estimate.
- ``n_steps`` equal steps of ``h = (t_end - t0) / n_steps``.

Reference: W. Kutta, "Beitrag zur naeherungsweisen Integration totaler
Differentialgleichungen", Z. Math. Phys. 46 (1901) 435-453; E. Hairer, S. P. Norsett,
G. Wanner, *Solving Ordinary Differential Equations I*, section II.1.

``solver()`` returns the compiled ``solve(rhs, ...)``; ``rhs`` is a first-class numba
function (``_common.RHS``), so the loop is compiled once for every scene and cached on
disk, and only the right-hand side is compiled per scene.
"""

import numpy as np

from ._common import (
    ENDPOINTS, FINISHED, NONFINITE, RHS, all_finite, compiled, copy_into, f8, i8,
    store)

ORDER = 4
STAGES_PER_STEP = 4


def _solve(rhs, t0, t_end, y0, p, n_steps, mode):
    """``n_steps`` RK4 steps from t0 to t_end.

    Returns ``(status, ts, ys, n_out, stats, t, y)`` as the adaptive methods do
    (``stats = [steps, 0, rhs evaluations]``); ``mode`` ENDPOINTS stores only the ends.
    """
    n = y0.shape[0]
    h = (t_end - t0) / n_steps
    k1 = np.empty(n)
    k2 = np.empty(n)
    k3 = np.empty(n)
    k4 = np.empty(n)
    ytmp = np.empty(n)
    y = y0.copy()
    stats = np.zeros(3, dtype=np.int64)
    cap = 2 if mode == ENDPOINTS else n_steps + 1
    ts = np.empty(cap)
    ys = np.empty((cap, n))
    n_out = 0
    t = t0
    ts, ys, n_out = store(ts, ys, n_out, t, y)
    status = FINISHED
    for step in range(n_steps):
        rhs(t, y, p, k1)
        for i in range(n):
            ytmp[i] = y[i] + 0.5 * h * k1[i]
        rhs(t + 0.5 * h, ytmp, p, k2)
        for i in range(n):
            ytmp[i] = y[i] + 0.5 * h * k2[i]
        rhs(t + 0.5 * h, ytmp, p, k3)
        for i in range(n):
            ytmp[i] = y[i] + h * k3[i]
        rhs(t + h, ytmp, p, k4)
        stats[2] += 4
        for i in range(n):
            ytmp[i] = y[i] + h / 6.0 * (k1[i] + 2.0 * k2[i] + 2.0 * k3[i] + k4[i])
        if not all_finite(ytmp):
            status = NONFINITE
            break
        copy_into(y, ytmp)
        t = t0 + (step + 1) * h
        stats[0] += 1
        if mode != ENDPOINTS:
            ts, ys, n_out = store(ts, ys, n_out, t, y)
    if mode == ENDPOINTS:
        ts, ys, n_out = store(ts, ys, n_out, t, y)
    return status, ts, ys, n_out, stats, t, y


ARGS = (RHS, f8, f8, f8[::1], f8[::1], i8, i8)


def solver():
    """The compiled ``solve(rhs, t0, t_end, y0, p, n_steps, mode)``."""
    return compiled(_solve, ARGS)
