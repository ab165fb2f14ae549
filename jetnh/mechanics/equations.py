"""Equations of motion from the composite action (12) under each variation, and Chetaev's.

Zhao et al. (2008), section 3.  The variation of A = int (L + lambda_a f^a) dt under any
variation delta (components eta^s, commutator c^s) is, after integration by parts, (13)::

    delta A = int { E_s eta^s - P_s c^s } dt + [P_s eta^s]_{t1}^{t2},
    E_s = [L]_s + lambda_a [f^a]_s - lambda_a_t df^a/dqdot^s,   P_s = dF/dqdot^s.

The equations are the coefficients of the independent eta's: with the paper's convention
(``convention="paper"``) every eta^s counts as independent after the commutator has been
used; with ``convention="imposed"`` the variation's Chetaev condition restricts eta to
eta^alpha = Phi^alpha_mu eta^mu first.  The coefficients are taken with the Euler
operator in the eta fields, so no printed formula is used.

Principles and forms (paper equation numbers; the registry is ``jetnh.mechanics.principles``):

- vakonomic: "multiplier" (15), "explicit" (17), "reduced" (18), "embedded" (20);
  affine: (36), (37).  The imposed convention gives the same equations (normal extremals).
- holder: the same as vakonomic in the paper's convention (22); imposed: the projection
  P^T([L] + lambda [f]) = 0 with lambda left arbitrary.
- suslov: "multiplier" (29), "reduced" (30), "embedded" (31); affine (38).  Imposed:
  (30b) alone, without multipliers.
- chetaev (Lagrange-d'Alembert): the action of L alone under Hoelder's variation, eta
  restricted in either convention: "maggi" P^T [L] = 0, "multiplier" [L]_s + nu_a
  df^a/dqdot^s = 0 with reactions nu, "voronets" on L~.

Generalized forces Q_s (``System(..., forces=..., dissipation=...)``) enter every
principle through their virtual work: the integrand of (13) gains Q_s eta^s, so every
row gains Q_s beside [L]_s; the projected rows gain P^T Q, and the forms on L~ the
embedded force Q_mu + Phi^alpha_mu Q_alpha on the constraints.
"""

from __future__ import annotations

import warnings
from dataclasses import dataclass
from functools import cached_property

import sympy as sp

from . import accelerations, principles
from ..algebra import dag, linalg
from ..frozen import Frozen
from ..errors import JetnhWarning, PrincipleError
from .principles import CONVENTIONS, EquationForm, Principle
from .principles import multiplier_symbols  # noqa: F401 -- kept importable from here
from .variations import Variation, jet_space, make

#: each principle's forms (``jetnh.mechanics.principles``), by canonical name
FORMS = {p.name: tuple(f.name for f in p.forms) for p in principles.REGISTRY}


# ---------------------------------------------------------------------- (13)
@dataclass(frozen=True)
class ActionVariation:
    """delta (L + lambda f) = integrand + D(boundary): eq. (13) before integrating over t."""

    variation: Variation
    lagrangian: sp.Expr          # F = L + lambda_a f^a
    E: tuple                     # [L]_s + lambda [f]_s - lambda_t df/dqdot^s
    P: tuple                     # dF/dqdot^s
    integrand: sp.Expr           # E_s eta^s - P_s c^s
    boundary: sp.Expr            # P_s eta^s: dropped by the end conditions (1)

    def residual(self) -> sp.Expr:
        """delta F - D(boundary) - integrand: zero (expand) when (13) holds."""
        v = self.variation
        return v.delta(self.lagrangian) - v.J.D(self.boundary) - self.integrand


def action_variation(system: System, variation: Variation, multipliers=()) -> ActionVariation:
    """The variation of the composite action (12) under ``variation``, as in (13)."""
    J = variation.J
    F = system.L + sp.Add(*[lam * f for lam, f in zip(multipliers, system.constraints)])
    E = J.euler(F, wrt=J.q)
    P = tuple(dag.diff(F, v) for v in J.qd)
    eta, c = variation.eta, variation.c
    integrand = sp.Add(*[E[s] * eta[s] - P[s] * c[s] for s in range(J.n)])
    boundary = sp.Add(*[P[s] * eta[s] for s in range(J.n)])
    return ActionVariation(variation, F, E, P, integrand, boundary)


