"""Variation operators as vector fields on the jet bundle, with an explicit [d, delta].

A variation delta has components eta^s = delta q^s (fields with jets of their own) and a
commutator c^s = [d, delta] q^s = d/dt(delta q^s) - delta qdot^s, so that
delta qdot^s = D eta^s - c^s.  Zhao et al. (2008), section 2:

- free:        c = 0, no condition on eta;
- vakonomic:   c = 0 and delta f = 0, eq. (5);
- Hoelder:     c = 0 and the Chetaev condition df/dqdot^s eta^s = 0, eq. (7);
- Suslov:      delta f = 0 and the Chetaev condition, eq. (9); with c^mu = 0 (26) the
               commutator of the dependent coordinates follows from (10): (25), (27).

The variational identity that all of them satisfy is derived here, not copied::

    delta f + df/dqdot^s c^s - d/dt(df/dqdot^s eta^s) = [f]_s eta^s

(The paper's (3) prints df/dq^s in the second term; ``printed_identity_residual`` shows
that form fails.)
"""

from __future__ import annotations

from dataclasses import dataclass, field

import sympy as sp

from ..algebra import dag, linalg
from ..errors import PrincipleError
from .principles import named

KINDS = ("free", "vakonomic", "holder", "suslov")


def eta_symbols(J) -> tuple[sp.Symbol, ...]:
    """The variation components eta^s as field names ``eta_<coordinate>``."""
    return named("eta", J.q)


@dataclass(frozen=True)
class Variation:
    """A variation delta: ``eta`` = delta q^s, ``c`` = [d, delta] q^s, on jet space ``J``.

    ``J`` carries the eta fields (and any multipliers), so ``J.D`` acts on them.
    ``conditions`` maps the name of each condition the variation imposes to the tuple of
    residuals that must vanish.
    """

    kind: str
    system: System
    J: object
    eta: tuple
    c: tuple
    conditions: dict = field(default_factory=dict)
    paper: str = ""

    def velocity_components(self) -> tuple:
        """delta qdot^s = D(eta^s) - c^s."""
        return tuple(self.J.D(e) - c for e, c in zip(self.eta, self.c))

    def delta(self, F) -> sp.Expr:
        """delta F = dF/dq^s eta^s + dF/dqdot^s delta qdot^s for first-order F."""
        J = self.J
        dv = self.velocity_components()
        cache: dict = {}
        return sp.Add(*[dag.diff(F, q, cache=cache) * e + dag.diff(F, v, cache=cache) * w
                        for q, v, e, w in zip(J.q, J.qd, self.eta, dv)])

    def as_field(self):
        """The variation as a vector field on the jet bundle (components on q and qdot)."""
        from ..geometry.fields import VectorField

        comps = dict(zip(self.J.q, self.eta))
        comps.update(zip(self.J.qd, self.velocity_components()))
        return VectorField(self.J, comps)

    def residuals(self) -> dict[str, tuple]:
        """Each imposed condition's residuals (all zero when eta satisfies them)."""
        return {k: tuple(v) for k, v in self.conditions.items()}


def jet_space(system: System, multipliers=()):
    """The jet space of ``system``'s variations: its coordinates with the fields eta_<q>
    and the ``multipliers`` (Symbols or names)."""
    names = [s.name for s in eta_symbols(system.J)]
    names += [m if isinstance(m, str) else m.name for m in multipliers]
    return system.J.with_fields(tuple(names))


def _space(system: System, extra=()):
    return jet_space(system, extra), eta_symbols(system.J)


def _chetaev(system, J, eta):
    A = system.jacobian
    return tuple(sp.Add(*[A[a, s] * eta[s] for s in range(J.n)]) for a in range(system.k))


def euler_of_constraints(system: System, J=None, constraints=None) -> sp.Matrix:
    """[f^a]_s = df^a/dq^s - d/dt df^a/dqdot^s (k x n)."""
    J = J or system.J
    cons = system.constraints if constraints is None else constraints
    return sp.Matrix([list(J.euler(f, wrt=system.J.q)) for f in cons]) if cons else sp.zeros(0, J.n)


def defect(system: System, eta=None, J=None) -> tuple:
    """The equivalence defect (11): [f^a]_s delta q^s, one per constraint."""
    if J is None:
        J, etas = _space(system)
        eta = etas if eta is None else eta
    F = euler_of_constraints(system, J)
    return tuple(sp.Add(*[F[a, s] * eta[s] for s in range(J.n)]) for a in range(system.k))


