"""The change of chart at an edge in one compiled call (``numeric.atlas``'s ``switch`` of
a split whose multipliers keep their values).

``change(t, y, p, table, addr, eps, cur, out)`` does at the state ``y`` of chart ``cur``
what ``atlas._choose`` does in Python, with the same numbers: every velocity (the
dependent ones from the chart's aux kernel), df/dqdot (its Jacobian kernel), the measure
of every split (``atlas.measures_at``: the same sums and cofactors, k <= 3), then, in the
order of ``_choose`` (two splits: by index; more: by decreasing measure, ties by index),
the first split other than ``cur`` of measure at least ``2 eps`` whose aux kernel gives
back every velocity at the new state (relative 1e-8): its index, the new state written
to ``out`` (coordinates and multipliers copied, its independent velocities taken from
the velocities).  -1: no such split; ``-2 - i``: split ``i`` (``cur`` itself when its
own kernels are missing) has no kernels here yet (the caller builds its chart in Python
and asks again).

``table`` (int64) row 0: ``(n, k, n_state, n_p, N)``; row ``1 + i`` of split ``i``: the
positions of its dependent velocities (in the split's order, as its aux row gives them),
the columns of its minor (increasing), the positions of its independent velocities.
``addr`` (int64, 3 x N): each split's Jacobian and aux kernel addresses and its aux row's
length, 0 where not known.  The kernels are called by address (``kernels.calls``);
the arrays are checked against the sizes first.
"""

from __future__ import annotations

import functools

import numba
import numpy as np
from numba import types

from .kernels import calls, loop_cache
from .kernels.calls import _call_at

_f8, _i8 = types.float64, types.int64
#: what it reads (read-only arrays too) and writes
_IN1, _TABLE = types.Array(_f8, 1, "C", readonly=True), types.Array(_i8, 2, "C", readonly=True)
SIGNATURE = _i8(_f8, _IN1, _IN1, _TABLE, _TABLE, _f8, _i8, _f8[::1])


@numba.njit(inline="always")
def _det(M, k):
    """The determinant of the k x k matrix ``M`` (k <= 3) as ``atlas._det`` takes it."""
    if k == 1:
        return M[0, 0]
    if k == 2:
        return M[0, 0] * M[1, 1] - M[0, 1] * M[1, 0]
    a, b, c = M[0, 0], M[0, 1], M[0, 2]
    d, e, f = M[1, 0], M[1, 1], M[1, 2]
    g, h, i = M[2, 0], M[2, 1], M[2, 2]
    return a * (e * i - f * h) - b * (d * i - f * g) + c * (d * h - e * g)


def _change(t, y, p, table, addr, eps, cur, out):
    n, k, n_state, n_p, N = table[0, 0], table[0, 1], table[0, 2], table[0, 3], table[0, 4]
    if (y.shape[0] < n_state or out.shape[0] < n_state or p.shape[0] < n_p
            or table.shape[0] < N + 1 or table.shape[1] < k + n or addr.shape[0] < 3
            or addr.shape[1] < N or not 0 <= cur < N or not 1 <= k <= 3):
        raise ValueError("the arrays of a chart change do not fit its table")
    if addr[0, cur] == 0 or addr[1, cur] == 0:
        return -2 - cur
    A = np.empty(k * n)
    _call_at(addr[0, cur], t, y, p, A)
    aux = np.empty(max(addr[2, cur], k))
    _call_at(addr[1, cur], t, y, p, aux)
    qd = np.empty(n)                    # every velocity (``Chart.velocity_list``)
    row = table[1 + cur]
    for j in range(n - k):
        qd[row[2 * k + j]] = y[n + j]
    for j in range(k):
        qd[row[j]] = aux[j]
    # the measures (``measures_at``)
    m = np.zeros(N)
    if k == 1:
        gram = 0.0
        for a in range(n):
            gram += A[a] * A[a]
        if gram > 0.0:
            for i in range(N):
                c = A[table[1 + i, k]]
                m[i] = c * c / gram
    else:
        G = np.empty((k, k))
        for r in range(k):
            for s in range(k):
                acc = 0.0
                for a in range(n):
                    acc += A[r * n + a] * A[s * n + a]
                G[r, s] = acc
        gram = _det(G, k)
        if gram > 0.0:
            M = np.empty((k, k))
            for i in range(N):
                for r in range(k):
                    for s in range(k):
                        M[r, s] = A[r * n + table[1 + i, k + s]]
                d = _det(M, k)
                m[i] = d * d / gram
    order = np.arange(N)
    if N > 2:                           # by decreasing measure, ties by index (stable)
        for i in range(1, N):
            j = i
            while j > 0 and -m[order[j]] < -m[order[j - 1]]:
                order[j], order[j - 1] = order[j - 1], order[j]
                j -= 1
    for i in order:
        if i == cur or m[i] < 2.0 * eps:
            continue
        if addr[1, i] == 0:
            return -2 - i
        ind = table[1 + i]
        for j in range(n):
            out[j] = y[j]
        for j in range(n - k):
            out[n + j] = qd[ind[2 * k + j]]
        for j in range(2 * n - k, n_state):
            out[j] = y[j]
        aux_new = np.empty(max(addr[2, i], k))
        _call_at(addr[1, i], t, out, p, aux_new)
        back = np.empty(n)
        for j in range(n - k):
            back[ind[2 * k + j]] = out[n + j]
        for j in range(k):
            back[ind[j]] = aux_new[j]
        same = True
        for j in range(n):
            b = abs(qd[j])
            if not abs(back[j] - qd[j]) <= 1e-8 * (b if b > 1.0 else 1.0):
                same = False
                break
        if same:
            return i
    return -1


@functools.cache
def compiled():
    """``_change`` compiled (or loaded from the signed store) on first use, for
    ``SIGNATURE`` only (``jetnh cache warm`` compiles it ahead: ``atlas:change``),
    stamped with this file and ``kernels.calls`` (the kernels' calling convention,
    compiled into it)."""
    stamp = loop_cache.file_stamp(__file__) + loop_cache.file_stamp(calls.__file__)
    return loop_cache.signed_njit(_change, SIGNATURE, stamp, nogil=True,
                                  error_model="numpy")


@functools.cache
def change():
    """The machine-code entry of ``compiled()`` (``methods._common.entry_point``: no
    type dispatch, ~1.5 us a call), which takes exactly the types of ``SIGNATURE``
    (readable arrays; ``out`` writable): the caller checks what it is given
    (``atlas.Atlas.change``)."""
    from .methods._common import entry_point

    return entry_point(compiled())