def stationarity(system: System, variation: Variation, multipliers=(), restrict=False):
    """Coefficients of the independent eta's in the integrand of (13).

    ``restrict``: impose the Chetaev condition first (eta^alpha = Phi^alpha_mu eta^mu with
    Phi = -A_alpha^-1 A_mu from the constraint Jacobian); the result then has one
    equation per independent coordinate.
    """
    av = action_variation(system, variation, multipliers)
    J, eta = variation.J, variation.eta
    integrand = av.integrand + virtual_work(system, eta)
    wrt = eta
    if restrict:
        admissible = chetaev_admissible(system, eta)
        integrand = integrand.xreplace({eta[s]: admissible[s] for s in system.dep_index})
        wrt = tuple(eta[i] for i in system.ind_index)
    return J.euler(integrand, wrt=wrt)


def virtual_work(system: System, eta) -> sp.Expr:
    """Q_s eta^s: the virtual work of the generalized forces."""
    return sp.Add(*[Q * e for Q, e in zip(system.Q, eta)])


def chetaev_admissible(system: System, eta) -> tuple:
    """eta restricted to the Chetaev subspace ker(df/dqdot): P eta^mu, the independent
    components kept, the dependent ones eta^alpha = Phi^alpha_mu eta^mu."""
    N = null_basis(system)
    ind = [eta[i] for i in system.ind_index]
    return tuple(sp.Add(*[N[s, m] * ind[m] for m in range(len(ind))]) for s in range(system.J.n))


def null_basis(system: System) -> sp.Matrix:
    """P (n x (n-k)): columns span ker df/dqdot; rows of independent coordinates are I."""
    ind = list(system.ind_index)
    Phi = (-linalg.solve(system.jacobian_dependent, system.jacobian[:, ind]) if system.k
           else sp.zeros(0, len(ind)))
    return linalg.embed(Phi, ind, system.dep_index)


# ---------------------------------------------------------------------- results
class Equations(Frozen):
    """The equations of motion of one principle in one form; each expression means = 0.

    ``multipliers`` are the Lagrange multipliers that are states (vakonomic, Hoelder,
    Suslov); ``reactions`` are the algebraic multipliers of Chetaev's multiplier form.
    ``accelerations()`` solves the principle (not merely this form) for the
    accelerations and multiplier rates (``jetnh.mechanics.accelerations``).  Both the expressions
    and the accelerations are computed on first use.  Immutable (``jetnh.frozen``).
    """

    def __init__(self, system, principle, form, convention, expressions, multipliers=(),
                 reactions=(), arbitrary=(), J=None, paper="", explicit=False, solver=None):
        self.system = system
        self.principle = principle
        self.form = form
        self.convention = convention
        self._build = expressions if callable(expressions) else (lambda: expressions)
        self.multipliers = tuple(multipliers)
        self.reactions = tuple(reactions)
        self.arbitrary = tuple(arbitrary)
        self.J = J or system.J
        self.paper = paper
        self.explicit = explicit
        self._solver = solver

    @cached_property
    def expressions(self) -> tuple:
        return tuple(self._build())

    @cached_property
    def constraints(self) -> tuple:
        """The constraints the multipliers belong to (explicit ones for explicit forms)."""
        s = self.system
        return s.explicit_constraints if self.explicit else s.constraints

    @cached_property
    def multiplier_rates(self) -> tuple[sp.Symbol, ...]:
        return tuple(self.J.jet(m, 1) for m in self.multipliers)

    def accelerations(self) -> accelerations.Accelerations:
        """Every J.qdd[s] and multiplier rate -> expression in t, q, qdot, multipliers, parameters.

        Valid on the constraint manifold: the dependent velocities qdot^alpha stand for
        their values phi^alpha (``System.phi``) there; substitute them
        (``expr.xreplace(system.phi)``) to write an acceleration in the independent
        velocities alone.  Linear solves only (no simplify), structured so that the only
        denominators are det(df/dqdot^alpha) and the reduced mass matrix.

        Returns
        -------
        jetnh.mechanics.accelerations.Accelerations
            a read-only dict, Symbol (``x_tt``, ``lambda_x_t``, ...) -> sympy
            expression, whose repr keeps to the text budget.
        """
        return accelerations.Accelerations(self._accelerations)

    @cached_property
    def _accelerations(self):
        return self._solver()

    def __iter__(self):
        return iter(self.expressions)

    def __len__(self):
        return len(self.expressions)

    def __repr__(self):
        paper = f" {self.paper}" if self.paper else ""
        return f"<Equations {self.principle} ({self.form}, {self.convention} convention){paper}>"

    def shared_form(self):
        """The expressions in shared form (``jetnh.algebra.shared``): named intermediate
        quantities, linear in the shared size, never flattened."""
        from ..algebra.shared import shared_form

        return shared_form([(None, e) for e in self.expressions])

    def __str__(self):
        from ..display import TEXT_BUDGET

        head = f"{self.principle} equations, {self.form} form {self.paper}".rstrip()
        return head + "\n" + self.shared_form().text(
            TEXT_BUDGET, more=" (eom.shared_form().text() shows them all)")

    def latex(self) -> str:
        """Every expression, in shared form (``aligned``; no size budget)."""
        return self.shared_form().latex(self.J)

    def _repr_latex_(self):
        from ..display import equations_latex

        return equations_latex(self)

    def _repr_html_(self):
        from ..display import equations_html

        return equations_html(self)


