"""The verdicts kernel (``KernelSpec.variant == "verdicts"``): what connect's verdicts on
a motion found read at hundreds of times along it, compiled once per scene instead of
walking the expression graph at each time.

``verdicts(t, y, p, out)`` (its C callback ``verdicts_c``) writes, each block row-major
(``verdict_blocks``): the Lagrangian L; df/dq and df/dqdot (k x n each) of the
constraints f = 0; dphi/dq (k x n) and dphi/du (k x m) of the dependent velocities
phi(t, q, u), u the independent ones; dg/dq (h x n) of the holonomic constraints g = 0.
Expressions in t, the coordinates, every velocity (the dependent ones through phi) and
the parameters: nothing is derived but these first derivatives, by ``dag.jacobian`` on
the shared graph.
"""

from __future__ import annotations

from ...algebra import dag
from ..layout import CODEGEN_VERSION, JAC_SIGNATURE, SIGNATURE, Layout
from .continuous import HEADER, _function
from .prepare import Preparer
from .spec import KernelSource, KernelSpec


def verdict_blocks(system) -> dict:
    """Name -> ``slice`` of each block of the verdicts kernel's output (``L``, ``f_q``,
    ``f_qdot``, ``phi_q``, ``phi_u``, ``g_q``)."""
    n, k = len(system.J.q), system.k
    m, h = len(system.independent_velocities), len(system.holonomic)
    out, at = {}, 0
    for name, size in (("L", 1), ("f_q", k * n), ("f_qdot", k * n), ("phi_q", k * n),
                       ("phi_u", k * m), ("g_q", h * n)):
        out[name] = slice(at, at + size)
        at += size
    return out


def verdict_expressions(system) -> list:
    """The entries of the verdicts kernel, in the order of ``verdict_blocks``."""
    J = system.J
    q, us = list(J.q), list(system.independent_velocities)
    phis = [system.phi[v] for v in system.dependent_velocities]
    cache: dict = {}
    return ([system.L]
            + list(dag.jacobian(list(system.constraints), q, cache))
            + list(system.jacobian)
            + list(dag.jacobian(phis, q, cache)) + list(dag.jacobian(phis, us, cache))
            + list(dag.jacobian(list(system.holonomic), q, cache)))


def generate_verdicts(spec: KernelSpec, layout: Layout) -> KernelSource:
    """The kernel module of the verdicts kernel of ``spec``'s system (``layout``: the
    scene's)."""
    system = spec.system
    prepare = Preparer(system, spec.multipliers, spec.params, spec.runtime_params)
    phi_exprs = [prepare(system.phi[v], f"the dependent velocity {v}")
                 for v in system.dependent_velocities]
    exprs = prepare.many([(e, f"verdict entry {i}")
                          for i, e in enumerate(verdict_expressions(system))])
    src = [HEADER.format(version=CODEGEN_VERSION, key=spec.key, sig=SIGNATURE,
                         jac_sig=JAC_SIGNATURE)]
    src.append(_function("verdicts", layout, phi_exprs, exprs))
    return KernelSource(spec.key, layout, "\n".join(src))
