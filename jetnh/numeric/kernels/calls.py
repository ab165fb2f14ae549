"""Kernels called from Python through their C callbacks.

A scene's kernels are compiled as C callbacks only (``numeric.codegen``): the integrators call
them by address, and an njit function beside each would compile the same body twice.
From Python, ``Kernel(address)(t, y, p, out)`` calls a callback through a trampoline
that takes it as a first-class function; the trampolines are compiled once for all
scenes (and cached on disk by numba) and called at their machine-code entry.  A call from
Python costs about 3 us, mostly numba unboxing the first-class function (an njit call
with arrays costs about 0.2 us): well below a step of scipy's ``solve_ivp``, the one
caller per step; the compiled loops call the callbacks directly.
"""

from __future__ import annotations

import numba
import numpy as np

from ..methods._common import RHS, FunctionAddress, entry_point
from ..methods.radau import JAC, JAC_SIGNATURE

_f8 = numba.types.float64
_JIT = dict(cache=True, error_model="numpy", nogil=True)


@numba.njit(numba.types.void(RHS, _f8, _f8[::1], _f8[::1], _f8[::1]), **_JIT)
def _call(f, t, y, p, out):
    f(t, y, p, out)


@numba.njit(numba.types.void(RHS, _f8[::1], _f8[:, ::1], _f8[::1], _f8[:, ::1]), **_JIT)
def _rows(f, ts, ys, p, out):
    for i in range(ts.shape[0]):
        f(ts[i], ys[i], p, out[i])


@numba.njit(numba.types.void(JAC, _f8, _f8[::1], _f8[::1], _f8[:, ::1]), **_JIT)
def _call_jac(f, t, y, p, J):
    f(t, y, p, J)


def _check(name, a, ndim, size):
    """``a`` a C-contiguous float64 array of ``ndim`` dimensions with rows of at least
    ``size`` entries (a Jacobian ``J``: at least ``size`` rows too); the kernels read and
    write without bounds checks."""
    if not (isinstance(a, np.ndarray) and a.dtype == np.float64 and a.ndim == ndim
            and a.flags.c_contiguous):
        raise TypeError(f"{name} must be a C-contiguous float64 array of {ndim} "
                        f"dimension{'s' if ndim > 1 else ''} (np.ascontiguousarray(x, "
                        f"dtype=float)), got {type(a).__name__} "
                        f"{getattr(a, 'dtype', '')} {getattr(a, 'shape', '')}")
    if a.shape[-1] < size or (name == "J" and a.shape[0] < size):
        raise ValueError(f"{name} has shape {a.shape}; the kernel needs {size} entries "
                         f"per row")


class Kernel:
    """``kernel(t, y, p, out)``: the C callback ``address`` (a ``FunctionAddress``) called
    from Python; ``y``, ``p`` and ``out`` C-contiguous float64 arrays of at least
    ``sizes = (n_y, n_p, n_out)`` entries (``out`` an n_out x n_out matrix ``J`` for a
    Jacobian)."""

    __slots__ = ("address", "sizes", "_entry", "_out")

    def __init__(self, address: FunctionAddress, sizes, jacobian: bool = False):
        self.address, self.sizes = address, tuple(sizes)
        self._entry = entry_point(_call_jac if jacobian else _call)
        self._out = ("J", 2) if jacobian else ("out", 1)

    def __call__(self, t, y, p, out):
        n_y, n_p, n_out = self.sizes
        _check("y", y, 1, n_y)
        _check("p", p, 1, n_p)
        _check(self._out[0], out, self._out[1], n_out)
        self._entry(self.address, float(t), y, p, out)


class Rows:
    """``rows(ts, ys, p, out)``: the kernel at every row, ``out[i] = kernel(ts[i], ys[i],
    p)`` (``sizes`` as for ``Kernel``)."""

    __slots__ = ("address", "sizes", "_entry")

    def __init__(self, address: FunctionAddress, sizes):
        self.address, self.sizes = address, tuple(sizes)
        self._entry = entry_point(_rows)

    def __call__(self, ts, ys, p, out):
        n_y, n_p, n_out = self.sizes
        for name, a, ndim, size in (("ts", ts, 1, 0), ("ys", ys, 2, n_y), ("p", p, 1, n_p),
                                    ("out", out, 2, n_out)):
            _check(name, a, ndim, size)
        if not ys.shape[0] == ts.shape[0] <= out.shape[0]:
            raise ValueError(f"ys has {ys.shape[0]} rows and out {out.shape[0]} for "
                             f"{ts.shape[0]} times")
        self._entry(self.address, ts, ys, p, out)


def jacobian_address(cfunc) -> FunctionAddress:
    """The ``FunctionAddress`` of a Jacobian callback (signature ``JAC_SIGNATURE``)."""
    return FunctionAddress(cfunc, JAC_SIGNATURE)
