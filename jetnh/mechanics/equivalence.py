"""When do two principles share solutions?  Zhao et al. (2008), (11), (32), (39).

- ``branch_32``: the multiplier values lambda_alpha = -p_alpha (32) on which the
  vakonomic (20) and Suslov (31) equations coincide.
- ``frobenius_T``: for affine constraints, T^alpha_mu = K^alpha_{rho mu} qdot^rho where
  K^alpha_{rho sigma} = X_rho B^alpha_sigma - X_sigma B^alpha_rho are the Frobenius
  obstructions of the distribution (X_rho = d_rho + B^beta_rho d_beta, qdot^0 = 1); so
  T vanishes for all velocities exactly when the constraints are integrable, which is
  the content of the affine condition (39).
- ``branch_rates``: d/dt(lambda_alpha + p_alpha) along the vakonomic flow; on the branch
  (32) it is dL~/dq^alpha (no forces), so the branch is invariant, and the agreement of
  the accelerations on it a common solution, only where that vanishes on the constraints
  (Chaplygin systems, the paper's Example 1); elsewhere the flow leaves the branch.
- ``compare``: decides for two principles whether their accelerations agree identically,
  on the branch (32) (and whether that branch is invariant), or at given states.  A
  principle whose multipliers are left free (Hoelder in the "imposed" convention:
  P^T([L] + lambda [f]) = 0 with no equation for lambda) has a family of motions, one
  for each function lambda(t); ``compare`` then says for which choice of lambda (zero,
  or the other principle's multiplier) the family's accelerations are the other's, so
  that the other's motions are members of the family (Chetaev's at lambda = 0, the
  vakonomic ones with lambda following the vakonomic equation), not conversely.

Agreement of expressions is decided by evaluation at random states on the constraint
manifold (with random multipliers and parameters), a Schwartz-Zippel style test: a
nonzero analytic difference vanishes at random points with probability zero.  The
expressions are evaluated on their shared graph (``dag.evaluate``), never flattened.
Verdicts hold off the singular sets of the two acceleration systems
(``Comparison.singular``), where a random point falls with probability zero too.
"""

from __future__ import annotations

from dataclasses import dataclass, field

import sympy as sp

from ..algebra import dag, linalg, singular, zero
from . import principles
from .system import System
from ..errors import ArgumentError, PrincipleError
from ..frozen import FrozenDict
from ..geometry.frobenius import bracket_components

_POINTS = 4


def branch_32(system: System, multipliers, explicit: bool = True) -> dict:
    """{lambda_alpha: -p_alpha} on the constraint manifold: the branch of (32), for the
    multipliers of the explicit constraints qdot^alpha - phi^alpha.  For those of the
    constraints as given (``explicit=False``; f = A_dep (qdot^alpha - phi^alpha) when
    affine) the same branch is lambda = -A_dep^-T p."""
    p = sp.Matrix([system.on_constraints(e) for e in system.p_dependent])
    if not explicit:
        p = linalg.solve(system.on_constraints(system.jacobian_dependent.T), p)
    return {lam: -e for lam, e in zip(multipliers, p)}


def branch_rates(system: System, eqs) -> list:
    """d/dt(g_alpha) along the solved equations ``eqs`` (with multipliers), where
    g = lambda + p for explicit constraints and g = A_dep^T lambda + p as given, so that
    g = 0 is the branch (32) (``branch_32``).  On the branch these rates are
    dL~/dq^alpha for the vakonomic equations (20a) without forces: the branch is
    invariant exactly where they vanish on the constraints."""
    lams = eqs.multipliers
    lam = sp.Matrix(lams)
    if not eqs.explicit:
        lam = system.jacobian_dependent.T * lam
    g = [lam[a] + system.p_dependent[a] for a in range(system.k)]
    acc = eqs.accelerations()
    rates = [system.J.D(e) + sp.Add(*[sp.diff(e, m) * eqs.J.jet(m, 1) for m in lams])
             for e in g]
    return dag.xreplace(rates, dict(acc))


def obstructions(system: System) -> dict:
    """K^alpha_{rho sigma} = X_rho B^alpha_sigma - X_sigma B^alpha_rho, keyed
    (x_rho, x_sigma, q_alpha) with rho < sigma over (t, q^mu); zeros included."""
    return bracket_components(system.J, system.B, system.dependent, system.independent)


