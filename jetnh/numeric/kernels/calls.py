"""Kernels called from Python through their C callbacks.

A scene's kernels are compiled as C callbacks only (``numeric.codegen``): the integrators
call them by address, and an njit function beside each would compile the same body twice.
From Python, ``Kernel(address, sizes)(t, y, p, out)`` calls a callback through a
trampoline that takes its address as an integer (``_call_at``, an intrinsic that calls
the address with the C signature of the kernels): the trampolines are compiled once for
all scenes, on first use, and kept in jetnh's signed store (``loop_cache``, never numba's
own cache, whose files are read unchecked), and a call costs less than twice a call of an
njit function computing the same kernel (``benchmarks/kernel_call.py``; passing the
callback as a first-class function instead, numba unboxed it on every call, ten times
that).

Every array is checked before the callback reads it: its type, dtype, dimensions and
layout by numba's dispatcher (which takes C-contiguous float64 arrays of the declared
dimensions, the output writable, and nothing else; ``_explain`` names what was wrong), and
its size inside the trampoline, before the call (the kernels read and write without
bounds checks).
"""

from __future__ import annotations

import functools

import numba
import numpy as np
from numba import types
from numba.extending import intrinsic

from . import loop_cache
from ..methods._common import RHS_SIGNATURE, FunctionAddress
from ..methods.radau import JAC_SIGNATURE

_f8, _i8 = types.float64, types.int64
#: what a kernel reads (read-only arrays too: a frozen trajectory's) and what it writes
_IN1, _IN2 = (types.Array(_f8, n, "C", readonly=True) for n in (1, 2))
_OUT1, _OUT2 = _f8[::1], _f8[:, ::1]
_JIT = dict(error_model="numpy", nogil=True)


@intrinsic
def _call_at(typingctx, address, t, y, p, out):
    """Call the C callback at ``address`` (an integer) with ``(t, y, p, out)``: the
    arguments as the callback's C signature takes them (numba's first-class-function
    ABI: each array as its structure, by value)."""
    prototype = types.FunctionPrototype(types.void, (t, y, p, out))

    def codegen(context, builder, signature, args):
        function = builder.inttoptr(args[0], context.get_value_type(prototype))
        builder.call(function, args[1:])
        return context.get_dummy_value()

    return types.void(address, t, y, p, out), codegen


#: the sizes a kernel reads and writes travel as one integer, 21 bits each (one argument
#: instead of three: each argument of a call from Python costs)
_BITS = 21


def _pack(sizes) -> int:
    n_y, n_p, n_out = (int(n) for n in sizes)
    if not all(0 <= n < 1 << _BITS for n in (n_y, n_p, n_out)):
        raise ValueError(f"kernel sizes {sizes} out of range")
    return n_y | n_p << _BITS | n_out << 2 * _BITS


@numba.njit(inline="always")
def _fits(y_n, p_n, out_n, sizes):
    """Raise unless the arrays hold what the kernel reads and writes (``sizes``: the
    packed ``(n_y, n_p, n_out)``, ``_pack``)."""
    mask = (1 << _BITS) - 1
    n_y, n_p, n_out = sizes & mask, (sizes >> _BITS) & mask, sizes >> 2 * _BITS
    if y_n < n_y:
        raise ValueError("y (or a row of ys) has fewer entries than the kernel needs "
                         "(given, needed)", y_n, n_y)
    if p_n < n_p:
        raise ValueError("p has fewer entries than the kernel needs (given, needed)", p_n,
                         n_p)
    if out_n < n_out:
        raise ValueError("out (or J, or a row of out) has fewer entries than the kernel "
                         "needs (given, needed)", out_n, n_out)


def _call(address, sizes, t, y, p, out):
    _fits(y.shape[0], p.shape[0], out.shape[0], sizes)
    _call_at(address, t, y, p, out)


def _call_jac(address, sizes, t, y, p, J):
    _fits(y.shape[0], p.shape[0], min(J.shape[0], J.shape[1]), sizes)
    _call_at(address, t, y, p, J)


def _rows(address, sizes, ts, ys, p, out):
    _fits(ys.shape[1], p.shape[0], out.shape[1], sizes)
    if ys.shape[0] != ts.shape[0] or out.shape[0] < ts.shape[0]:
        raise ValueError("ys needs a row for each time and out at least as many (times, "
                         "rows of ys, rows of out)", ts.shape[0], ys.shape[0], out.shape[0])
    for i in range(ts.shape[0]):
        _call_at(address, ts[i], ys[i], p, out[i])


