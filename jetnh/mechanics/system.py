"""A constrained system: a Lagrangian L(t, q, qdot) and constraints f^a(t, q, qdot) = 0,
with optional non-potential generalized forces Q_s(t, q, qdot).

Implements the objects of Zhao et al. (2008), sections 2-4: the split into independent
coordinates q^mu and dependent q^alpha, the explicit form qdot^alpha = phi^alpha(t, q, qdot^mu)
(text above (16)), the affine form B^alpha_rho (33)-(34), the embedded Lagrangian L~,
the momenta p_alpha, and T^alpha_mu (defined under (18)).  The Frobenius test decides
integrability; the Chaplygin and regularity tests classify the system.

Derived objects are computed on first access and cached; a System is an immutable value.
"""

from __future__ import annotations

import re
import warnings
from collections.abc import Mapping, Set
from dataclasses import dataclass
from functools import cached_property

import sympy as sp
from sympy.core.function import AppliedUndef

from ..algebra import dag, linalg
from ..frozen import Frozen, FrozenDict
from . import inputs, principles
from ..errors import ConstraintError, JetnhWarning, JetSpaceError, LagrangianError
from ..geometry.jet import JetSpace, key_name, sympy_object
from .principles import NAMED, PRINCIPLES  # noqa: F401 -- PRINCIPLES kept importable here

@dataclass(frozen=True)
class Classification:
    """What kind of constrained system this is."""

    affine: bool
    integrable: bool
    chaplygin: bool
    regular: bool
    rheonomic: bool

    def __str__(self):
        flags = [("affine" if self.affine else "nonlinear"),
                 ("integrable" if self.integrable else "nonholonomic"),
                 ("Chaplygin" if self.chaplygin else "not Chaplygin"),
                 ("regular L" if self.regular else "singular L"),
                 ("rheonomic" if self.rheonomic else "scleronomic")]
        return ", ".join(flags)


class ExplicitForm(FrozenDict):
    """``System.phi``: a read-only dict, dependent velocity -> phi^alpha, whose repr keeps
    to the text budget (a large expression shows as its size and symbols)."""

    __slots__ = ()

    def __repr__(self):
        from ..display import text, text_items

        return "{" + text_items(f"{v}: {text(e)}" for v, e in self.items()) + "}"

    __str__ = __repr__

    def __reduce__(self):
        return ExplicitForm, (dict(self),)


def paired_columns(jacobian, cols) -> list[int]:
    """The columns ``cols`` of df/dqdot (k x n) reordered so that the a-th constraint
    contains the a-th column's velocity (a matching on the nonzero entries, the given
    order kept where it pairs so); as given when no such order exists (then the block
    is singular).  ``System.dependent`` is in this order."""
    k = len(cols)
    if k < 2:
        return list(cols)
    nonzero = [[jacobian[i, c] != 0 for c in cols] for i in range(k)]
    row_of = [j if nonzero[j][j] else None for j in range(k)]      # column -> its row

    def augment(i, seen):
        for j in range(k):
            if nonzero[i][j] and j not in seen:
                seen.add(j)
                if row_of[j] is None or augment(row_of[j], seen):
                    row_of[j] = i
                    return True
        return False

    for i in range(k):
        if i not in row_of and not augment(i, set()):
            return list(cols)
    col_of = {i: j for j, i in enumerate(row_of)}
    return [cols[col_of[i]] for i in range(k)]


#: the most solutions (Bezout's bound) of nonlinear constraints solved in closed form
MAX_ROOTS = 2


