"""Singularity indicators: the quantities whose vanishing makes the equations singular
(the ``sing`` kernels of the continuous and of the discrete methods compute them).

The shared walk over the graph lives in the symbolic core (``algebra.singular``:
``compare`` reports the same quantities).
"""

from __future__ import annotations

import sympy as sp

from ...algebra import dag, singular



def singular_indicators(system, accelerations, numbers,
                        memo: dict | None = None) -> list[tuple[str, sp.Expr]]:
    """``(kind, expression)`` of each singularity indicator, in the user's symbols with the
    compiled parameters (``numbers``: name -> number) substituted:

    - ``"split"``: det(df^a/dqdot^alpha) on the constraints (k <= 3; for larger k the
      determinant, or the LU pivots beyond k = 6, of the solve for phi appear among the
      next kind);
    - ``"constraint"``: denominators and fractional-power/log/... arguments of phi^alpha
      (a constraint not differentiable there, e.g. sqrt(xdot^2 + ydot^2) -> 0);
    - ``"acceleration"``: the same in the accelerations (``accelerations``: expressions),
      among them the determinant of the reduced mass matrix.

    Numbers are dropped, products split into factors and repeats (up to sign) removed.
    No simplification: a quantity is an indicator as the derivation wrote it.
    ``memo`` (a dict, filled here): the substitution's, ``dag.xreplace``'s ``memo``.
    """
    sub = {s: numbers[s.name] for s in system.parameters if s.name in numbers}
    found = []
    k = system.k
    if 0 < k <= 3:
        A = system.jacobian_dependent
        if any(not e.is_number for e in A):
            det = A[0, 0] if k == 1 else A.det(method="berkowitz")
            found.append(("split", system.on_constraints(det)))
    # one walk over each shared graph (one per expression would revisit the shared parts)
    phi = [system.phi[v] for v in system.dependent_velocities]
    found += [("constraint", b) for b in singular.bases(sp.Tuple(*phi))]
    found += [("acceleration", b) for b in singular.bases(sp.Tuple(*accelerations))]
    # one substitution for all: equal parts stay one object (no tree comparisons below)
    bases = dag.xreplace([b for _, b in found], sub, memo=memo)
    return _distinct_factors((kind, b) for (kind, _), b in zip(found, bases))


def _distinct_factors(found) -> list[tuple[str, sp.Expr]]:
    """``(kind, factor)`` of the ``(kind, base)`` pairs, each factor once (its first kind)."""
    out, seen = [], set()
    for kind, b in found:
        for f in singular.factors(b):
            if f not in seen:
                seen.add(f)
                out.append((kind, f))
    return out


def label(e, limit: int = 400) -> str:
    """An indicator as text: printed in full when its tree is short; a nested solve's
    pivot (whose tree can be exponentially long) by its shared size instead."""
    count, stack = 0, [e]
    while stack:
        count += 1
        if count > limit:
            return (f"a nested expression of {dag.size(e)} distinct subexpressions in "
                    + ", ".join(sorted(s.name for s in dag.free_symbols(e))))
        stack.extend(stack.pop().args)
    return sp.sstr(e)


def discrete_indicators(system, numbers) -> list[tuple[str, sp.Expr]]:
    """``(kind, expression)`` of the singularity indicators of the discrete integrators
    (dla, dvi), at a node (t, q, qdot): ``"constraint"``, the singular bases
    (``singular.bases``) of the constraints f^a as written, and ``"lagrangian"``, those of
    L -- with the compiled parameters (``numbers``) substituted.  The discrete step uses
    the implicit constraints, never the explicit form phi, so a singular split (the knife
    edge at cos(phi) = 0) is no singularity for it."""
    sub = {s: numbers[s.name] for s in system.parameters if s.name in numbers}
    return _distinct_factors(
        (kind, b) for kind, exprs in (("constraint", system.constraints),
                                      ("lagrangian", [system.L]))
        for e in exprs for b in singular.bases(sp.sympify(e, strict=True).xreplace(sub)))
