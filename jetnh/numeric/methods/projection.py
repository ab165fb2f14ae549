"""Projection of an accepted step onto the holonomic constraints g(t, q) = 0.

The equations of a system with holonomic constraints use their derivatives D g = 0
(jetnh's dependent velocities solve them exactly), so g stays constant along the exact
flow, while a numerical step changes it by its local error: unchecked, |g| grows like
the global error.  After every accepted step the coordinates are moved orthogonally back
onto g = 0 by the simplified Gauss-Newton iteration of Hairer, Lubich & Wanner,
*Geometric Numerical Integration* (2006), section IV.4 (standard projection)::

    q <- q - G^T (G G^T)^{-1} g(t, q),   G = dg/dq at the current q,

until the correction is below the spacing of the floating-point numbers (at most
``MAX_ITERATIONS``).  The correction is of the size of the local error, so the method's
order is kept (HLW IV.4, Theorem 4.2).  Velocities need no projection: the dependent
velocities are no states but phi(t, q, qdot^mu), which solves D g = 0 exactly at every
state.  The step's dense output (``t_eval``) is the method's interpolant between two
projected states: on g = 0 to the interpolant's error, not to roundoff.  The iteration is
deterministic: a run is reproducible bit for bit.

``hol(t, y, p, out)`` is the generated kernel (``codegen``): ``out = (g_1..g_m, dg_i/dq^j
row by row)``.
"""

from __future__ import annotations

import math

import numpy as np

from ._common import jit

#: Gauss-Newton iterations per step (one or two suffice: the start is within the local
#: error of g = 0)
MAX_ITERATIONS = 8


@jit
def workspace(m, nq):
    """The arrays of ``project``: hol's output, G G^T, the multipliers."""
    m1 = max(m, 1)
    return np.empty(m1 * (1 + nq)), np.empty((m1, m1)), np.empty(m1)


@jit
def project(hol, m, nq, t, y, p, w, A, mu):
    """Move the coordinates y[:nq] onto g(t, q) = 0 (module docstring); returns the
    number of ``hol`` evaluations.  Leaves y as it is where G G^T is singular or a value
    is not finite (the position-level residual in the diagnostics then shows it)."""
    calls = 0
    for _ in range(MAX_ITERATIONS):
        hol(t, y, p, w)
        calls += 1
        for i in range(m):
            for k in range(m):
                acc = 0.0
                for j in range(nq):
                    acc += w[m + i * nq + j] * w[m + k * nq + j]
                A[i, k] = acc
            mu[i] = w[i]
        # Gaussian elimination with partial pivoting: (G G^T) mu = g
        for c in range(m):
            piv = c
            for r in range(c + 1, m):
                if abs(A[r, c]) > abs(A[piv, c]):
                    piv = r
            if not (abs(A[piv, c]) > 0.0) or not math.isfinite(A[piv, c]):
                return calls
            if piv != c:
                for k in range(m):
                    A[c, k], A[piv, k] = A[piv, k], A[c, k]
                mu[c], mu[piv] = mu[piv], mu[c]
            for r in range(c + 1, m):
                f = A[r, c] / A[c, c]
                for k in range(c, m):
                    A[r, k] -= f * A[c, k]
                mu[r] -= f * mu[c]
        for c in range(m - 1, -1, -1):
            acc = mu[c]
            for k in range(c + 1, m):
                acc -= A[c, k] * mu[k]
            mu[c] = acc / A[c, c]
        big = 0.0
        for j in range(nq):
            d = 0.0
            for i in range(m):
                d += w[m + i * nq + j] * mu[i]
            if not math.isfinite(d):
                return calls
            y[j] -= d
            big = max(big, abs(d) / max(1.0, abs(y[j])))
        if big <= 4.0 * 2.220446049250313e-16:
            break
    return calls
