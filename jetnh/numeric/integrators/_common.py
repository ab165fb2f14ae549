"""Numeric helpers shared by the compiled integrators (none of them calls the rhs).

Status codes returned by every ``solve``:

``FINISHED`` (0) reached the end of the interval; ``MAX_STEPS`` (1) stopped after the
allowed number of steps; ``TOO_SMALL_STEP`` (2) the step size fell below ten units in
the last place of t; ``NONFINITE`` (3) the right-hand side or the state became NaN or
infinite; ``NOT_CONVERGED`` (4) an implicit stage equation did not converge.
"""

import math

import numba
import numpy as np

FINISHED, MAX_STEPS, TOO_SMALL_STEP, NONFINITE, NOT_CONVERGED = 0, 1, 2, 3, 4

STATUS_TEXT = {
    FINISHED: "reached the end of the interval",
    MAX_STEPS: "stopped after max_steps steps",
    TOO_SMALL_STEP: "step size fell below the spacing of floating-point numbers",
    NONFINITE: "the state or the right-hand side became NaN or infinite",
    NOT_CONVERGED: "an implicit stage equation did not converge",
}

#: the step-size controller of Hairer-Norsett-Wanner II.4 with scipy's constants
SAFETY = 0.9
MIN_FACTOR = 0.2
MAX_FACTOR = 10.0

#: output modes
EVERY_STEP, AT_T_EVAL, ENDPOINTS = 0, 1, 2

jit = numba.njit(cache=True, error_model="numpy", nogil=True)


@jit
def rms_norm(x):
    """sqrt(mean(x**2)): the error norm of Hairer-Norsett-Wanner (II.4.11)."""
    s = 0.0
    for i in range(x.shape[0]):
        s += x[i] * x[i]
    return math.sqrt(s / x.shape[0]) if x.shape[0] else 0.0


@jit
def all_finite(x):
    for i in range(x.shape[0]):
        if not math.isfinite(x[i]):
            return False
    return True


@jit
def grow(ts, ys, n):
    """Make room for at least n + 1 rows, doubling the capacity."""
    if n < ts.shape[0]:
        return ts, ys
    cap = max(2 * ts.shape[0], 16)
    ts2 = np.empty(cap)
    ys2 = np.empty((cap, ys.shape[1]))
    for i in range(n):
        ts2[i] = ts[i]
        for j in range(ys.shape[1]):
            ys2[i, j] = ys[i, j]
    return ts2, ys2


@jit
def store(ts, ys, n, t, y):
    ts, ys = grow(ts, ys, n)
    ts[n] = t
    for j in range(y.shape[0]):
        ys[n, j] = y[j]
    return ts, ys, n + 1


@jit
def initial_step_h0(y0, f0, rtol, atol, interval, scale):
    """First half of the starting-step heuristic (Hairer-Norsett-Wanner II.4, p. 169):
    h0 from |y0| and |f0|; fills ``scale`` = atol + rtol |y0|."""
    for i in range(y0.shape[0]):
        scale[i] = atol[i] + abs(y0[i]) * rtol
    d0 = 0.0
    d1 = 0.0
    for i in range(y0.shape[0]):
        d0 += (y0[i] / scale[i]) ** 2
        d1 += (f0[i] / scale[i]) ** 2
    n = max(y0.shape[0], 1)
    d0 = math.sqrt(d0 / n)
    d1 = math.sqrt(d1 / n)
    if d0 < 1e-5 or d1 < 1e-5:
        h0 = 1e-6
    else:
        h0 = 0.01 * d0 / d1
    return min(h0, interval), d1


@jit
def initial_step_h1(f0, f1, h0, d1, scale, order, interval, max_step):
    """Second half: an explicit Euler step of size h0 estimates the second derivative."""
    d2 = 0.0
    for i in range(f0.shape[0]):
        d2 += ((f1[i] - f0[i]) / scale[i]) ** 2
    d2 = math.sqrt(d2 / max(f0.shape[0], 1)) / h0
    if d1 <= 1e-15 and d2 <= 1e-15:
        h1 = max(1e-6, h0 * 1e-3)
    else:
        h1 = (0.01 / max(d1, d2)) ** (1.0 / (order + 1))
    return min(100 * h0, h1, interval, max_step)


@jit
def copy_into(dst, src):
    """dst[:] = src as a loop (numba compiles slice assignment slowly)."""
    for i in range(src.shape[0]):
        dst[i] = src[i]


@jit
def min_step(t, direction):
    """Ten units in the last place of t in the direction of integration."""
    return 10.0 * abs(np.nextafter(t, direction * np.inf) - t)


# ---------------------------------------------------------------------- compiled entry points
f8 = numba.types.float64
i8 = numba.types.int64
#: the type of every right-hand side: rhs(t, y, p, out) -> None
RHS_SIGNATURE = numba.types.void(f8, f8[::1], f8[::1], f8[::1])
RHS = numba.types.FunctionType(RHS_SIGNATURE)

_COMPILED = {}


def compiled(pyfunc, argtypes):
    """``pyfunc`` compiled for ``argtypes`` on first use (cached on disk by numba).

    The right-hand side is an argument of type ``RHS`` (a first-class function), so the
    compiled loop does not depend on which scene calls it: one compilation serves all.
    """
    key = (pyfunc.__module__, pyfunc.__qualname__)
    if key not in _COMPILED:
        _COMPILED[key] = numba.njit(argtypes, cache=True, error_model="numpy",
                                    nogil=True)(pyfunc)
    return _COMPILED[key]


@jit
def solve_linear(A, b, x):
    """x = A^-1 b by Gaussian elimination with partial pivoting (A, b overwritten).
    Returns False if A is singular to working precision."""
    n = b.shape[0]
    for c in range(n):
        piv = c
        big = abs(A[c, c])
        for r in range(c + 1, n):
            if abs(A[r, c]) > big:
                big = abs(A[r, c])
                piv = r
        if big == 0.0 or not math.isfinite(big):
            return False
        if piv != c:
            for j in range(n):
                A[c, j], A[piv, j] = A[piv, j], A[c, j]
            b[c], b[piv] = b[piv], b[c]
        for r in range(c + 1, n):
            m = A[r, c] / A[c, c]
            if m != 0.0:
                for j in range(c, n):
                    A[r, j] -= m * A[c, j]
                b[r] -= m * b[c]
    for r in range(n - 1, -1, -1):
        s = b[r]
        for j in range(r + 1, n):
            s -= A[r, j] * x[j]
        x[r] = s / A[r, r]
    return True