def frobenius_T(system: System) -> sp.Matrix:
    """T^alpha_mu rebuilt from the Frobenius obstructions: sum_rho K^alpha_{rho mu} qdot^rho."""
    J = system.J
    K = obstructions(system)
    coords = (J.t,) + system.independent
    vel = (sp.S.One,) + system.independent_velocities

    def k(qa, r, s):
        if r == s:
            return sp.S.Zero
        return K[(coords[r], coords[s], qa)] if r < s else -K[(coords[s], coords[r], qa)]
    return sp.Matrix(system.k, len(system.independent),
                     lambda a, m: sp.Add(*[k(system.dependent[a], r, m + 1) * vel[r]
                                           for r in range(len(coords))]))


_SHOWN = 4               # singular factors a verdict's text shows
_SHOWN_NODES = 60        # tree nodes up to which a shown factor is printed in full


@dataclass(frozen=True)
class Comparison:
    """The verdict of ``compare``: which coordinates' accelerations agree, and where.

    ``singular``: expressions (on the constraints; multipliers may occur) where one of
    the two acceleration systems is singular or undefined (``singular_set``);
    ``identical`` and ``on_branch_32`` hold off the set where one of them vanishes.
    ``on_branch_32``: the accelerations agree at every state on the branch
    lambda_alpha = -p_alpha (32) (an instantaneous statement); ``branch_invariant``
    (when that is True): whether the multiplier principle's flow keeps the branch
    (``branch_rates`` vanish on it), so that its motions started there are motions of the
    other principle.  When it is False, the motions share the instant, not the solution.
    ``free``: the multipliers one principle (``family``) leaves free, with no equation
    (Hoelder, "imposed"): its motions are a family with free functions lambda(t), and
    ``identical`` is False whenever they enter its accelerations.  ``choice``: the values
    of them ({} when ``free`` is empty; None when no tried choice works) at which the
    family's accelerations are the other principle's at every state (0 for Chetaev's,
    the other's multiplier, which then follows the other's equation, for vakonomic's): the
    other principle's motions are the family's motions for that choice.
    """

    principles: tuple
    identical: bool
    on_branch_32: bool | None
    defects: dict = field(default_factory=dict)   # q'' difference (symbolic, unsimplified)
    singular: list = field(default_factory=list)
    branch_invariant: bool | None = None
    free: tuple = ()
    family: str | None = None
    choice: dict | None = field(default_factory=dict)

    def __post_init__(self):
        """Its mappings read-only (``FrozenDict``), as every result's."""
        for name in ("defects", "choice"):
            value = getattr(self, name)
            if isinstance(value, dict) and not isinstance(value, FrozenDict):
                object.__setattr__(self, name, FrozenDict(value))

    def where(self) -> str:
        """The singular set as text, within budget ("" when empty)."""
        shown = [singular.label(e, _SHOWN_NODES) + " = 0" for e in self.singular[:_SHOWN]]
        more = len(self.singular) - len(shown)
        return " or ".join(shown + ([f"{more} more"] if more else []))

    def __str__(self):
        a, b = self.principles
        off = (f" off the singular set {self.where()} (there an acceleration system is "
               "singular or undefined)") if self.singular else ""
        if self.free:
            return self._family_text(a if self.family == b else b, off)
        if self.identical:
            return f"{a} and {b} have the same accelerations at every state{off}"
        if self.on_branch_32 and self.branch_invariant:
            return (f"{a} and {b} agree on the branch lambda_alpha = -p_alpha (32), which the "
                    f"motion keeps (common solutions from it), not in general"
                    f"{',' if off else ''}{off}")
        if self.on_branch_32:
            return (f"{a} and {b} have the same accelerations at states on the branch "
                    f"lambda_alpha = -p_alpha (32), but the motion leaves the branch "
                    f"(d/dt(lambda_alpha + p_alpha) != 0 on it), so they share no solutions "
                    f"in general{',' if off else ''}{off}")
        return f"{a} and {b} do not share solutions in general{off}"

    def _family_text(self, other, off):
        fam, names = self.family, ", ".join(map(str, self.free))
        head = (f"{fam} leaves {names} free (no equation for {'them' if len(self.free) > 1 else 'it'}),"
                f" so its motions are a family, one for each {names}(t);")
        if self.choice is None:
            return (f"{head} no choice tried ({names} = 0, or {other}'s multipliers) gives "
                    f"{other}'s accelerations at every state, so they share solutions only "
                    f"where some {names}(t) is chosen along them{',' if off else ''}{off}")
        at = ", ".join(f"{k} = 0" if v == 0 else f"{k} = {other}'s multiplier {v}"
                       for k, v in self.choice.items())
        follow = "" if all(v == 0 for v in self.choice.values()) else \
            f" (which then follows {other}'s equation)"
        return (f"{head} at {at}{follow} its accelerations are {other}'s at every state, so "
                f"every {other} motion is a {fam} motion (that choice), not conversely"
                f"{',' if off else ''}{off}")

    def __repr__(self):
        fam = (f"free={self.free!r}, family={self.family!r}, choice={self.choice!r}, "
               if self.free else "")
        return (f"Comparison({self.principles!r}, identical={self.identical}, "
                f"on_branch_32={self.on_branch_32}, branch_invariant={self.branch_invariant}, "
                f"{fam}"
                f"defects=<{len(self.defects)} expressions>, "
                f"singular=<{len(self.singular)}{': ' + self.where() if self.singular else ''}>)")

    def _repr_html_(self):
        from ..display import comparison_html

        return comparison_html(self)

    def _repr_latex_(self):
        from ..display import comparison_latex

        return comparison_latex(self)


