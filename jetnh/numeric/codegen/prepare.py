"""User expressions in kernel symbols: states ``s<i>``, dependent velocities ``v<a>``,
runtime parameters ``p<i>``, ``t``, and the compiled parameters as numbers.

The generated code is our own text (no user string is evaluated): user expressions are
sympy objects and reach the source only through the printer, with every symbol renamed to
a generated identifier; a symbol with no value, or an undefined function, is an error
naming it.
"""

from __future__ import annotations

import sympy as sp
from sympy.core.function import AppliedUndef

from ...algebra import dag
from ...errors import JetnhError


class Preparer:
    """Turns a user expression into kernel symbols: states -> s<i>, dependent velocities ->
    v<a>, runtime parameters -> p<i>, the compiled ones (``params``, name -> value) ->
    their numbers, t -> t.  Any other symbol, or an undefined function, is an error
    naming it."""

    def __init__(self, system, multipliers, params, runtime_params):
        J = system.J
        states = tuple(J.q) + tuple(system.independent_velocities) + tuple(multipliers)
        self.rename = {s: sp.Symbol(f"s{i}") for i, s in enumerate(states)}
        self.rename.update({v: sp.Symbol(f"v{a}")
                            for a, v in enumerate(system.dependent_velocities)})
        self.rename[J.t] = sp.Symbol("t")
        self.by_name = {name: sp.Symbol(f"p{i}") for i, name in enumerate(runtime_params)}
        #: parameter Symbol-name -> number (the compiled-in parameters)
        self.numbers = {name: number(v) for name, v in params.items()}
        self.by_name.update(self.numbers)
        self.names = {s.name: s for s in self.rename}
        #: the results of every call, one object per value (``dag.xreplace``)
        self.canon: dict = {}
        #: every subexpression substituted so far (the rule is the same in every call):
        #: the parts the rhs, aux and sing kernels share are rebuilt once
        self.memo: dict = {}

    def many(self, pairs) -> list:
        """``[self(expr, what) for expr, what in pairs]`` by one substitution over the
        graph of them all (shared parts rebuilt once); any error is reported by ``self``
        on the first expression that has it."""
        exprs = [sp.sympify(e, strict=True) for e, _ in pairs]
        sub, bad, undefined = self._rule(exprs)
        out = None if bad or undefined else dag.xreplace(exprs, sub, self.canon, self.memo)
        if out is None or dag.atoms(out, type(sp.nan), type(sp.zoo), type(sp.oo),
                                    type(sp.S.NegativeInfinity)):
            return [self(e, what) for e, what in pairs]
        return out

    def adopt(self, memo: dict):
        """Take the results of ``dag.xreplace``'s ``memo`` of a substitution of the
        compiled parameters alone (``numbers``) as known: what it made of a subexpression
        this preparer has substituted is substituted to the same result (the renaming
        applied after the numbers, as this preparer applies both at once)."""
        mine = self.memo
        for node, result, reached in list(memo.values()):
            done = mine.get(id(node))
            if reached and done is not None and done[2] and id(result) not in mine:
                mine[id(result)] = (result, done[1], True)

    def _rule(self, e):
        """The substitution for the symbols of ``e``, the names without a value, and the
        undefined functions (one walk of the graph)."""
        found = dag.nodes(e)
        sub, bad = {}, set()
        for s in {x for x in found if isinstance(x, sp.Symbol)}:
            if s in self.rename:
                sub[s] = self.rename[s]
            elif s.name in self.by_name:
                sub[s] = self.by_name[s.name]
            elif s.name in self.names:     # same name, other assumptions
                sub[s] = self.rename[self.names[s.name]]
            else:
                bad.add(s.name)
        return sub, bad, [x for x in found if isinstance(x, AppliedUndef)]

    def __call__(self, expr, what):
        e = sp.sympify(expr, strict=True)
        sub, bad, undefined = self._rule(e)
        if bad:
            raise JetnhError(
                f"{what} contains symbols with no value: {', '.join(sorted(bad))}; "
                "give them in params=")
        if undefined:
            raise JetnhError(f"{what} contains undefined functions {undefined}; "
                             "jetnh compiles explicit expressions only")
        out = dag.xreplace(e, sub, self.canon, self.memo)
        if dag.atoms(out, type(sp.nan), type(sp.zoo), type(sp.oo), type(sp.S.NegativeInfinity)):
            values = ", ".join(f"{k} = {v}" for k, v in sorted(self.numbers.items()))
            raise JetnhError(
                f"{what} is undefined for the parameter values {values}: substituting them "
                "divides by zero (or takes the log of zero) identically -- e.g. a Lagrangian "
                "degenerate for these values (a singular reduced mass matrix), or a constraint "
                "that cannot be solved for the dependent velocities; change the values, or "
                "pass the parameter in runtime_params= to find where the motion is singular")
        return out


def number(v) -> sp.Expr:
    """A parameter value as a sympy number: integral floats become Integers (so 1.0*x
    prints as x), others exact binary Floats."""
    v = float(v)
    return sp.Integer(int(v)) if v.is_integer() and abs(v) < 2**53 else sp.Float(v)