def _explain(names, dims):
    """The error for arguments a trampoline does not take: the first of ``names`` (the
    kernel's arguments, ``dims`` their dimensions, 0 a number; the last one written) that
    is not what the kernel reads or writes, and how to make it so."""
    def explain(*args):
        given = args[-len(names):]
        for name, ndim, a in zip(names, dims, given):
            if ndim == 0:
                if not isinstance(a, (int, float, np.integer, np.floating)):
                    raise TypeError(f"{name} must be a real number, got "
                                    f"{type(a).__name__}")
            elif not (isinstance(a, np.ndarray) and a.dtype == np.float64 and a.ndim == ndim
                      and a.flags.c_contiguous):
                raise TypeError(
                    f"{name} must be a C-contiguous float64 array of {ndim} "
                    f"dimension{'s' if ndim > 1 else ''} (np.ascontiguousarray(x, "
                    f"dtype=float)), got {type(a).__name__} {getattr(a, 'dtype', '')} "
                    f"{getattr(a, 'shape', '')}")
            elif name == names[-1] and not a.flags.writeable:
                raise TypeError(f"{name} is read-only, and the kernel writes it: pass a "
                                f"writable array ({name}.copy())")
        raise TypeError(f"the arguments {', '.join(names)} do not fit the kernel: "
                        f"{[type(a).__name__ for a in given]}")
    return explain


def _only_declared(dispatcher, names: str, dims):
    """``dispatcher`` called with its declared argument types only: numba's dispatcher
    compares the types of the arguments with them (in C, before anything is unboxed)
    and, with compilation disabled, converts nothing else; it then calls the
    dispatcher's ``_explain_matching_error``, here ``_explain`` (the argument, the fix)."""
    dispatcher.disable_compile()
    dispatcher._explain_matching_error = _explain(names.split(), dims)


#: each trampoline: its signature and its arguments for ``_explain``
_TRAMPOLINES = {
    _call: (types.void(_i8, _i8, _f8, _IN1, _IN1, _OUT1), "t y p out", (0, 1, 1, 1)),
    _call_jac: (types.void(_i8, _i8, _f8, _IN1, _IN1, _OUT2), "t y p J", (0, 1, 1, 2)),
    _rows: (types.void(_i8, _i8, _IN1, _IN2, _IN1, _OUT2), "ts ys p out", (1, 2, 1, 2)),
}


@functools.cache
def trampoline(py_func):
    """The compiled trampoline ``py_func`` (``_call``, ``_call_jac`` or ``_rows``):
    compiled, or loaded from the signed store, on first use; taking its declared
    argument types only (``_only_declared``)."""
    signature, names, dims = _TRAMPOLINES[py_func]
    dispatcher = loop_cache.signed_njit(py_func, signature, loop_cache.file_stamp(__file__),
                                        **_JIT)
    _only_declared(dispatcher, names, dims)
    return dispatcher


class Kernel(functools.partial):
    """``kernel(t, y, p, out)``: the C callback ``address`` (a ``FunctionAddress`` or a
    cfunc) called from Python; ``y``, ``p`` and ``out`` C-contiguous float64 arrays of at
    least ``sizes = (n_y, n_p, n_out)`` entries (``out`` an n_out x n_out matrix ``J`` for
    a Jacobian).  A ``functools.partial`` of the trampoline: calling it runs no Python
    code."""

    __slots__ = ()

    def __new__(cls, address, sizes, jacobian: bool = False):
        address = FunctionAddress(address, JAC_SIGNATURE if jacobian else RHS_SIGNATURE)
        self = super().__new__(cls, trampoline(_call_jac if jacobian else _call),
                               address.address, _pack(sizes))
        self.__dict__.update(address=address, sizes=tuple(sizes))
        return self


class Rows(functools.partial):
    """``rows(ts, ys, p, out)``: the kernel at every row, ``out[i] = kernel(ts[i], ys[i],
    p)`` (``sizes`` as for ``Kernel``)."""

    __slots__ = ()

    def __new__(cls, address, sizes):
        address = FunctionAddress(address)
        self = super().__new__(cls, trampoline(_rows), address.address, _pack(sizes))
        self.__dict__.update(address=address, sizes=tuple(sizes))
        return self


def jacobian_address(cfunc) -> FunctionAddress:
    """The ``FunctionAddress`` of a Jacobian callback (signature ``JAC_SIGNATURE``)."""
    return FunctionAddress(cfunc, JAC_SIGNATURE)