def singular_set(system: System, principle: str, convention: str = "paper") -> list:
    """Where ``principle``'s acceleration system (the linear system in q'' and the
    multiplier rates) is singular or undefined, on the constraints: the factors
    (``jetnh.algebra.singular``) of what its block solve divides by (``linalg.divisors``: the
    determinants of the split and of the reduced mass matrix for blocks up to 6, the LU
    pivots, whose product is the determinant, for larger ones), of det(df/dqdot^alpha)
    (k <= 3), and of the denominators and root, log, ... arguments of the solved
    accelerations, rates and phi.  So the set contains every singular state (for blocks
    larger than 6, possibly more: a pivot may vanish where the block is regular)."""
    return _singular(system, *_solved(system.equations(principle, convention=convention)))


def _solved(eqs) -> tuple:
    """The accelerations of ``eqs`` and what their solve divided by (``linalg.divisors``)."""
    with linalg.divisors() as divs:
        acc = eqs.accelerations()
    return acc, divs


def _singular(system: System, acc: dict, divs=()) -> list:
    exprs = (list(acc.values()) + [system.phi[v] for v in system.dependent_velocities]
             + [1 / d for d in divs])
    k = system.k
    A = system.jacobian_dependent
    if 0 < k <= 3 and any(not e.is_number for e in A):
        exprs.append(1 / (A[0, 0] if k == 1 else A.det(method="berkowitz")))
    return singular.singular_set(exprs, on=system.phi)


def agrees(system: System, expr, derived=None, points: int = _POINTS, seed: int = 0) -> bool:
    """Whether ``expr`` (an expression, or a list: every one of them) vanishes on the
    constraint manifold: ``zero.vanishes`` at random points (random multipliers and
    parameters, the dependent velocities on the constraints, the ``derived`` symbols set
    from the others)."""
    return zero.vanishes(expr, system, points, seed, derived=derived)


def compare(system: System, first: str, second: str, convention: str = "paper") -> Comparison:
    """Do ``first`` and ``second`` give the same coordinate accelerations?

    The verdict holds off ``Comparison.singular`` (see ``singular_set``).

    Parameters
    ----------
    system : System
        The constrained system.
    first, second : str
        Two different principles by name or alias (``jetnh.mechanics.principles``),
        reported by their canonical names.
    convention : {"paper", "imposed"}, default "paper"
        As in ``System.equations``.

    Returns
    -------
    jetnh.mechanics.equivalence.Comparison
        ``.identical``, the branch on which they agree, the differences of the
        accelerations and the singular set, printed in one shared form; for a principle
        with free multipliers (Hoelder, "imposed") the choice of them at which its
        accelerations are the other's (``free``, ``family``, ``choice``).
    """
    if not isinstance(system, System):
        raise ArgumentError(f"compare needs a jetnh System, not {type(system).__name__}")
    for p in (first, second):
        if not isinstance(p, str):
            raise ArgumentError(f"compare needs principles by name (e.g. 'chetaev'), not "
                                f"{type(p).__name__}")
    names = [principles.canonical(p) for p in (first, second)]
    if names[0] == names[1]:
        raise PrincipleError(f"compare needs two different principles; {first!r} and "
                             f"{second!r} are both {names[0]}")
    return comparisons(system, {p: system.equations(p, convention=convention)
                                for p in names})[0]