# ---------------------------------------------------------------------- derivation
def derive(system: System, principle: str | Principle, form: str | None = None,
           convention: str = "paper") -> Equations:
    """The equations of ``principle`` (a name, an alias or a ``Principle``) in ``form``
    (see the module docstring); the expressions and the accelerations are derived when
    first asked for."""
    p = principles.get(principle)
    if convention not in CONVENTIONS:
        raise PrincipleError(f"unknown convention {convention!r}; choose one of {CONVENTIONS}")
    f = p.form(form)
    if system.k == 0:
        return _unconstrained(system, p)
    if not p.has_multipliers:
        return _chetaev(system, p, f, convention)
    if p.restricts(convention):
        return _restricted(system, p, f, convention)
    return _composite(system, p, f, convention)



def _unconstrained(system, p):
    return Equations(system, p.name, "euler-lagrange", "paper",
                     lambda: tuple(e + Q for e, Q in zip(system.J.euler(system.L), system.Q)),
                     paper="",
                     solver=lambda: accelerations.solve(system))


def _explicit(system: System) -> System:
    """The same system with the constraints in explicit form qdot^alpha - phi^alpha."""
    if system.constraints == system.explicit_constraints:
        return system
    with warnings.catch_warnings():     # the user's system has warned already
        warnings.simplefilter("ignore", JetnhWarning)
        return system.replace(constraints=system.explicit_constraints, branch=None)


def _variation(system, kind, explicit, lams=()):
    """The base system (explicit constraints or as given) and its variation of ``kind``."""
    base = _explicit(system) if explicit else system
    return base, make(base, kind, extra_fields=[m.name for m in lams])


def _composite(system, p: Principle, f: EquationForm, convention):
    """Every eta independent: the coefficients of (13) for the composite action, then
    (projected, on L~) the reduced and embedded forms."""
    lams = p.multiplier_symbols(system)
    J = jet_space(system, lams)

    def expressions():
        base, var = _variation(system, p.variation, f.explicit, lams)
        E = stationarity(base, var, lams)
        if f.name in ("multiplier", "explicit"):
            return E
        return _reduced(base, E, J, lams, f.name, with_T=p.multipliers_act)

    rates = tuple(J.jet(m, 1) for m in lams)
    return Equations(system, p.name, f.name, convention, expressions, lams, J=J,
                     paper=f.label(system.is_affine), explicit=f.explicit,
                     solver=lambda: accelerations.solve(system, p.kappa, f.explicit,
                                                        lams, rates))