def make(system: System, kind: str, eta=None, extra_fields=()) -> Variation:
    """The variation of ``kind`` ("free", "vakonomic", "holder", "suslov") for ``system``.

    ``eta`` defaults to generic fields eta_<q>.  For Suslov the commutator is the one
    determined by delta f = 0 and the Chetaev condition with c^mu = 0, (26)-(27); it is
    computed from the implicit constraints by (10): df/dqdot^alpha c^alpha = [f]_s eta^s.
    """
    if kind not in KINDS:
        raise PrincipleError(f"unknown variation {kind!r}; choose one of {KINDS}")
    J, etas = _space(system, extra_fields)
    eta = tuple(etas if eta is None else eta)
    zero = tuple(sp.S.Zero for _ in J.q)
    if kind == "free":
        return Variation(kind, system, J, eta, zero, {}, "(4)")
    if kind == "vakonomic":
        v = Variation(kind, system, J, eta, zero, {}, "(5)")
        return _with(v, {"delta f = 0": tuple(v.delta(f) for f in system.constraints)})
    if kind == "holder":
        return Variation(kind, system, J, eta, zero,
                         {"Chetaev condition": _chetaev(system, J, eta)}, "(7)")
    # Suslov: c^mu = 0 and A_alpha c^alpha = [f]_s eta^s (from (10))
    rhs = sp.Matrix(defect(system, eta, J))
    c_dep = linalg.solve(system.jacobian_dependent, rhs) if system.k else sp.zeros(0, 1)
    c = list(zero)
    for a, i in enumerate(system.dep_index):
        c[i] = c_dep[a]
    v = Variation(kind, system, J, eta, tuple(c),
                  {"Chetaev condition": _chetaev(system, J, eta)}, "(9)")
    return _with(v, {"delta f = 0": tuple(v.delta(f) for f in system.constraints)})


def _with(v: Variation, more: dict) -> Variation:
    return Variation(v.kind, v.system, v.J, v.eta, v.c, {**v.conditions, **more}, v.paper)


# ---------------------------------------------------------------------- identities
def identity_residual(v: Variation) -> tuple:
    """Derived identity: delta f + df/dqdot^s c^s - D(df/dqdot^s eta^s) - [f]_s eta^s (= 0)."""
    return _identity(v, lambda f, s: sp.diff(f, v.system.J.qd[s]))


def printed_identity_residual(v: Variation) -> tuple:
    """The paper's (3) as printed, with df/dq^s multiplying the commutator (not 0 in general)."""
    return _identity(v, lambda f, s: sp.diff(f, v.system.J.q[s]))


def _identity(v: Variation, coefficient) -> tuple:
    J, sysm = v.J, v.system
    F = euler_of_constraints(sysm, J)
    out = []
    for a, f in enumerate(sysm.constraints):
        chet = sp.Add(*[sp.diff(f, J.qd[s]) * v.eta[s] for s in range(J.n)])
        out.append(v.delta(f) + sp.Add(*[coefficient(f, s) * v.c[s] for s in range(J.n)])
                   - J.D(chet) - sp.Add(*[F[a, s] * v.eta[s] for s in range(J.n)]))
    return tuple(out)


def reduced_identity_residual(v: Variation) -> tuple:
    """The identity (3) reduced by the variation's own conditions: (6), (8) or (10).

    vakonomic (6):  D(df/dqdot eta) + [f] eta          (uses delta f = 0, c = 0)
    Hoelder   (8):  delta f - [f] eta                   (uses c = 0, Chetaev)
    Suslov   (10):  df/dqdot^s c^s - [f] eta            (uses delta f = 0, Chetaev)
    Each vanishes when eta satisfies the variation's conditions.
    """
    J, sysm = v.J, v.system
    eta = v.eta
    F = euler_of_constraints(sysm, J)
    out = []
    for a, f in enumerate(sysm.constraints):
        fe = sp.Add(*[F[a, s] * eta[s] for s in range(J.n)])
        chet = sp.Add(*[sp.diff(f, J.qd[s]) * eta[s] for s in range(J.n)])
        if v.kind == "vakonomic":
            out.append(J.D(chet) + fe)
        elif v.kind == "holder":
            out.append(v.delta(f) - fe)
        elif v.kind == "suslov":
            out.append(sp.Add(*[sp.diff(f, J.qd[s]) * v.c[s] for s in range(J.n)]) - fe)
        else:
            out.append(sp.S.Zero)
    return tuple(out)
