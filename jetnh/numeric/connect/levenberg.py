"""Levenberg-Marquardt on F(u) = 0: the iteration (``levenberg_marquardt``, in Python: it
calls the shooting runs) and its step (``step``: the scaling, the SVD, the damped step and
its predicted decrease in one compiled call, kept in the signed store like the
integrator loops: a step costs a few microseconds instead of some thirty array calls)."""

from __future__ import annotations

import functools
import math

import numpy as np
from numba import types

from ...errors import ConnectError
from ..kernels import loop_cache
from ..methods._common import entry_point
from . import small

#: step() status: a step was made, F already met the tolerance, J has rank 0
STEP, CONVERGED, NO_RANK = 0, 1, 2


def _step(F, Jm, d, u, limit, mu, rcond, first, du):
    """One step of ``levenberg_marquardt`` from ``u`` with ``F = F(u)``, ``Jm = dF/du``,
    written into ``du``; returns ``(status, mu, s0, |F|^2, predicted decrease |F|^2 -
    |F + Jm du|^2)``.  ``d``: the column scales (the largest column norms of the
    Jacobians seen; ``first``: this one's), each at least 1e-6 of the largest, updated in
    place; ``mu`` < 0: 1e-6 s0^2, s0 the largest singular value of ``Jm / d``; the step
    is ``-D^-1 V diag(s / (s^2 + mu)) U^T F`` over the singular values above ``rcond``
    s0, shortened to at most max(1, |u|).  (Arrays are written, not returned: numba
    boxes a returned array through a pickle.)"""
    k, m = Jm.shape
    for i in range(k):
        if not abs(F[i]) <= limit[i]:
            break
    else:
        return CONVERGED, mu, 0.0, 0.0, 0.0
    top = 0.0
    for j in range(m):
        c = 0.0
        for i in range(k):
            c = math.hypot(c, Jm[i, j])
        du[j] = c                       # (the column norms, for now)
        top = max(top, c)
    for j in range(m):
        c = max(du[j], 1e-6 * top) if top > 0 else 1.0
        d[j] = c if first else max(c, d[j])
    A = np.empty((k, m))
    for i in range(k):
        for j in range(m):
            A[i, j] = Jm[i, j] / d[j]
    n_s = min(k, m)
    U, s, V = np.empty((k, n_s)), np.empty(n_s), np.empty((m, n_s))
    small.svd(A, U, s, V)
    r = 0
    if s.size and s[0] > 0:
        for a in range(s.size):
            if s[a] > rcond * s[0]:
                r += 1
    if r == 0:
        return NO_RANK, mu, 0.0, 0.0, 0.0
    if mu < 0:
        mu = 1e-6 * s[0] ** 2
    for j in range(m):
        du[j] = 0.0
    for a in range(r):
        c = 0.0
        for i in range(k):
            c += U[i, a] * F[i]
        c *= s[a] / (s[a] * s[a] + mu)
        for j in range(m):
            du[j] += c * V[j, a]
    size, uu = 0.0, 0.0
    for j in range(m):
        du[j] = -du[j] / d[j]
        size += du[j] * du[j]
        uu += u[j] * u[j]
    # at most the size of the unknowns (and 1): stay on the branch of solutions the
    # search starts near instead of jumping to a far one
    size = math.sqrt(size / max(1.0, uu))
    if size > 1.0:
        for j in range(m):
            du[j] /= size
    FF, LL = 0.0, 0.0
    for i in range(k):
        lin = F[i]
        for j in range(m):
            lin += Jm[i, j] * du[j]
        FF += F[i] * F[i]
        LL += lin * lin
    return STEP, mu, s[0], FF, FF - LL


_FLOAT = np.dtype(float)
_VEC = types.Array(types.float64, 1, "A")
_SIGNATURE = types.Tuple((types.int64, types.float64, types.float64, types.float64,
                          types.float64))(
    _VEC, types.Array(types.float64, 2, "A"), _VEC, _VEC, _VEC, types.float64,
    types.float64, types.boolean, _VEC)


@functools.cache
def step():
    """The compiled ``_step`` (compiled, or loaded from the signed store, on first
    use)."""
    stamp = loop_cache.file_stamp(__file__) + loop_cache.file_stamp(small.__file__)
    return loop_cache.signed_njit(_step, _SIGNATURE, stamp, error_model="numpy",
                                  nogil=True)