def _restricted(system, p: Principle, f: EquationForm, convention):
    """eta restricted to the Chetaev subspace first: one equation per independent
    coordinate.  Multipliers that act on the motion stay arbitrary (Hoelder imposed);
    the others drop out (Suslov imposed, (30b)); Chetaev's Maggi form has none."""
    lams = p.multiplier_symbols(system)
    arbitrary = lams if p.multipliers_act else ()
    return Equations(
        system, p.name, f.name, convention,
        lambda: stationarity(*_variation(system, p.variation, f.explicit, lams), lams,
                             restrict=True),
        arbitrary=arbitrary, J=jet_space(system, lams), paper=p.restricted_label,
        explicit=f.explicit,
        solver=lambda: accelerations.solve(system, p.kappa, f.explicit, arbitrary))


def _chetaev(system, p: Principle, f: EquationForm, convention):
    """The action of L alone, eta restricted (Maggi); or the same rows with the reactions
    nu_a df^a/dqdot^s (multiplier form), or on L~ (Voronets)."""
    if f.name == "maggi":
        return _restricted(system, p, f, convention)
    J = jet_space(system)
    solver = lambda: accelerations.solve(system, p.kappa)  # noqa: E731
    if f.name == "multiplier":
        nus = p.reaction_symbols(system)

        def expressions():
            A = system.jacobian
            return tuple(system.J.euler(system.L)[s] + system.Q[s]
                         + sp.Add(*[nus[a] * A[a, s] for a in range(system.k)])
                         for s in range(system.J.n))
        return Equations(system, p.name, f.name, convention, expressions, reactions=nus,
                         J=J, solver=solver)
    return Equations(system, p.name, f.name, convention,
                     lambda: _embedded(_explicit(system), J, system.p_dependent), J=J,
                     explicit=f.explicit, solver=solver)


def _reduced(base, E, J, lams, form, with_T=True):
    """(18)/(30): dependent rows as they are, independent rows projected by P^T;
    (20)/(31): the projected rows rewritten on L~ through identity (19), with the T
    term of acting multipliers (``with_T``; Suslov's cancels)."""
    dep_rows = [E[i] for i in base.dep_index]
    if form == "reduced":
        P = null_basis(base)
        proj = [sp.Add(*[P[s, m] * E[s] for s in range(J.n)]) for m in range(P.cols)]
        return tuple(dep_rows + proj)
    if not with_T:
        return tuple(dep_rows + list(_embedded(base, J)))
    coef = [p + lam for p, lam in zip(base.p_dependent, lams)]
    return tuple(dep_rows + list(_embedded(base, J, coef)))


def _embedded(ex: System, J, coefficients=None):
    """[L~]_mu + Phi^alpha_mu dL~/dq^alpha + c_alpha T^alpha_mu + Q~_mu, the projected rows
    rewritten through (19): c = p (Chetaev, Voronets form), c = p + lambda (vakonomic
    (20b)), no T term (Suslov (31b), whose p T cancels the one of (19)); Q~ is the
    projected force P^T Q on the constraints."""
    Lt = ex.L_tilde
    T = ex.T(on_constraints=False)
    eul = J.euler(Lt, wrt=ex.independent)
    Q = [ex.on_constraints(e) for e in ex.Q]
    out = []
    for m, i in enumerate(ex.ind_index):
        e = eul[m] + sp.Add(*[ex.Phi[a, m] * dag.diff(Lt, qa) for a, qa in enumerate(ex.dependent)])
        e += Q[i] + sp.Add(*[ex.Phi[a, m] * Q[j] for a, j in enumerate(ex.dep_index)])
        if coefficients is not None:
            e += sp.Add(*[coefficients[a] * T[a, m] for a in range(ex.k)])
        out.append(e)
    return tuple(out)
