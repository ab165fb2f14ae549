"""The Jacobian d rhs / d y of a scene's right-hand side, from the symbolic derivation.

``symbolic_jacobian(scene)`` differentiates the expressions the generated ``rhs`` kernel
evaluates (``codegen.kernel_expressions``) with respect to the states -- never finite
differences -- and compiles ``jac(t, y, p, J)`` (``J[i, j] = d rhs_i / d y_j``) as a C
callback for radau.  The dependent velocities v_a = phi_a(t, y) stay symbols: by the chain
rule ``J = d out / d y + (d out / d v) (d phi / d y)``, so nothing is substituted into
anything (shared structure kept); ``cse`` over all entries.

Kernel packages that carry a generated ``jac_c`` (``CompiledKernels.jac_fp``) are used
instead (``Scene.jacobian``).
"""

from __future__ import annotations

import math

import numba
import numpy as np
import sympy as sp

from . import codegen
from .integrators._common import FunctionAddress
from .integrators.radau import JAC_SIGNATURE

_COMPILED: dict[str, FunctionAddress] = {}


def jacobian_source(phi_exprs, rhs_exprs, n_params: int) -> str:
    """Python source of ``jac(t, y, p, J)`` for the kernel expressions (symbols ``s<i>``
    states, ``v<a>`` dependent velocities, ``p<i>`` run-time parameters, ``t``)."""
    n = len(rhs_exprs)
    s = [sp.Symbol(f"s{i}") for i in range(n)]
    v = [sp.Symbol(f"v{a}") for a in range(len(phi_exprs))]
    w = [[sp.Symbol(f"w{a}_{j}") for j in range(n)] for a in range(len(phi_exprs))]
    lines = ["def jac(t, y, p, J):"]
    body = [f"s{i} = y[{i}]" for i in range(n)]
    body += [f"p{i} = p[{i}]" for i in range(n_params)]
    body += [f"J[{i}, :] = 0.0" for i in range(n)]
    # dependent velocities and their derivatives d phi_a / d s_j
    dphi = [sp.diff(ph, sj) for ph in phi_exprs for sj in s]
    if phi_exprs:
        reps, red = sp.cse(list(phi_exprs) + dphi, symbols=sp.numbered_symbols("d"))
        body += [f"{a} = {codegen.print_expr(e)}" for a, e in reps]
        k = len(phi_exprs)
        body += [f"v{a} = {codegen.print_expr(red[a])}" for a in range(k)]
        body += [f"w{a}_{j} = {codegen.print_expr(red[k + a * n + j])}"
                 for a in range(k) for j in range(n)]
    entries, where = [], []
    for i, out in enumerate(rhs_exprs):
        d_v = [sp.diff(out, va) for va in v]
        for j, sj in enumerate(s):
            e = sp.diff(out, sj) + sum((dv * w[a][j] for a, dv in enumerate(d_v) if dv != 0),
                                       sp.S.Zero)
            if e != 0:
                entries.append(e)
                where.append((i, j))
    reps, red = sp.cse(entries, symbols=sp.numbered_symbols("c"))
    body += [f"{a} = {codegen.print_expr(e)}" for a, e in reps]
    body += [f"J[{i}, {j}] = {codegen.print_expr(e)}" for (i, j), e in zip(where, red)]
    return "\n".join(lines + ["    " + b for b in body]) + "\n"


def symbolic_jacobian(scene) -> FunctionAddress:
    """``jac(t, y, p, J)`` of ``scene`` as a first-class function for radau (compiled
    once per scene key in this process)."""
    if scene.key not in _COMPILED:
        compiled_params = {k: v for k, v in scene.params.items()
                           if k not in scene.runtime_params}
        phi, out = codegen.kernel_expressions(scene.system, scene.principle, compiled_params,
                                              scene.runtime_params, scene.form,
                                              scene.convention)
        src = jacobian_source(phi, out, len(scene.runtime_params))
        space = {"math": math, "np": np}
        exec(compile(src, f"<jacobian of {scene.key[:12]}>", "exec"), space)  # noqa: S102
        _COMPILED[scene.key] = FunctionAddress(
            numba.cfunc(JAC_SIGNATURE, error_model="numpy")(space["jac"]), JAC_SIGNATURE)
    return _COMPILED[scene.key]