class System(Frozen):
    """``System(J, L, constraints, dependent)``: a Lagrangian with constraints f^a = 0.

    Parameters
    ----------
    J : JetSpace
        The coordinates and their velocities.
    L : sympy expression
        The Lagrangian L(t, q, qdot) in ``J``'s symbols and parameters.
    constraints : expression or list of expressions, optional
        The f^a(t, q, qdot), meaning f^a = 0, of any nonlinearity: a list (or a column
        Matrix, read as its entries, or one expression alone); an entry ``Eq(lhs, rhs)``
        is lhs - rhs.  A constraint without velocities, g(t, q) = 0, is *holonomic*:
        it is kept as such in ``holonomic`` (in the order given) and enters
        ``constraints`` as its time derivative D g = dg/dt + dg/dq^s qdot^s (at its place
        in the list), so that every principle's derivation, the split and the
        accelerations treat it as a velocity constraint whose velocity Jacobian dg/dq^s
        is the configuration Jacobian; the split's dependent velocities make that block
        regular.  A ``Scene`` checks (or completes) the initial configuration against
        g = 0 and keeps its runs on it.
    dependent : Symbol, str or list, optional
        The split: the coordinates whose velocities the constraints determine (one per
        constraint; Symbols or names, in a list or one alone, or names in one string
        ``"x y"``); chosen automatically when omitted.  ``dependent[a]`` is the
        coordinate the a-th constraint is solved for, whose velocity it contains: the
        given order is kept where it pairs so, otherwise the coordinates are reordered
        to pair (``System.dependent`` is in the order of ``constraints``).  The
        multiplier lambda_<dependent[a]> of every principle belongs to that pair: it
        multiplies the a-th constraint, and qdot^a - phi^a in the explicit forms (the
        same multiplier where df^a/dqdot^alpha is the identity, constraints solved for
        their coordinates; otherwise the explicit forms' multipliers are
        (df/dqdot^alpha)^T lambda on the constraints).
    branch : int, optional
        Selects a root (from 0) when the constraints are nonlinear in the dependent
        velocities and have several solutions for them; checked at construction.
    defaults : dict, optional
        Parameters (Symbols or names) -> default real numbers, used by ``Scene``.
    name : str, optional
        A label; neither it nor ``defaults`` changes the symbolic results.
    forces : dict, optional
        Coordinates (Symbols or names) -> non-potential generalized forces
        Q_s(t, q, qdot) (the others are 0).
    dissipation : sympy expression, optional
        A Rayleigh function D(t, q, qdot) adding Q_s = -dD/dqdot^s.  Every principle's
        equations carry Q_s beside [L]_s.
    check_branch : bool, default True
        False defers the check of ``branch`` to the first use of ``phi`` (a model file
        is read without solving its constraints).
    speeds : jetnh.mechanics.kane_bridge.Speeds, optional
        The map between a Kane model's generalized speeds and the velocities
        (``from_mechanics`` sets it; ``System.speeds``).

    Notes
    -----
    Coordinates may be written as sympy.physics.mechanics dynamicsymbols x(t),
    x(t).diff(t) (converted to x, x_t).  Abs(u) and sign(u) of t, q, qdot are kept as
    sqrt(u**2) and u/sqrt(u**2): the same functions, differentiable away from u = 0, where
    the compiled integrators stop (a singularity indicator); other non-smooth functions
    (Piecewise, Heaviside, Max, floor, re, ...) of t, q, qdot are refused.  A parameter
    named like a velocity (xdot, x_dot, dx, ...) is a constant, with a JetnhWarning;
    coordinates and parameters named like jetnh's multipliers (lambda_x, nu_x, eta_x) are
    refused.
    Strings are never parsed.  Every refusal is a JetnhError saying what to write instead.

    A System is a value: immutable (``FrozenError`` on assignment; ``forces`` and
    ``defaults`` are read-only mappings), equal to and hashed as any System built from the
    same inputs.

    Examples
    --------
    A knife edge: it moves only along its heading theta.

    >>> import sympy as sp
    >>> import jetnh as jn
    >>> J = jn.JetSpace("x y theta")
    >>> x, y, th = J.q
    >>> xd, yd, thd = J.qd
    >>> knife = jn.System(J, (xd**2 + yd**2 + thd**2) / 2,
    ...                   constraints=[sp.sin(th) * xd - sp.cos(th) * yd], dependent=[y])
    >>> knife.is_integrable()
    False
    """

    @dag.collector_paused()
    def __init__(self, J: JetSpace, L, constraints=(), dependent=None, branch: int | None = None,
                 defaults=None, name: str = "", forces=None, dissipation=None, *,
                 check_branch: bool = True, speeds=None):
        if not isinstance(J, JetSpace):
            raise JetSpaceError(f"the first argument must be a JetSpace, got {type(J).__name__}")
        self.J = J
        self.L = self._first_order(L, "the Lagrangian")
        given = tuple(self._first_order(f, f"constraint {i + 1}")
                      for i, f in enumerate(inputs.constraint_list(constraints)))
        self._check_constraints(given)
        #: the position-level constraints g(t, q) = 0 (the given ones without velocities)
        self.holonomic = tuple(f for f in given if not self._has_velocity(f))
        #: their places in ``constraints`` (where D g stands)
        self.holonomic_rows = tuple(i for i, f in enumerate(given)
                                    if not self._has_velocity(f))
        self.constraints = tuple(f if self._has_velocity(f) else J.D(f) for f in given)
        checked = ((q, self._first_order(e, f"the force on {q.name}"))
                   for q, e in inputs.force_items(forces, J))
        self.forces = FrozenDict({q: e for q, e in checked if e != 0})
        self.dissipation = (sp.S.Zero if dissipation is None
                            else self._first_order(dissipation, "the dissipation function"))
        self._check_dissipation()
        self._check_names()
        self._branch = inputs.branch_arg(branch)
        self._check_velocities()
        self.dependent = self._paired(self._choose_split(dependent))
        dep = set(self.dependent)
        self.independent = tuple(s for s in J.q if s not in dep)
        self._check_solvable()
        if not isinstance(name, (str, type(None))):
            raise ConstraintError(f"name must be a str, got {type(name).__name__}")
        self.name = name or ""
        self.defaults = FrozenDict(self._defaults({} if defaults is None else defaults))
        #: for a System read from a Kane model (``from_mechanics``): the map between its
        #: generalized speeds and the velocities (``jetnh.mechanics.kane_bridge.Speeds``)
        self.speeds = speeds
        if self._branch is not None and check_branch:
            self.phi                                    # noqa: B018 -- check the branch now

    # ------------------------------------------------------------------ value semantics
    def _identity(self) -> tuple:
        """The inputs that define the system (two systems with equal ones are equal)."""
        return (self.J, self.L, self.given_constraints, frozenset(self.forces.items()),
                self.dissipation, self.dependent, self._branch,
                frozenset(self.defaults.items()), self.name)

    def __eq__(self, other):
        return self is other or (type(other) is type(self)
                                 and self._identity() == other._identity())

    def __hash__(self):
        return hash(self._identity())

    @property
    def branch(self) -> int | None:
        """The root of nonlinear constraints selected at construction (None: the only one)."""
        return self._branch

    def _defaults(self, given) -> dict:
        if not isinstance(given, Mapping):
            raise ConstraintError(
                f"defaults must be a mapping {{parameter: number}}, got {type(given).__name__}")
        by_name = {p.name: p for p in self.parameters}
        out = {}
        for key, val in given.items():
            name = key_name(key)
            if name is None:
                raise ConstraintError(
                    f"defaults key {key!r} is a {type(key).__name__}; use the parameter's "
                    "Symbol or its name")
            if name not in by_name:
                raise ConstraintError(
                    f"default given for {name!r}, which is not a parameter of the system "
                    f"(parameters: {sorted(by_name)})")
            if by_name[name] in out:
                raise ConstraintError(f"two defaults given for the parameter {name!r}")
            out[by_name[name]] = inputs.real_number(val, f"the default of {name!r}")
        return out

    # ------------------------------------------------------------------ validation
    def _first_order(self, expr, what):
        J = self.J
        err = LagrangianError if what == "the Lagrangian" else ConstraintError
        expr = inputs.scalar(expr, what, err)
        if dag.has(expr, AppliedUndef):         # dynamicsymbols x(t), x(t).diff(t): convert
            expr = inputs.convert_dynamic(expr, J)
        expr = J.check(expr)
        inputs.refuse_specials(expr, J, what, err)
        expr = inputs.smooth_kinks(expr, J, what, err)
        if J.order(expr) > 1:
            raise err(
                f"{what} contains accelerations or higher jets ({expr}); jetnh treats "
                "first-order Lagrangians, constraints and forces, functions of (t, q, qdot) "
                "only")
        if any(J.split(s) and J.split(s)[0] in J.fields
               for s in dag.free_symbols(expr)):
            raise err(f"{what} contains a field of the jet space; use coordinates only")
        return expr

    def _check_dissipation(self):
        if self.dissipation != 0 and not (self.dissipation.free_symbols & set(self.J.qd)):
            raise ConstraintError(
                f"the dissipation function {self.dissipation} contains no velocity, so it "
                "gives no force (Q_s = -dD/dqdot^s); write D(t, q, qdot), e.g. "
                "c*J.qd[0]**2/2, or put a potential into the Lagrangian")

    def _check_names(self):
        """Refuse coordinates and parameters named like jetnh's own symbols; warn about
        parameters named like velocities (they are constants, not the velocity)."""
        J = self.J
        reserved = {}
        for q in J.q:
            for prefix, what in NAMED.items():
                reserved[f"{prefix}_{q.name}"] = f"{what} of {q.name}"
        for q in J.q:
            if q.name in reserved:
                raise JetSpaceError(
                    f"the coordinate {q.name!r} has the name jetnh gives to "
                    f"{reserved[q.name]}; rename the coordinate")
        lookalike = inputs.velocity_lookalikes(J)
        for p in self.parameters:
            m = inputs.JET_TAIL.match(p.name)
            base = m.group(1) if m else p.name
            if base in reserved:
                raise JetSpaceError(
                    f"the parameter {p.name!r} has the name jetnh gives to {reserved[base]} "
                    f"(or its jets); rename the parameter")
            if m and m.group(2) and p.name not in lookalike:
                warnings.warn(
                    f"the symbol {p.name!r} is named like a jet of {base!r}, which is not a "
                    f"coordinate of {J!r}: jetnh treats it as a constant parameter. Add "
                    f"{base!r} to the jet space, or rename the parameter",
                    JetnhWarning, stacklevel=3)
            if p.name in lookalike:
                q = lookalike[p.name]
                warnings.warn(
                    f"the symbol {p.name!r} is not a jet coordinate of {J!r}: jetnh treats it "
                    f"as a constant parameter. If it means the velocity of {q.name}, write "
                    f"J.qd[{J.q.index(q)}] (the Symbol {J.jet(q, 1).name!r}) instead",
                    JetnhWarning, stacklevel=3)
        for f in set().union(*(dag.atoms(e, AppliedUndef) for e in self._inputs)):
            if f.func.__name__ in lookalike:
                q = lookalike[f.func.__name__]
                warnings.warn(
                    f"{f} is an explicit function, not the velocity of {q.name}; write "
                    f"J.qd[{J.q.index(q)}] (the Symbol {J.jet(q, 1).name!r}) for the velocity",
                    JetnhWarning, stacklevel=3)

    def _has_velocity(self, f) -> bool:
        return bool(dag.free_symbols(f) & set(self.J.qd))

    def _check_constraints(self, given):
        J = self.J
        for i, f in enumerate(given):
            if f == 0:
                raise ConstraintError(
                    f"constraint {i + 1} is identically zero (0 = 0); remove it")
            if (not (dag.free_symbols(f) & (set(J.q) | set(J.qd) | {J.t}))
                    and not dag.has(f, AppliedUndef)):
                raise ConstraintError(
                    f"constraint {i + 1}, {f} = 0, involves neither time, coordinates nor "
                    "velocities: it is a condition on the parameters, not a constraint; "
                    "remove it")
            if not (dag.free_symbols(f) & (set(J.q) | set(J.qd))):
                raise ConstraintError(
                    f"constraint {i + 1}, {f} = 0, involves time only: it holds at isolated "
                    "instants, not along a motion; remove it (or add the coordinates it "
                    "relates)")

    def _check_velocities(self):
        if self.k and linalg.numeric_rank(self.jacobian) < self.k:
            raise ConstraintError(
                "the constraints are dependent: their velocity Jacobian df/dqdot has rank "
                f"< {self.k}; remove the redundant ones")
        if self.k >= self.J.n:
            raise ConstraintError(
                f"{self.k} constraints on {self.J.n} coordinates leave no freedom; need fewer "
                "constraints than coordinates")

    def _choose_split(self, dependent):
        J = self.J
        if dependent is None:
            return self._auto_split()
        if isinstance(dependent, str):
            items = [n for n in re.split(r"[\s,]+", dependent.strip()) if n]
        elif isinstance(dependent, (sp.Symbol, sp.Basic)) and not isinstance(
                dependent, (sp.MatrixBase, sp.Tuple)):
            items = [dependent]
        elif isinstance(dependent, (Set, Mapping)):
            raise ConstraintError(
                f"dependent must be ordered (a list or tuple): a {type(dependent).__name__} "
                "does not say which constraint solves for which coordinate")
        else:
            try:
                items = list(dependent)
            except TypeError:
                raise ConstraintError(
                    f"dependent must be coordinates (Symbols of J.q or their names), got "
                    f"{dependent!r}") from None
        by_name = {s.name: s for s in J.q}
        dep = []
        for d in items:
            name = key_name(d)
            if name is None:
                raise ConstraintError(
                    f"dependent coordinate {d!r} (of type {type(d).__name__}) is not a coordinate; "
                    f"give Symbols of J.q or their names ({', '.join(by_name)})")
            if name not in by_name:
                info = J.split(sp.Symbol(name))
                hint = (f" ({name} is a jet of {info[0].name}: give the coordinate itself)"
                        if info else "")
                raise ConstraintError(
                    f"dependent coordinate {name!r} is not a coordinate of {J!r}{hint}")
            dep.append(by_name[name])
        if len(set(dep)) != len(dep):
            raise ConstraintError(f"the dependent coordinates {dep} repeat a coordinate")
        if len(dep) != self.k:
            raise ConstraintError(
                f"{len(dep)} dependent coordinates given for {self.k} constraints; give one "
                "per constraint")
        return tuple(dep)

    def _paired(self, dependent) -> tuple[sp.Symbol, ...]:
        """``dependent`` reordered so that the a-th constraint contains the velocity of the
        a-th coordinate (``paired_columns``)."""
        cols = paired_columns(self.jacobian, [self.J.q.index(d) for d in dependent])
        return tuple(self.J.q[c] for c in cols)

    def _auto_split(self) -> tuple[sp.Symbol, ...]:
        """Prefer coordinates, last first (the paper's alpha = m+1..n), whose velocity enters
        some constraint linearly with a constant coefficient; keep the block invertible."""
        J, k = self.J, self.k
        if k == 0:
            return ()
        A = self.jacobian
        order = list(range(J.n - 1, -1, -1))

        def score(j):
            col = A[:, j]
            const = any(e != 0 and e.is_number for e in col)
            return (0 if const else 1, order.index(j))

        chosen: list[int] = []
        for j in sorted(range(J.n), key=score):
            trial = chosen + [j]
            if linalg.numeric_rank(A[:, trial]) == len(trial):
                chosen = trial
            if len(chosen) == k:
                break
        if len(chosen) < k:
            raise ConstraintError("no split makes the constraints solvable for dependent velocities")
        return tuple(J.q[j] for j in sorted(chosen))

    def _check_solvable(self):
        if self.k and linalg.numeric_rank(self.jacobian_dependent) < self.k:
            names = ", ".join(s.name for s in self.dependent)
            raise ConstraintError(
                f"the constraints cannot be solved for the velocities of {names}: "
                "df/dqdot^alpha is singular. Choose another split (dependent=...) or omit it")

    # ------------------------------------------------------------------ basic data
    @property
    def k(self) -> int:
        """The number of constraints."""
        return len(self.constraints)

    @cached_property
    def dep_index(self) -> tuple[int, ...]:
        return tuple(self.J.q.index(s) for s in self.dependent)

    @cached_property
    def ind_index(self) -> tuple[int, ...]:
        return tuple(self.J.q.index(s) for s in self.independent)

    @cached_property
    def dependent_velocities(self) -> tuple[sp.Symbol, ...]:
        return self.J.jets(1, self.dependent)

    @cached_property
    def independent_velocities(self) -> tuple[sp.Symbol, ...]:
        return self.J.jets(1, self.independent)

    @property
    def _inputs(self) -> tuple:
        """Every expression the user gave: L, the constraints (holonomic ones also as
        given), forces and dissipation."""
        return (self.L, *self.constraints, *self.holonomic, *self.forces.values(),
                self.dissipation)

    @cached_property
    def Q(self) -> tuple[sp.Expr, ...]:
        """The generalized forces Q_s (every coordinate): ``forces`` - dD/dqdot^s."""
        J = self.J
        return tuple(self.forces.get(q, sp.S.Zero) - sp.diff(self.dissipation, v)
                     for q, v in zip(J.q, J.qd))

    @property
    def forced(self) -> bool:
        """Whether any generalized force is nonzero."""
        return any(e != 0 for e in self.Q)

    @cached_property
    def parameters(self) -> tuple[sp.Symbol, ...]:
        """Symbols that are neither time nor jet coordinates, sorted by name."""
        syms = set().union(*(dag.free_symbols(e) for e in self._inputs))
        J = self.J
        return tuple(sorted((s for s in syms if s != J.t and not J.split(s)),
                            key=lambda s: s.name))

    @cached_property
    def jacobian(self) -> sp.Matrix:
        """df^a/dqdot^s (k x n)."""
        # one cache for every entry: the constraints of a chain share their parts, each
        # differentiated once by each velocity (a velocity a part lacks: zero, no walk)
        return dag.jacobian(self.constraints, self.J.qd) if self.k else sp.zeros(0, self.J.n)

    @cached_property
    def jacobian_dependent(self) -> sp.Matrix:
        return self.jacobian[:, list(self.dep_index)] if self.k else sp.zeros(0, 0)

    @cached_property
    def is_affine(self) -> bool:
        """Whether every constraint is affine in the velocities: df/dqdot free of them.
        A velocity under Abs or sign (kept as sqrt(u**2)) is only piecewise affine: not
        affine (its B would be undefined at u = 0 and differ on either side)."""
        qd = set(self.J.qd)

        def non_smooth(e):
            return any(isinstance(p, sp.Pow) and not p.exp.is_integer
                       and dag.free_symbols(p.base) & qd for p in dag.nodes(e))

        return all(not non_smooth(e) and all(sp.expand(sp.diff(e, v)) == 0 for v in vs)
                   for e in self.jacobian for vs in [dag.free_symbols(e) & qd] if vs)

    # ------------------------------------------------------------------ explicit form
    @cached_property
    @dag.collector_paused()
    def phi(self) -> dict[sp.Symbol, sp.Expr]:
        """The explicit form: dependent velocity qdot^alpha -> phi^alpha(t, q, qdot^mu).

        A read-only dict whose repr keeps to the text budget (``ExplicitForm``); the
        values are shared graphs (``jetnh.algebra.dag``): print a large one with
        ``jetnh.algebra.shared.shared_form([(None, e)]).text()``, not ``str``."""
        return ExplicitForm(self._explicit_solution())

    def _explicit_solution(self) -> dict:
        vel = self.dependent_velocities
        if not vel:
            if self._branch is not None:
                self._affine_branch()
            return {}
        fs = sp.Matrix(self.constraints)
        A = self.jacobian_dependent
        if all(sp.diff(e, v) == 0 for e in A                      # affine in qdot^alpha
               for v in set(vel) & dag.free_symbols(e)):
            if self._branch is not None:
                self._affine_branch()
            rest = fs.xreplace({v: 0 for v in vel})
            sol = linalg.solve(A, -rest)
            return {v: sol[i] for i, v in enumerate(vel)}
        return self._solve_nonlinear(vel)

    def _affine_branch(self):
        """A branch given for constraints with one solution (affine in the dependent
        velocities, or none): branch 0 is that solution (a warning), others an error."""
        if self._branch > 0:
            raise ConstraintError(
                f"branch={self._branch}, but the constraints have 1 solution for the dependent "
                "velocities (they are affine in them); branch applies only to constraints "
                "with several solutions: omit it")
        inputs.single_root_warning(self._branch)

    def _solve_nonlinear(self, vel):
        self._check_root_budget(vel)
        try:
            sols = sp.solve(list(self.constraints), list(vel), dict=True)
        except (NotImplementedError, ValueError) as exc:
            sols = []
            reason = f" ({exc})"
        else:
            reason = ""
        sols = [s for s in sols if all(v in s for v in vel)]
        special = {type(a).__name__ for s in sols for e in s.values()
                   for a in sp.preorder_traversal(e)
                   if isinstance(a, (sp.LambertW, sp.RootOf, sp.Piecewise))}
        if special:
            raise ConstraintError(
                "the dependent velocities solve the constraints only through "
                f"{', '.join(sorted(special))}, which jetnh does not compile; write the "
                "constraints in explicit form qdot^alpha - phi^alpha(t, q, qdot^mu), or choose "
                "another dependent coordinate")
        if not sols:
            raise ConstraintError(
                "the dependent velocities cannot be isolated from the constraints" + reason +
                "; write the constraints in explicit form qdot^alpha - phi^alpha(t, q, qdot^mu)")
        listing = "; ".join(f"[{i}] " + ", ".join(f"{v} = {s[v]}" for v in vel)
                            for i, s in enumerate(sols))
        if len(sols) > 1 and self._branch is None:
            raise ConstraintError(
                f"the constraints have {len(sols)} solutions for the dependent velocities: "
                f"{listing}. Choose one with System(..., branch=i)")
        if self._branch is not None and self._branch >= len(sols):
            raise ConstraintError(
                f"branch={self._branch}, but the constraints have {len(sols)} solution"
                f"{'s' if len(sols) > 1 else ''} for the dependent velocities ({listing}); "
                f"branch counts from 0 to {len(sols) - 1}")
        if self._branch is not None and len(sols) == 1:
            inputs.single_root_warning(self._branch)
        s = sols[self._branch or 0]
        return {v: s[v] for v in vel}

    def _check_root_budget(self, vel):
        """The budget of the nonlinear solve, checked before it starts: every constraint
        polynomial in the dependent velocities, of degree <= 2, and at most
        ``MAX_ROOTS`` solutions by Bezout's bound (one transcendental equation in one
        dependent velocity is solved and its solutions checked instead) (two coupled quadratics, or a quartic,
        have closed forms too large to generate code from, when sympy finds them)."""
        if len(vel) == 1 and not self.constraints[0].is_polynomial(*vel):
            return          # one equation in one unknown: sympy's solve, checked after
        degrees = []
        for i, f in enumerate(self.constraints):
            if not f.is_polynomial(*vel):
                raise ConstraintError(
                    f"constraint {i} is not polynomial in the dependent velocities "
                    f"{', '.join(map(str, vel))}; jetnh solves polynomial constraints of "
                    f"degree <= 2 only: write it in explicit form qdot^alpha - phi^alpha(t, "
                    "q, qdot^mu), or choose another dependent coordinate")
            degrees.append(sp.Poly(f, *vel).total_degree())
        roots = 1
        for d in degrees:
            roots *= max(d, 1)
        if max(degrees) > 2 or roots > MAX_ROOTS:
            raise ConstraintError(
                f"the constraints have degrees {degrees} in the dependent velocities: up to "
                f"{roots} solutions, beyond the budget of {MAX_ROOTS} (degree <= 2, one "
                "quadratic at most) for solving them in closed form; write them in explicit "
                "form qdot^alpha - phi^alpha(t, q, qdot^mu) for the branch you mean")

    @cached_property
    def explicit_constraints(self) -> tuple[sp.Expr, ...]:
        """f^alpha = qdot^alpha - phi^alpha, in the order of ``dependent``."""
        return tuple(v - self.phi[v] for v in self.dependent_velocities)

    def on_constraints(self, expr, prolonged: bool = False):
        """``expr`` restricted to the constraints: dependent velocities replaced by phi.

        With ``prolonged`` the dependent accelerations are replaced too, by
        D(phi^alpha) on the constraints (the first prolongation of the constraint set):
        identities such as (19) hold there, not on J^2 at large.
        """
        expr = sympy_object(expr)         # never a string (it would be executed)
        if not self.phi:
            return expr
        # derivatives of undefined functions by a velocity need subs (it builds Subs objects)
        replace = expr.subs if expr.has(sp.Derivative) else expr.xreplace
        if prolonged:
            expr = replace(self.dependent_accelerations)
            replace = expr.subs if expr.has(sp.Derivative) else expr.xreplace
        return replace(self.phi)

    @cached_property
    def dependent_accelerations(self) -> dict[sp.Symbol, sp.Expr]:
        """qddot^alpha -> D(phi^alpha) restricted to the constraints."""
        J = self.J
        return {J.jet(a, 2): J.D(self.phi[v]).xreplace(self.phi)
                for a, v in zip(self.dependent, self.dependent_velocities)}

    @cached_property
    def Phi(self) -> sp.Matrix:
        """d phi^alpha / d qdot^mu (rows: dependent, cols: independent)."""
        return sp.Matrix(self.k, len(self.independent),
                         lambda a, m: dag.diff(self.phi[self.dependent_velocities[a]],
                                              self.independent_velocities[m]))

    @cached_property
    def B(self) -> sp.Matrix:
        """The affine form (33)-(34): B^alpha_rho with rho = 0 (time) then the independent mu."""
        if not self.is_affine:
            raise ConstraintError(
                "the constraints are not affine in the velocities (a velocity under Abs or "
                "sign is only piecewise affine); B^alpha_rho exists only for affine "
                "constraints (use phi / Phi for the general explicit form)")
        vel = self.independent_velocities
        cols = []
        for v, phi in ((v, self.phi[v]) for v in self.dependent_velocities):
            b0 = dag.xreplace(phi, {u: sp.S.Zero for u in vel})
            cols.append([b0] + [dag.diff(phi, u) for u in vel])
        return sp.Matrix(cols)

    # ------------------------------------------------------------------ L~, p, T
    @cached_property
    def L_tilde(self) -> sp.Expr:
        """The embedded Lagrangian L~(t, q, qdot^mu) = L(t, q, qdot^mu, phi).

        A shared graph (``jetnh.algebra.dag``): for chains its printed tree is exponentially
        long; print it with ``jetnh.algebra.shared.shared_form([(None, L_tilde)]).text()``
        or ``jetnh.display.text`` (its size and symbols when large)."""
        return self.on_constraints(self.L)

    @cached_property
    def p_dependent(self) -> tuple[sp.Expr, ...]:
        """p_alpha = dL/dqdot^alpha (not restricted to the constraints)."""
        return tuple(dag.diff(self.L, v) for v in self.dependent_velocities)

    def T(self, on_constraints: bool = True) -> sp.Matrix:
        """T^alpha_mu = -[phi^alpha]_mu - dphi^alpha/dq^beta dphi^beta/dqdot^mu (text under (18)).

        Rows: dependent alpha; columns: independent mu.  With ``on_constraints`` the
        dependent velocities are replaced by phi.  The entries are shared graphs
        (``jetnh.algebra.dag``), built in time linear in the shared size; for chains their
        printed trees are exponentially long: print them with
        ``jetnh.algebra.shared.shared_form([(None, e) for e in T]).text()``.
        """
        J, Phi = self.J, self.Phi
        rows = []
        for a, va in enumerate(self.dependent_velocities):
            ph = self.phi[va]
            eul = J.euler(ph, wrt=self.independent)
            cache: dict = {}                # d phi^alpha / d q^beta once per row
            dq = [dag.diff(ph, qb, cache=cache) for qb in self.dependent]
            rows.append([-eul[m] - sp.Add(*[d * Phi[b, m] for b, d in enumerate(dq) if d != 0])
                         for m in range(len(self.independent))])
        T = sp.Matrix(rows) if rows else sp.zeros(0, len(self.independent))
        if not on_constraints or not self.phi:
            return T
        if any(dag.has(e, sp.Derivative) for e in T):
            return T.applyfunc(self.on_constraints)
        # every entry restricted in one walk of the shared graph (a tree walk is exponential)
        return sp.Matrix(T.rows, T.cols, dag.xreplace(list(T), self.phi))

    # ------------------------------------------------------------------ classification
    def frobenius(self):
        """The Frobenius test of the constraints (see ``jetnh.geometry.frobenius``)."""
        from ..geometry.frobenius import FrobeniusResult, frobenius_from_constraints

        if not self.k:                      # no constraints: trivially integrable
            return FrobeniusResult(True, {}, "brackets")
        return frobenius_from_constraints(self.J, self.constraints, self.dependent)

    def is_integrable(self) -> bool:
        """Whether the constraints are integrable (holonomic), by the Frobenius theorem.

        With a chosen ``branch`` (constraints with several solutions for the dependent
        velocities) the answer is for that branch, qdot^alpha = phi^alpha, the constraints
        this System integrates (ydot^2 = xdot^2, branch ydot = xdot: integrable);
        ``frobenius()`` keeps the answer for the union of the branches."""
        if self._branch is None or not self.k:
            return bool(self.frobenius().integrable)
        from ..geometry.frobenius import frobenius_from_constraints

        return bool(frobenius_from_constraints(self.J, self.explicit_constraints,
                                               self.dependent).integrable)

    @cached_property
    def mass_matrix(self) -> sp.Matrix:
        """d^2 L / dqdot^r dqdot^s."""
        qd = self.J.qd
        return sp.Matrix(self.J.n, self.J.n, lambda r, s: dag.diff(self.L, qd[r], qd[s]))

    def is_regular(self) -> bool:
        """Whether the Hessian of L in the velocities is generically invertible."""
        return linalg.numeric_rank(self.mass_matrix) == self.J.n

    def is_chaplygin(self) -> bool:
        """Chaplygin: affine, scleronomic, homogeneous constraints, and neither L nor the
        B^alpha_mu depend on the dependent coordinates q^alpha."""
        if not (self.k and self.is_affine):
            return False
        B = self.B
        syms = dag.free_symbols(list(B))
        if any(e != 0 for e in B[:, 0]) or self.J.t in syms:
            return False
        dep = set(self.dependent)
        return not (syms & dep) and not (dag.free_symbols(self.L) & dep)

    def classify(self) -> Classification:
        J = self.J
        rheo = J.t in set().union(*(f.free_symbols for f in self.constraints)) if self.k else False
        return Classification(affine=self.is_affine, integrable=self.is_integrable(),
                              chaplygin=self.is_chaplygin(), regular=self.is_regular(),
                              rheonomic=rheo)

    def replace(self, **changes) -> "System":
        """A new System from this one's inputs with ``changes`` (any of ``J``, ``L``,
        ``constraints``, ``dependent``, ``branch``, ``defaults``, ``name``, ``forces``,
        ``dissipation``, ``speeds``), checked as any new System."""
        inputs_ = dict(J=self.J, L=self.L, constraints=self.given_constraints,
                       dependent=self.dependent, branch=self._branch, defaults=self.defaults,
                       name=self.name, forces=self.forces,
                       dissipation=self.dissipation if self.dissipation != 0 else None,
                       speeds=self.speeds)
        unknown = sorted(set(changes) - set(inputs_))
        if unknown:
            raise ConstraintError(f"System.replace has no input {', '.join(unknown)}; the "
                                  f"inputs are {', '.join(inputs_)}")
        return System(**{**inputs_, **changes})

    def with_split(self, dependent) -> "System":
        """The same system with another split."""
        return self.replace(dependent=dependent)

    @property
    def given_constraints(self) -> tuple[sp.Expr, ...]:
        """The constraints as given: ``constraints`` with each holonomic g in place of
        its derivative D g."""
        hol = dict(zip(self.holonomic_rows, self.holonomic))
        return tuple(hol.get(i, f) for i, f in enumerate(self.constraints))

    # ------------------------------------------------------------------ equations
    def equations(self, principle: str, form: str | None = None, convention: str = "paper"):
        """The equations of motion under ``principle``, each expression meaning = 0.

        Parameters
        ----------
        principle : str or jetnh.mechanics.principles.Principle
            "chetaev", "vakonomic", "holder" or "suslov" (or an alias, or a
            ``jetnh.mechanics.principles.Principle``).
        form : str, optional
            One of the principle's forms (``jetnh.mechanics.equations``: "multiplier",
            "reduced", "embedded", ...); default its first.
        convention : {"paper", "imposed"}, default "paper"
            Whether every eta^s counts as independent after the commutator has been used
            (the paper's reading) or the Chetaev condition restricts eta first.

        Returns
        -------
        Equations
            ``.expressions``, ``.multipliers`` and ``.accelerations()``; derived once per
            principle, form and convention and kept.
        """
        from .equations import derive

        key = ("equations", principles.canonical(principle), form, convention)
        try:
            found = self._memo.get(key)
        except TypeError:           # an unhashable form or convention: derive names it
            return derive(self, principle, form=form, convention=convention)
        if found is None:
            found = self._memo[key] = derive(self, principle, form=form,
                                             convention=convention)
        return found

    def _repr_html_(self):
        from ..display import system_html

        return system_html(self)

    def _repr_latex_(self):
        from ..display import system_latex

        return system_latex(self)

    def __repr__(self):
        """Within the text budget: a large expression shows as its size and symbols, and
        list entries past the budget are counted."""
        from ..display import TEXT_BUDGET, text, text_items

        share = TEXT_BUDGET // 5            # L, constraints, forces, dissipation, holonomic
        extra = (f", forces={{{text_items((f'{q.name}: {text(e)}' for q, e in self.forces.items()), share)}}}"
                 if self.forces else "")
        extra += f", dissipation={text(self.dissipation)}" if self.dissipation != 0 else ""
        extra += (f", holonomic=[{text_items(map(text, self.holonomic), share)}]"
                  if self.holonomic else "")
        return (f"System(L={text(self.L)}, "
                f"constraints=[{text_items(map(text, self.constraints), share)}], "
                f"dependent=[{text_items((repr(s.name) for s in self.dependent), share)}]{extra})")
