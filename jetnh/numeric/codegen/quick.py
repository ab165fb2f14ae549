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

A kernel is compiled quickly when its straight-line program has more instructions than the
threshold of its kind (``quick_ops``, ``decorator``), chosen by how often it is called:
``rhs`` at every stage of a step (``QUICK_OPS``); ``aux``, ``sing``, ``hol``, the user
events and connect's verdicts once a step or less (``QUICK_OPS // 8``); ``jac`` once a step
at most, and then beside an LU factorisation (``QUICK_OPS // 4``).  The -O3 route costs
four to six times the quick route's compile time per instruction at any size (its greedy
register allocation also grows faster than the kernel above ~6 000 instructions) and
saves about 0.3 ns per instruction and call, so it pays after some 10^5 calls whatever the
size: a kernel called once a step needs about ten times the steps an ``rhs`` needs.
Every catalogue model, and the N-trailer up to N = 8, keeps numba's ``-O3`` for ``rhs``,
``aux`` and ``sing`` (``jac`` too in the catalogue's defaults).  ``JETNH_QUICK_OPS`` (an
integer) moves the ``rhs`` threshold and the others with it; it is part of the kernel
cache key (``quick_ops``), the ratios part of the format of generated modules
(``layout.CODEGEN_VERSION``), and the choice is written in the kernel's source.  Numba
caches a quick callback like any other: its object code, in the kernel entry, under the
entry's manifest.
"""

from __future__ import annotations

import functools
import os
from functools import cached_property

from ...errors import JetnhError

#: ``rhs`` kernels (called at every stage) with more straight-line instructions than this
#: are compiled quickly; kernels called once a step or less at lower thresholds
#: (``quick_ops``)
QUICK_OPS = 8000

#: threshold of a kind, as a divisor of the ``rhs`` threshold: ``jac``, and the rest
#: (``aux``, ``sing``, ``hol``, ``events``, ``verdicts``: once a step or less)
_DIVISOR = {"rhs": 1, "jac": 4}
_ONCE_A_STEP = 8


def quick_ops(kind: str = "rhs") -> int:
    """The threshold in force for kernels of ``kind``: ``JETNH_QUICK_OPS`` (else
    ``QUICK_OPS``) divided by the kind's divisor (1 for ``rhs``, 4 for ``jac``, 8 for
    kernels called once a step or less)."""
    value = os.environ.get("JETNH_QUICK_OPS", "").strip()
    if not value:
        threshold = QUICK_OPS
    else:
        try:
            threshold = max(0, int(value))
        except ValueError:
            raise JetnhError(f"JETNH_QUICK_OPS={value!r} is not an integer; set it to the "
                             "number of instructions above which rhs kernels are compiled "
                             "quickly, or unset it for the default") from None
    return threshold // _DIVISOR.get(kind, _ONCE_A_STEP)


def decorator(n_ops: int, sig: str = "_SIG", kind: str | None = None) -> str:
    """The decorator line of a callback of ``kind`` whose program has ``n_ops``
    instructions (``kind`` by default "jac" for ``_JAC_SIG``, else "rhs")."""
    kind = kind or ("jac" if sig == "_JAC_SIG" else "rhs")
    name = "quick_cfunc" if n_ops > quick_ops(kind) else "numba.cfunc"
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
        jetnh_quick = True                      # read by ``llvm.straight_line``

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