def comparisons(system: System, equations: dict) -> list:
    """``compare`` for every pair of ``equations`` (principle -> Equations, in order),
    each principle solved once."""
    solved = {p: _solved(e) for p, e in equations.items()}
    sing = {p: _singular(system, *s) for p, s in solved.items()}
    canon: dict = {}        # equal subexpressions of all principles made one object, so
    accs = {}               # that their differences never compare trees (dag.xreplace)
    for p, (acc, _) in solved.items():
        accs[p] = dict(zip(acc, dag.xreplace(list(acc.values()), {}, canon)))
    names = list(equations)
    return [_compare(system, (a, b), (equations[a], equations[b]),
                     (accs[a], accs[b]), sing[a] + sing[b])
            for i, a in enumerate(names) for b in names[i + 1:]]


def _compare(system, principles, eqs, accs, factors) -> Comparison:
    (e1, e2), (a1, a2) = eqs, accs
    qdd = system.J.qdd
    defects = {q: a1[q] - a2[q] for q in qdd}
    fam = 0 if e1.arbitrary else 1 if e2.arbitrary else None
    free = eqs[fam].arbitrary if fam is not None else ()
    if free and not set(free) & dag.free_symbols(list(accs[fam].values())):
        free = ()                                 # they do not enter the motion
    if free:
        choice = _free_choice(system, eqs[fam], eqs[1 - fam], defects)
        sing = list(dict.fromkeys(factors))
        return Comparison(principles, False, None, defects, sing, None, tuple(free),
                          principles[fam], choice)
    same = agrees(system, list(defects.values()))
    on_branch = invariant = None
    owner = e1 if e1.multipliers else e2
    if not same and owner.multipliers:
        sub = branch_32(system, owner.multipliers, owner.explicit)
        on_branch = agrees(system, list(defects.values()), derived=sub)
        if on_branch:
            invariant = agrees(system, branch_rates(system, owner), derived=sub)
    sing = list(dict.fromkeys(factors))
    # the branches in the multipliers first, then those in the state, then parameters
    lams, jet = set(e1.multipliers + e2.multipliers), set(system.J.q + system.J.qd)
    jet.add(system.J.t)

    def rank(f):
        syms = dag.free_symbols(f)
        return 0 if syms & lams else 1 if syms & jet else 2
    sing.sort(key=rank)
    return Comparison(principles, same, on_branch, defects, sing, invariant)


def _free_choice(system, fam, other, defects):
    """The values of ``fam``'s free multipliers at which ``defects`` vanish at every
    state: the other principle's multipliers (same form of the constraints), else zero;
    None if neither."""
    free = fam.arbitrary
    tries = []
    if len(other.multipliers) == len(free) and other.explicit == fam.explicit:
        tries.append(dict(zip(free, other.multipliers)))
    tries.append({m: sp.S.Zero for m in free})
    for sub in tries:
        if agrees(system, dag.xreplace(list(defects.values()), sub)):
            return sub
    return None


def defect_along(system: System, first: str, second: str, samples, convention: str = "paper"):
    """Largest |q''_first - q''_second| over given states: do the principles agree along a
    trajectory?  Evaluated on the shared graph, all the states at once
    (``dag.evaluate_numpy``).  ``samples`` maps names (or Symbols) to arrays of equal length, e.g.
    ``traj.as_dict()`` of a jetnh Trajectory; multipliers missing from it count as zero."""
    import numpy as np

    e1 = system.equations(first, convention=convention)
    e2 = system.equations(second, convention=convention)
    a1, a2 = e1.accelerations(), e2.accelerations()
    data = {(k.name if isinstance(k, sp.Symbol) else str(k)): np.asarray(v, dtype=float)
            for k, v in dict(samples).items()}
    defects = dag.xreplace([a1[q] - a2[q] for q in system.J.qdd], system.phi)
    syms = sorted(dag.free_symbols(defects), key=lambda s: s.name)
    missing = [s.name for s in syms if s.name not in data
               and s not in (e1.multipliers + e2.multipliers)]
    if missing:
        from ..errors import JetnhError
        raise JetnhError(f"the samples lack values for {missing}; pass every coordinate, "
                         "velocity and parameter (e.g. traj.as_dict() plus parameters)")
    n = len(next(iter(data.values())))
    point = {s: data.get(s.name, np.zeros(n)) for s in syms}
    vals = dag.evaluate_numpy(defects, point)
    return max((float(np.max(np.abs(np.broadcast_to(v, (n,))))) for v in vals), default=0.0)
