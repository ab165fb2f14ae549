"""Quick compilation of huge kernels: a numba C callback compiled with LLVM's light
optimisation (the ``-O1`` passes on the IR: on each function, then once on the module) and
its fastest code generation (``-O0``: fast instruction selection and the local register
allocator).

Numba compiles every function with LLVM's ``-O3`` code generation, whose greedy register
allocator takes most of a huge straight-line kernel's compile time, growing faster than
the kernel: on the N-trailer's vakonomic rhs, 1.0 CPU s at 6 169 instructions and 7.9 s
at 23 049 (about s^1.5), against 0.3 s and 0.8 s quick (linear), for a kernel about 2.2x
slower per call.  Both are the same arithmetic in the same order: no pass reassociates
floating-point operations (no fast-math), so the results are bit-for-bit equal.

A kernel is compiled quickly when its straight-line program has more than ``QUICK_OPS``
instructions (``decorator``); the kernels at or below it keep numba's ``-O3`` and their
per-call cost.  ``JETNH_QUICK_OPS`` (an integer) moves the threshold; it is part of the
kernel cache key (``quick_ops``), and the choice is written in the kernel's source.  Numba
caches a quick callback like any other: its object code, in the kernel entry, under the
entry's manifest.
"""

from __future__ import annotations

import functools
import os
from functools import cached_property

from ...errors import JetnhError

#: kernels with more straight-line instructions than this are compiled quickly
QUICK_OPS = 8000


def quick_ops() -> int:
    """The threshold in force: ``JETNH_QUICK_OPS`` if set, else ``QUICK_OPS``."""
    value = os.environ.get("JETNH_QUICK_OPS", "").strip()
    if not value:
        return QUICK_OPS
    try:
        return max(0, int(value))
    except ValueError:
        raise JetnhError(f"JETNH_QUICK_OPS={value!r} is not an integer; set it to the number "
                         "of instructions above which kernels are compiled quickly, or "
                         "unset it for the default") from None


def decorator(n_ops: int, sig: str = "_SIG") -> str:
    """The decorator line of a callback whose program has ``n_ops`` instructions."""
    name = "quick_cfunc" if n_ops > quick_ops() else "numba.cfunc"
    return f"@{name}({sig}, **_CB)"


@functools.lru_cache(maxsize=1)
def _quick_cfunc_class():
    """``numba.cfunc``'s class on a target whose code generator compiles quickly."""
    from numba.core import codegen, cpu, registry
    from numba.core.ccallback import CFunc

    class QuickCodegen(codegen.JITCPUCodegen):
        def _customize_tm_options(self, options):
            super()._customize_tm_options(options)
            options["opt"] = 0                  # code generation: -O0

        def _function_pass_manager(self, **kwargs):
            kwargs["opt"] = 1                   # IR passes: -O1 on each function, then
            return super()._function_pass_manager(**kwargs)

        def _module_pass_manager(self, **kwargs):
            # once more on the module (what the first round exposes: negations folded
            # into subtractions, then equal products), not twice (numba's "cheap" round)
            kwargs["opt"] = 0 if kwargs.get("cost") == "cheap" else 1
            return super()._module_pass_manager(**kwargs)

    class QuickContext(cpu.CPUContext):
        def init(self):
            super().init()
            self._internal_codegen = QuickCodegen("jetnh.quick")

    class QuickTarget(registry.CPUTarget):
        @cached_property
        def _toplevel_target_context(self):
            return QuickContext(self.typing_context, self._target_name)

        @cached_property
        def _toplevel_typing_context(self):
            return registry.cpu_target.typing_context

    class QuickCFunc(CFunc):
        _targetdescr = QuickTarget("cpu")

    return QuickCFunc


def quick_cfunc(sig, cache=False, **options):
    """``numba.cfunc(sig, cache=..., **options)`` compiled quickly (see the module)."""
    from numba.core import sigutils

    sig = sigutils.normalize_signature(sig)

    def wrap(func):
        res = _quick_cfunc_class()(func, sig, locals={}, options=options)
        if cache:
            res.enable_caching()
        res.compile()
        return res

    return wrap