@functools.cache
def _step_entry():
    """The machine-code entry of ``step()`` (no type dispatch per call): called only
    with the declared types (``_fitted``'s arrays, floats and a bool)."""
    return entry_point(step())


def _fitted(got, n):
    """``(F, dF/du)`` as the compiled step reads them (float64 arrays), checked to
    fit ``n`` unknowns: it indexes them without bounds checks."""
    F, Jm = got[0], got[1]
    # (a float64 array's dtype is numpy's one instance of it, as a rule: compared first)
    if type(F) is not np.ndarray or (F.dtype is not _FLOAT and F.dtype != _FLOAT):
        F = np.asarray(F, dtype=float)
    if type(Jm) is not np.ndarray or (Jm.dtype is not _FLOAT and Jm.dtype != _FLOAT):
        Jm = np.asarray(Jm, dtype=float)
    if F.ndim != 1 or Jm.shape != (F.shape[0], n):
        raise ConnectError(f"internal: residuals of shape {F.shape} and a Jacobian of "
                           f"shape {Jm.shape} for {n} unknowns (please report this)")
    return F, Jm


def _scaled(got, n, inv):
    """``_fitted`` ``(F, dF/du)`` with each condition multiplied by its weight
    (``inv``; None: as they are)."""
    F, Jm = _fitted(got, n)
    return (F, Jm) if inv is None else (F * inv, Jm * inv[:, None])


def levenberg_marquardt(evaluate, u, scale, tol, max_iter, rcond, stuck=None,
                        weight=None):
    """Levenberg-Marquardt on F(u) = 0 (``evaluate(u)`` is ``(F, dF/du)``, or None
    where the runs fail), in unknowns scaled by the largest
    column norms of the Jacobian seen so far (More's scaling: the multipliers'
    columns are often orders of magnitude smaller than the velocities'): the step
    ``-D^-1 V diag(s / (s^2 + mu)) U^T F`` of the SVD of ``J D^-1`` truncated at
    ``rcond`` times its largest singular value (``step``)
    (mu -> 0: the minimum-norm Gauss-Newton step, quadratic convergence near a
    solution; mu large: a short step down the gradient), mu adapted by the ratio of
    the actual to the predicted decrease (Nielsen's rule), a failed run counted as no
    decrease; ``stuck(u, F, J)`` is told of every rejected step.  ``weight``: each
    condition's weight in |F|^2 (F and its row of J multiplied by it; default 1).
    Converged: max |F| / ``scale`` <= ``tol``; ``scale`` may be a function of the
    unknowns (``scale(u)``, read again at every accepted step).  Returns ``(u,
    converged, iterations)``."""
    got = evaluate(u)
    if got is None:
        return u, False, 0
    u = np.ascontiguousarray(u, dtype=float)
    inv = None if weight is None else np.asarray(weight, dtype=float)
    F, Jm = _scaled(got, u.size, inv)
    # converged: |F| <= limit (tol times the scale, weighted alike), entrywise
    limit = np.empty(F.shape)
    moving = scale if callable(scale) else None

    def bound(scale):
        limit[:] = tol * np.asarray(scale, dtype=float) * (1.0 if inv is None else inv)
    bound(scale if moving is None else moving(u))
    compiled = _step_entry()
    rcond = float(rcond)
    # (d is written by the first step before it is read)
    d, du, mu, nu = np.empty(len(u)), np.empty(len(u)), -1.0, 2.0
    for it in range(1, max_iter + 1):
        status, mu, s0, FF, predicted = compiled(F, Jm, d, u, limit, mu, rcond, it == 1,
                                                 du)
        if status == CONVERGED:
            return u, True, it - 1
        if status == NO_RANK:
            return u, False, it
        v = u + du
        trial = evaluate(v)
        rho = -1.0
        if trial is not None and predicted > 0:
            F_new = trial[0] if inv is None else np.asarray(trial[0], dtype=float) * inv
            rho = (FF - F_new.dot(F_new)) / predicted
        if rho > 0:
            u, (F, Jm) = v, _scaled(trial, u.size, inv)
            if moving is not None:
                bound(moving(u))
            mu *= max(1.0 / 3.0, 1.0 - (2.0 * rho - 1.0) ** 3)
            nu = 2.0
        else:
            if stuck is not None:
                stuck(u, F, Jm)
            mu *= nu
            nu *= 2.0
            if mu > 1e20 * s0 ** 2:          # no step of any length decreases |F|
                return u, False, it
    return u, bool((abs(F) <= limit).all()), max_iter
