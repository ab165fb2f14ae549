"""Compiled kernels: stored, loaded and called.

``store`` is the private signed disk store (it hands out verified bytes, never code);
``loader`` compiles them, or generates, compiles and stores new kernels
(``load(key, make_source)``); ``compiled`` is the record of a loaded module
(``CompiledKernels``); ``calls`` calls its C callbacks from Python; ``loop_cache`` keeps the
compiled integrator loops in the store (numba's cache files, signed).

``of(spec, persistent)`` is the kernels of a ``codegen.KernelSpec`` of the continuous
kinds; ``jacobian_kernels`` and ``sensitivity_kernels`` those of a scene with the
Jacobian of its right-hand side, and for runs with sensitivities.
"""

from __future__ import annotations

from .. import codegen
from .compiled import CompiledKernels
from .loader import clear, load
from .store import cache_root, info

__all__ = ["CompiledKernels", "load", "of", "jacobian_kernels", "sensitivity_kernels",
           "cache_root", "info", "clear"]


def of(spec: codegen.KernelSpec, persistent: bool = True) -> CompiledKernels:
    """The kernels of ``spec`` (variant "", "jacobian" or "sensitivities"): from memory,
    from the store, or generated (``codegen.generate``) and stored."""
    return load(spec.key, lambda: codegen.generate(spec), persistent=persistent)


def jacobian_kernels(scene) -> CompiledKernels:
    """The compiled kernels of ``scene`` with the Jacobian of its right-hand side:
    ``ck.jac(t, y, p, J)`` (``ck.jac_fp`` its C callback, signature
    ``layout.JAC_SIGNATURE``) writes ``J[i, j] = d rhs_i / d y_j`` for ``J`` a
    C-contiguous ``(n_state, n_state)`` float64 array.  Stored beside the scene's
    kernels (its own key)."""
    return of(_variant(scene.spec, "jacobian"), scene.cache)


def sensitivity_kernels(scene) -> CompiledKernels:
    """The compiled kernels of ``scene`` for a run with sensitivities: ``rhs_c`` of the
    state augmented by ``S = dy/d(y0, p)`` (n x m, m = n_state + n_runtime_params,
    row-major after the state; ``codegen.llvm.sensitivity_program``), ``jac_c`` radau's
    Jacobian of it, and the scene's ``aux_c`` and ``sing_c`` (which read the state
    alone).  Stored beside the scene's kernels (its own key)."""
    return of(_variant(scene.spec, "sensitivities"), scene.cache)


#: (spec, variant) -> the spec of that variant: a new spec computes its key (an srepr
#: of the system, milliseconds), which a run with sensitivities must not pay each time
_VARIANTS: dict = {}


def _variant(spec: codegen.KernelSpec, variant: str) -> codegen.KernelSpec:
    found = _VARIANTS.get((spec, variant))
    if found is None:
        if len(_VARIANTS) >= 256:
            _VARIANTS.clear()
        found = _VARIANTS[(spec, variant)] = spec.but(variant=variant)
    return found
