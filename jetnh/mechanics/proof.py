"""Symbolic proofs for generic systems: abstract L, f^a, phi^alpha, B^alpha_rho.

A generic system has an undefined Lagrangian L(t, q, qdot) and undefined constraint
functions, so an identity shown for it holds for every smooth system of that size.
sympy writes derivatives of undefined functions in several equivalent ways
(``Derivative(L(.., phi(..)), phi(..))``, ``Subs(Derivative(L(.., _xi), _xi), _xi, ..)``);
``canonical`` rewrites each as a function named by the slots it differentiates
(``L_4_6(args)`` = d^2 L / d slot4 d slot6), after which ``expand`` decides zero exactly.
A ``Proof`` records the statement, the steps used and the verdict: a step is checked
(its residuals are exactly zero, or for ``refute`` not) or a remark (prose, an inference
that is not machine-checked: ``holds`` None), and only checked steps decide the verdict.
"""

from __future__ import annotations

from dataclasses import dataclass, field

import sympy as sp
from sympy.core.function import AppliedUndef

from .system import System
from ..geometry.jet import JetSpace


def canonical(expr) -> sp.Expr:
    """Derivatives of undefined functions as slot-indexed undefined functions."""
    def visit(e):
        if isinstance(e, sp.Subs):
            inner, variables, values = e.args
            return visit(inner).xreplace(dict(zip(variables, values)))
        if isinstance(e, sp.Derivative) and isinstance(e.expr, AppliedUndef):
            F = e.expr
            slots = []
            for v, count in e.variable_count:
                idx = [i for i, a in enumerate(F.args) if a == v]
                if len(idx) != 1:
                    raise ValueError(f"cannot place the derivative variable {v} in {F}")
                slots += idx * count
            name = F.func.__name__ + "".join(f"_{i}" for i in sorted(slots))
            return sp.Function(name)(*[visit(a) for a in F.args])
        if e.args:
            return e.func(*[visit(a) for a in e.args])
        return e
    return visit(sp.sympify(expr, strict=True))


def is_zero(expr) -> bool:
    """Exact zero test for expressions in generic functions: canonical form, then expand
    (of the numerator over a common denominator when the expression has fractions)."""
    e = sp.expand(canonical(expr))
    return e == 0 or sp.expand(sp.numer(sp.together(e))) == 0


@dataclass
class Proof:
    """A statement proven (or refuted) for a generic system of a given size.

    ``steps``: (text, holds) with holds True/False for a checked step and None for a
    remark; ``holds``: every checked step holds, None while no step is checked (remarks
    prove nothing)."""

    statement: str
    n: int
    k: int
    steps: list = field(default_factory=list)
    holds: bool | None = None

    def step(self, text: str, residuals=()) -> bool | None:
        """Record a step; its residuals must all be exactly zero for it to hold.  Without
        residuals nothing is checked: the step is a remark (``remark``), holds None."""
        residuals = list(residuals)
        if not residuals:
            return self.remark(text)
        ok = all(is_zero(r) for r in residuals)
        self.steps.append((text, ok))
        self.holds = ok if self.holds is None else self.holds and ok
        return ok

    def remark(self, text: str) -> None:
        """Record prose that is not machine-checked (an inference from the checked
        steps, a reference): shown as such, never counted as proven."""
        self.steps.append((text, None))

    def refute(self, text: str, residuals) -> bool:
        """Record that a (printed) statement is false: some residual is not zero."""
        refuted = not all(is_zero(r) for r in residuals)
        self.steps.append((text, refuted))
        self.holds = refuted if self.holds is None else self.holds and refuted
        return refuted

    @property
    def checked(self) -> int:
        """How many steps were machine-checked (the others are remarks)."""
        return sum(ok is not None for _, ok in self.steps)

    def as_dict(self) -> dict:
        return {"statement": self.statement, "n": self.n, "k": self.k,
                "holds": self.holds,
                "steps": [{"step": s, "holds": ok, "checked": ok is not None}
                          for s, ok in self.steps]}


def generic_system(n: int, k: int, form: str = "explicit") -> System:
    """A system on n coordinates with k generic constraints; the last k are dependent.

    form: "implicit" f^a(t, q, qdot); "explicit" qdot^alpha - phi^alpha(t, q, qdot^mu);
    "affine" qdot^alpha - B^alpha_mu(t, q) qdot^mu - B^alpha_0(t, q).
    """
    J = JetSpace([f"q{i}" for i in range(1, n + 1)])
    t, q, qd = J.t, J.q, J.qd
    L = sp.Function("L")(t, *q, *qd)
    dep = q[n - k:]
    ind_v = qd[:n - k]
    if form == "implicit":
        cons = [sp.Function(f"f{a + 1}")(t, *q, *qd) for a in range(k)]
    elif form == "explicit":
        cons = [qd[n - k + a] - sp.Function(f"phi{a + 1}")(t, *q, *ind_v) for a in range(k)]
    elif form == "affine":
        cons = [qd[n - k + a] - sp.Function(f"B{a + 1}_0")(t, *q)
                - sp.Add(*[sp.Function(f"B{a + 1}_{m + 1}")(t, *q) * ind_v[m]
                           for m in range(n - k)]) for a in range(k)]
    else:
        raise ValueError(f"unknown form {form!r}")
    return System(J, L, cons, dep)
