"""An initial state's floats checked and its dependent velocities, in one compiled call.

``floats()(route, t, y, p, aux)`` is the check ``Scene.replace`` makes of the most common
initial values, in one call instead of two kernel calls (``calls.Kernel``) and the Python
around them: whether the state ``y`` is finite, every singularity indicator of the
``sing`` kernel finite and at least ``MARGIN`` from zero, and the first ``n_dep`` outputs
of the ``aux`` kernel (phi^alpha) finite; each "finite" as Python's
``math.isfinite(sum(values))`` decides it (plain left-to-right double sums: a NaN, an
infinity or an overflow of the sum fails).  ``route`` (``route_of``) holds the kernels'
addresses and sizes: one argument for what is the same on every call of a scene (each
argument of a call from Python costs).  The kernels are called through the trampolines'
intrinsic (``calls._call_at``) after the same size checks (``calls._fits``); compiled
once for all scenes into the signed store (``loop_cache``).
"""

from __future__ import annotations

import functools
import math

import numpy as np
from numba import types

from . import loop_cache
from .calls import _IN1, _OUT1, _call_at, _fits

_f8, _i8 = types.float64, types.int64

#: the least ``|indicator|`` at which the check passes (``Scene._dependent_velocity_floats``)
MARGIN = 1e-6


def route_of(sing, aux, n_ind, n_dep) -> np.ndarray:
    """The ``route`` of ``floats()`` (read-only): the ``sing`` kernel's address and packed
    sizes (``calls.Kernel.args``; 0 and 0 where there is none), the ``aux`` kernel's,
    the numbers of indicators and of dependent velocities."""
    route = np.array([*((0, 0) if sing is None else sing.args), *aux.args, n_ind, n_dep],
                     dtype=np.int64)
    route.flags.writeable = False
    return route


def _floats(route, t, y, p, aux):
    """True where ``y`` is finite, every one of the ``n_ind`` entries of ``sing(t, y, p,
    g)`` (none where ``n_ind`` is 0) finite and of size at least ``MARGIN``, and the
    first ``n_dep`` entries of ``aux_of(t, y, p, aux)`` finite; False as soon as one is
    not (``aux`` then unset).  (Holding the GIL: a call of microseconds.)"""
    sing, sing_sizes, aux_of, aux_sizes, n_ind, n_dep = (
        route[0], route[1], route[2], route[3], route[4], route[5])
    s = 0.0
    for v in y:
        s += v
    if not math.isfinite(s):
        return False
    if n_ind:
        g = np.empty(n_ind)
        _fits(y.shape[0], p.shape[0], g.shape[0], sing_sizes)
        _call_at(sing, t, y, p, g)
        s = 0.0
        for v in g:
            s += v
        if not math.isfinite(s):
            return False
        for v in g:
            if not abs(v) >= MARGIN:
                return False
    _fits(y.shape[0], p.shape[0], aux.shape[0], aux_sizes)
    if n_dep > aux.shape[0]:
        raise ValueError("more dependent velocities than aux outputs (given, held)",
                         n_dep, aux.shape[0])
    _call_at(aux_of, t, y, p, aux)
    s = 0.0
    for i in range(n_dep):
        s += aux[i]
    return math.isfinite(s)


_SIGNATURE = types.boolean(types.Array(_i8, 1, "C", readonly=True), _f8, _IN1, _IN1, _OUT1)


@functools.cache
def floats():
    """The compiled ``_floats`` (compiled, or loaded from the signed store, on first use;
    its declared argument types only)."""
    return loop_cache.signed_njit(_floats, _SIGNATURE, loop_cache.file_stamp(__file__),
                                  error_model="numpy")
