"""Hypothesis strategies for property tests of constrained mechanics on jet spaces.

Every public name is a function returning a hypothesis strategy, so strategies compose
the way hypothesis' own do::

    from hypothesis import given, strategies as st
    import jetnh.strategies as jst

    @given(jst.jet_spaces(min_n=2).flatmap(lambda J: st.tuples(
        st.just(J), jst.lagrangians(J), jst.affine_constraints(J))))
    def test_something(case):
        J, L, (constraints, dependent) = case
        ...

    @given(jst.systems(affine=True))
    def test_something_else(system):          # a jetnh.System
        ...

The expressions are deliberately *small* (a few terms, shallow nesting) so that sympy
stays fast, and *everywhere defined on the reals*: there is no division except by
``1 + a**2``, square roots are taken only of ``1 + a**2`` or ``2 + sin(a)`` (strictly
positive), and ``exp`` only of bounded arguments (``sin``, ``cos`` or a small multiple
of a single variable).  Coefficients are small rationals, so results are exact.

Public names:

``jet_spaces(min_n=1, max_n=6)``
    JetSpace with coordinates q1..qn.
``jet_expressions(J, order=1, max_depth=3, with_time=True, of=None)``
    expressions in t and the jets of order <= ``order`` of the bases ``of``.
``polynomials(J, order=1, max_degree=2, max_terms=3, with_time=True, of=None)``
    polynomials in the same variables.
``lagrangians(J, with_time=True, gyroscopic=None, max_depth=2, mass="diagonal")``
    regular Lagrangians 1/2 qd^T M(q) qd (+ gyroscopic terms) - V(t, q); ``mass="full"``
    for non-diagonal configuration-dependent M.
``affine_constraints(J, m=None, dependent=None, implicit=False)``
    ``(constraints, dependent)`` with constraints qd^a - B^a_mu qd^mu - B^a_0, or with
    ``implicit`` A(q) qd + b(t, q).
``nonlinear_constraints(J, m=None, dependent=None, implicit=False)``
    ``(constraints, dependent)`` with constraints qd^a - phi^a(t, q, qd^mu), phi nonlinear,
    or with ``implicit`` nonlinear in the dependent velocities too.
``constrained_systems(min_n=2, max_n=4, affine=None, implicit=False, mass="diagonal")``
    ``(J, L, constraints, dependent)``.
``forces(J, max_depth=2)``
    generalized forces ``{coordinate: Q(t, q, qd)}`` on some of the coordinates.

Values, for tests that need a system, a principle or a scene rather than its parts::

    @given(jst.scenes(jst.systems(max_n=3, affine=True)))
    def test_a_scene(scene):
        ...

``systems(min_n=2, max_n=4, affine=None, implicit=False, mass="diagonal", forced=False)``
    ``System`` values from :func:`constrained_systems` (with :func:`forces` if ``forced``).
``principles()``
    the registered ``Principle`` values.
``scenes(of=None, under=None, t_end=1.0, max_value=1.0)``
    ``jetnh.Scene`` values: a system (of ``of``), a principle (of ``under``) and a state in
    [-max_value, max_value] (dependent velocities from the constraints).
"""

from __future__ import annotations

from functools import lru_cache
from typing import Iterable, Sequence

import sympy as sp
from hypothesis import strategies as st
from hypothesis.errors import InvalidArgument

from .geometry.jet import JetSpace

__all__ = [
    "jet_spaces",
    "jet_expressions",
    "polynomials",
    "lagrangians",
    "affine_constraints",
    "nonlinear_constraints",
    "constrained_systems",
    "forces",
    "systems",
    "principles",
    "scenes",
]


# ---------------------------------------------------------------------------- helpers
@lru_cache(maxsize=None)
def _rationals(max_num: int = 3, max_den: int = 3, nonzero: bool = False, positive: bool = False):
    """Small rationals p/q, |p| <= max_num, 1 <= q <= max_den (shrinks towards 0 or 1)."""
    if positive:
        nums = st.integers(1, max_num)
    elif nonzero:
        nums = st.sampled_from([s * p for p in range(1, max_num + 1) for s in (1, -1)])
    else:
        nums = st.integers(-max_num, max_num)
    return st.builds(sp.Rational, nums, st.integers(1, max_den))


def _variables(J: JetSpace, order: int, with_time: bool, of) -> tuple[sp.Symbol, ...]:
    if order < 0:
        raise InvalidArgument(f"order must be >= 0, got {order}")
    bases = tuple(J.q if of is None else of)
    if not bases and not with_time:
        raise InvalidArgument("no variables: give some bases in `of` or with_time=True")
    out = [J.t] if with_time else []
    for k in range(order + 1):
        out.extend(J.jets(k, of=bases))
    return tuple(out)


# Strategies are values: the private builders are cached so that drawing a deep
# expression does not rebuild (and re-validate) the same strategies over and over.
@lru_cache(maxsize=1024)
def _monomial(variables: tuple[sp.Symbol, ...], max_degree: int = 2):
    return _monomial_impl(variables, max_degree)


@lru_cache(maxsize=1024)
def _bounded(variables: tuple[sp.Symbol, ...], depth: int):
    return _bounded_impl(variables, depth)


@lru_cache(maxsize=1024)
def _expr(variables: tuple[sp.Symbol, ...], depth: int, nonconstant: bool = False):
    return _expr_impl(variables, depth, nonconstant)


@lru_cache(maxsize=1024)
def _choice(variables: tuple[sp.Symbol, ...]):
    return st.sampled_from(variables)


@st.composite
def _monomial_impl(draw, variables: Sequence[sp.Symbol], max_degree: int = 2):
    """c * v1**k1 * ... with total degree 1..max_degree."""
    c = draw(_rationals(nonzero=True))
    degree = draw(st.integers(1, max_degree))
    factors = draw(st.lists(_choice(variables), min_size=degree, max_size=degree))
    return c * sp.Mul(*factors)


@st.composite
def _bounded_impl(draw, variables: Sequence[sp.Symbol], depth: int):
    """A bounded argument for exp: c*v, or sin/cos of a non-constant subexpression."""
    kind = draw(st.sampled_from(("linear", "sin", "cos")))
    if kind == "linear" or depth <= 0:
        return draw(_rationals(max_num=1, max_den=2, nonzero=True)) * draw(_choice(variables))
    inner = draw(_expr(variables, depth - 1, nonconstant=True))
    return (sp.sin if kind == "sin" else sp.cos)(inner)


@st.composite
def _expr_impl(draw, variables: Sequence[sp.Symbol], depth: int, nonconstant: bool = False):
    """A small, everywhere-defined expression of nesting depth <= ``depth``.

    ``nonconstant`` leaves out rational leaves (used for the arguments of functions, so
    that no effort goes into constants like ``sin(2/3)``).
    """
    leaf_kinds = ("var", "monomial") if nonconstant else ("const", "var", "monomial")
    kinds = leaf_kinds if depth <= 0 else leaf_kinds + (
        "sum", "product", "sin", "cos", "exp", "sqrt", "recip")
    kind = draw(st.sampled_from(kinds))
    if kind == "const":
        return draw(_rationals())
    if kind == "var":
        return draw(_choice(variables))
    if kind == "monomial":
        return draw(_monomial(variables))
    sub = _expr(variables, depth - 1)
    arg = _expr(variables, depth - 1, nonconstant=True)
    if kind == "sum":
        return draw(arg) + draw(sub)
    if kind == "product":
        return draw(arg) * draw(sub if not nonconstant else arg)
    c = draw(_rationals(nonzero=True))
    if kind in ("sin", "cos"):
        return c * (sp.sin if kind == "sin" else sp.cos)(draw(arg))
    if kind == "exp":
        return c * sp.exp(draw(_bounded(variables, depth - 1)))
    if kind == "sqrt":
        a = draw(arg)
        if draw(st.booleans()):
            return c * sp.sqrt(2 + sp.sin(a))
        return c * sp.sqrt(1 + a**2)
    # "recip": division only by a strictly positive denominator
    return c / (1 + draw(arg) ** 2)


# ---------------------------------------------------------------------------- public
def jet_spaces(min_n: int = 1, max_n: int = 6) -> st.SearchStrategy[JetSpace]:
    """Jet spaces with ``min_n <= n <= max_n`` coordinates named ``q1, ..., qn`` (time ``t``)."""
    if not 1 <= min_n <= max_n:
        raise InvalidArgument(f"need 1 <= min_n <= max_n, got min_n={min_n}, max_n={max_n}")
    return st.integers(min_n, max_n).map(
        lambda n: JetSpace([f"q{i}" for i in range(1, n + 1)]))


def jet_expressions(J: JetSpace, order: int = 1, max_depth: int = 3, with_time: bool = True,
                    of: Iterable[sp.Symbol] | None = None) -> st.SearchStrategy[sp.Expr]:
    """Small random expressions in ``t`` and the jets of order ``<= order`` of ``of``.

    ``of`` defaults to the coordinates ``J.q`` (give fields of ``J.with_fields`` to include
    them).  The expression is a sum of one to three terms, each built from rationals,
    monomials, sums and products, ``c*sin(a)``, ``c*cos(a)``, ``c*exp(b)`` with bounded
    ``b``, ``c*sqrt(1 + a**2)``, ``c*sqrt(2 + sin(a))`` and ``c/(1 + a**2)``, nested at
    most ``max_depth`` deep.  It is defined (finite, real) at every real point.  It may
    be constant; it has jet order at most ``order``.
    """
    variables = _variables(J, order, with_time, of)
    if max_depth < 0:
        raise InvalidArgument(f"max_depth must be >= 0, got {max_depth}")
    return st.lists(_expr(variables, max_depth), min_size=1, max_size=3).map(
        lambda terms: sp.Add(*terms))


def polynomials(J: JetSpace, order: int = 1, max_degree: int = 2, max_terms: int = 3,
                with_time: bool = True, of: Iterable[sp.Symbol] | None = None
                ) -> st.SearchStrategy[sp.Expr]:
    """Polynomials with small rational coefficients in ``t`` and jets of order ``<= order``.

    A constant plus up to ``max_terms`` monomials of degree ``1..max_degree``.
    """
    variables = _variables(J, order, with_time, of)
    if max_degree < 1 or max_terms < 0:
        raise InvalidArgument("need max_degree >= 1 and max_terms >= 0")
    return st.builds(
        lambda c, terms: c + sp.Add(*terms),
        _rationals(),
        st.lists(_monomial(variables, max_degree), max_size=max_terms))


MASSES = ("diagonal", "full")


@st.composite
def lagrangians(draw, J: JetSpace, with_time: bool = True, gyroscopic: bool | None = None,
                max_depth: int = 2, mass: str | None = "diagonal") -> sp.Expr:
    """Regular Lagrangians ``1/2 qd^T M(q) qd + sum_s A_s(t, q) qd_s - V(t, q)``.

    ``mass="diagonal"``: ``M = diag(m_s g_s)``, ``m_s`` positive rationals, ``g_s`` 1
    except, sometimes, for one coordinate where it is ``1 + q_r**2/2``.  ``mass="full"``:
    that diagonal plus one or two ``w w^T`` with ``w_s(q)`` rationals or small order-0
    expressions, so M is non-diagonal and configuration-dependent; ``None`` draws
    either.  M is positive definite everywhere.  ``V`` is a small expression of order 0
    (nested at most ``max_depth`` deep); ``with_time=False`` makes ``L`` autonomous.
    Gyroscopic terms ``A_s(t, q) qd_s`` (linear in velocities) appear sometimes;
    ``gyroscopic=True/False`` forces them on or off.
    """
    if mass not in MASSES + (None,):
        raise InvalidArgument(f"mass must be one of {MASSES} or None, got {mass!r}")
    masses = draw(st.lists(_rationals(max_num=3, max_den=2, positive=True),
                           min_size=J.n, max_size=J.n))
    gains = [sp.S.One] * J.n
    if draw(st.booleans()):
        s = draw(st.integers(0, J.n - 1))
        r = draw(st.sampled_from(J.q))
        gains[s] = 1 + r**2 / 2
    kinetic = sp.Add(*(m * g * v**2 for m, g, v in zip(masses, gains, J.qd))) / 2
    if (mass or draw(st.sampled_from(MASSES))) == "full":
        entry = st.one_of(_rationals(), jet_expressions(J, order=0, max_depth=1,
                                                        with_time=False))
        for _ in range(draw(st.integers(1, 2))):
            w = draw(st.lists(entry, min_size=J.n, max_size=J.n))
            kinetic += sp.Add(*(c * v for c, v in zip(w, J.qd))) ** 2 / 2
    order0 = jet_expressions(J, order=0, max_depth=max_depth, with_time=with_time)
    potential = draw(st.one_of(st.just(sp.S.Zero), order0))
    L = kinetic - potential
    if gyroscopic is None:
        gyroscopic = draw(st.booleans())
    if gyroscopic:
        picks = draw(st.lists(st.integers(0, J.n - 1), min_size=1, max_size=min(2, J.n),
                              unique=True))
        for s in picks:
            L += draw(st.one_of(_rationals(nonzero=True), order0)) * J.qd[s]
    return L


def _check_split(J: JetSpace, m, dependent):
    """Validate ``m`` / ``dependent`` eagerly; ``dependent`` as coordinates of ``J`` (or None)."""
    if J.n < 2:
        raise InvalidArgument(f"constraints need a jet space with n >= 2 coordinates, got {J!r}")
    if dependent is not None:
        by_name = {s.name: s for s in J.q}
        names = [d.name if isinstance(d, sp.Symbol) else str(d) for d in dependent]
        if any(n not in by_name for n in names) or len(set(names)) != len(names):
            raise InvalidArgument(f"dependent={dependent!r}: need distinct coordinates of {J!r}")
        if not 1 <= len(names) < J.n:
            raise InvalidArgument(f"need 1 <= len(dependent) < n={J.n}, got {len(names)}")
        if m is not None and m != len(names):
            raise InvalidArgument(f"m={m} but {len(names)} dependent coordinates given")
        return tuple(by_name[n] for n in names)
    if m is not None and not 1 <= m < J.n:
        raise InvalidArgument(f"need 1 <= m < n={J.n}, got m={m}")
    return None


@st.composite
def _split(draw, J: JetSpace, m, dependent):
    """(dependent, independent) coordinates."""
    if dependent is None:
        m = draw(st.integers(1, J.n - 1)) if m is None else m
        dependent = tuple(draw(st.permutations(J.q))[:m])
    independent = tuple(s for s in J.q if s not in dependent)
    return dependent, independent


def _coefficients(J: JetSpace, with_time: bool = True):
    """B(t, q): sometimes 0, sometimes a constant, otherwise a small order-0 expression."""
    return st.one_of(st.just(sp.S.Zero), _rationals(nonzero=True),
                     jet_expressions(J, order=0, max_depth=2, with_time=with_time))


def affine_constraints(J: JetSpace, m: int | None = None,
                       dependent: Sequence[sp.Symbol] | None = None, implicit: bool = False):
    """``(constraints, dependent)``: m affine constraints.

    Explicit (``implicit=False``): each constraint is ``qd[a] - sum_mu B_mu(t, q) qd[mu] -
    B_0(t, q)`` for a dependent coordinate ``a`` and the independent ones ``mu``, with each
    ``B`` zero, a constant or a small expression of order 0.  Implicit: ``A(q) qd + b(t,
    q)``, those explicit ones mixed by ``S(q)`` (``_mixing``, invertible everywhere),
    so that ``A_dep = S`` is full and configuration-dependent.  ``m`` (1 <= m < n) and
    ``dependent`` are drawn unless given (``dependent`` as Symbols or names).  Returns
    ``(tuple_of_expressions, tuple_of_dependent_coordinates)``.
    """
    return _affine_constraints(J, m, _check_split(J, m, dependent), implicit)


@st.composite
def _affine_constraints(draw, J, m, dependent, implicit=False):
    dep, indep = draw(_split(J, m, dependent))
    coeffs = _coefficients(J)
    constraints = []
    for a in dep:
        rhs = sum((draw(coeffs) * J.qd[J.q.index(mu)] for mu in indep), sp.S.Zero)
        rhs += draw(coeffs)
        constraints.append(J.qd[J.q.index(a)] - rhs)
    if implicit:
        constraints = list(draw(_mixing(J, len(dep))) * sp.Matrix(constraints))
    return tuple(constraints), tuple(dep)


@st.composite
def _mixing(draw, J: JetSpace, k: int):
    """S(q) = U(q) diag(1 + w_a(q)^2) with U unit upper-triangular: det S >= 1 everywhere;
    entries rationals or small order-0 expressions (time-independent)."""
    entry = st.one_of(_rationals(nonzero=True), jet_expressions(J, order=0, max_depth=1,
                                                                with_time=False))
    U = sp.eye(k)
    for a in range(k):
        for b in range(a + 1, k):
            U[a, b] = draw(entry)
    scale = [1 + draw(entry) ** 2 for _ in range(k)]
    return U * sp.diag(*scale)


@st.composite
def _nonlinear_term(draw, J: JetSpace, indep_v: Sequence[sp.Symbol]):
    """A term genuinely nonlinear in the independent velocities, times a nonzero coefficient."""
    c = draw(_rationals(nonzero=True))
    u = draw(st.sampled_from(indep_v))
    v = draw(st.sampled_from(indep_v))
    kind = draw(st.sampled_from(("product", "sqrt", "weighted_square", "cubic")))
    if kind == "product":
        term = u * v
    elif kind == "sqrt":
        term = sp.sqrt(1 + u**2)
    elif kind == "weighted_square":
        weight = draw(jet_expressions(J, order=0, max_depth=1))
        term = (1 + weight**2) * u**2
    else:
        term = u**2 * v
    return c * term


def nonlinear_constraints(J: JetSpace, m: int | None = None,
                          dependent: Sequence[sp.Symbol] | None = None,
                          implicit: bool = False):
    """``(constraints, dependent)``: constraints nonlinear in the velocities.

    Explicit (``implicit=False``): each constraint is ``qd[a] - phi(t, q, qd_mu)`` where
    ``phi`` is an affine part (as in :func:`affine_constraints`) plus one or two
    nonlinear terms among ``c qd_mu qd_nu``, ``c sqrt(1 + qd_mu**2)``, ``c (1 +
    w(q)**2) qd_mu**2`` and ``c qd_mu**2 qd_nu``: nonlinear in the independent
    velocities.  Implicit: one constraint (m = 1: sympy's solve of several such is slow)
    ``exp(c qd[a]) - (1 + phi^2)/(1 + w^2)``, ``phi = c0 + c1 qd_mu + c2 qd_mu qd_nu``,
    ``w = c3 q_r`` (small rationals: sympy solves it quickly), nonlinear in the dependent
    velocity too; its only solution is ``qd[a] = log((1 + phi^2)/(1 + w^2))/c`` and its
    Jacobian ``c exp(c qd[a])`` never vanishes.  ``m`` and ``dependent`` as in
    :func:`affine_constraints`.
    """
    if implicit and (m or 1) != 1 or implicit and dependent is not None and len(dependent) != 1:
        raise InvalidArgument("implicit nonlinear constraints come one at a time (m=1)")
    return _nonlinear_constraints(J, 1 if implicit else m, _check_split(J, m, dependent),
                                  implicit)


@st.composite
def _nonlinear_constraints(draw, J, m, dependent, implicit=False):
    dep, indep = draw(_split(J, m, dependent))
    indep_v = tuple(J.qd[J.q.index(mu)] for mu in indep)
    coeffs = _coefficients(J)
    constraints = []
    if implicit:                        # small coefficients: sympy solves it quickly
        u, x = draw(_choice(indep_v)), draw(_choice(J.q))
        phi = (draw(_rationals()) + draw(_rationals(nonzero=True)) * u
               + draw(_rationals(nonzero=True)) * u * draw(_choice(indep_v)))
        c = draw(st.sampled_from((1, sp.Rational(1, 2), -sp.Rational(1, 2))))
        v = J.qd[J.q.index(dep[0])]
        w = draw(_rationals(nonzero=True)) * x
        return (sp.exp(c * v) - (1 + phi**2) / (1 + w**2),), tuple(dep)
    for a in dep:
        phi = draw(coeffs)
        if draw(st.booleans()):
            phi += sum((draw(coeffs) * v for v in indep_v), sp.S.Zero)
        for term in draw(st.lists(_nonlinear_term(J, indep_v), min_size=1, max_size=2)):
            phi += term
        if all(sp.diff(phi, u, v) == 0 for u in indep_v for v in indep_v):
            phi += indep_v[0] ** 2          # nonlinear terms cancelled: keep the promise
        constraints.append(J.qd[J.q.index(a)] - phi)
    return tuple(constraints), tuple(dep)


def constrained_systems(min_n: int = 2, max_n: int = 4, affine: bool | None = None,
                        implicit: bool | None = False, mass: str | None = "diagonal"):
    """``(J, L, constraints, dependent)``: a jet space, a regular Lagrangian and constraints.

    ``J`` has ``min_n <= n <= max_n`` coordinates (``min_n >= 2``; larger ``max_n`` for
    larger systems: sympy's cost grows fast with n), ``L`` comes from
    :func:`lagrangians` with ``mass``; ``affine=True`` draws :func:`affine_constraints`,
    ``False`` :func:`nonlinear_constraints`, ``None`` either; ``implicit`` is passed to
    them (``None``: either).
    """
    if min_n < 2:
        raise InvalidArgument(f"constrained systems need min_n >= 2, got {min_n}")
    if mass not in MASSES + (None,):
        raise InvalidArgument(f"mass must be one of {MASSES} or None, got {mass!r}")
    spaces = jet_spaces(min_n, max_n)
    return _constrained_systems(spaces, affine, implicit, mass)


@st.composite
def _constrained_systems(draw, spaces, affine, implicit=False, mass="diagonal"):
    J = draw(spaces)
    L = draw(lagrangians(J, mass=mass))
    if affine is None:
        affine = draw(st.booleans())
    if implicit is None:
        implicit = draw(st.booleans())
    kind = affine_constraints if affine else nonlinear_constraints
    constraints, dependent = draw(kind(J, implicit=implicit))
    return J, L, constraints, dependent


def forces(J: JetSpace, max_depth: int = 2) -> st.SearchStrategy[dict]:
    """Generalized forces ``{coordinate: Q}`` on one or more of the coordinates: a viscous
    term ``-c qd_s`` (``c`` a positive rational) plus a small expression in ``t``, ``q``
    and ``qd`` (:func:`jet_expressions`, at most ``max_depth`` deep)."""
    def force(q):
        v = J.jet(q, 1)
        return st.builds(lambda c, e: -c * v + e, _rationals(positive=True),
                         jet_expressions(J, order=1, max_depth=max_depth))

    return st.lists(st.sampled_from(J.q), min_size=1, max_size=J.n, unique=True).flatmap(
        lambda qs: st.fixed_dictionaries({q: force(q) for q in qs}))


# ---------------------------------------------------------------------------- values
def systems(min_n: int = 2, max_n: int = 4, affine: bool | None = None,
            implicit: bool | None = False, mass: str | None = "diagonal",
            forced: bool = False) -> st.SearchStrategy:
    """``System`` values: :func:`constrained_systems` (same arguments) built into a
    System, with generalized forces from :func:`forces` when ``forced``."""
    cases = constrained_systems(min_n, max_n, affine, implicit, mass)
    if forced:
        return cases.flatmap(lambda c: forces(c[0]).map(lambda f: _system(c, f)))
    return cases.map(_system)


def _system(case, forces_=None):
    from .mechanics.system import System

    J, L, constraints, dependent = case
    return System(J, L, constraints, dependent, forces=forces_)


def principles() -> st.SearchStrategy:
    """The registered ``jetnh.Principle`` values (chetaev, vakonomic, holder, suslov)."""
    from .mechanics.principles import REGISTRY

    return st.sampled_from(REGISTRY)


def scenes(of: st.SearchStrategy | None = None, under: st.SearchStrategy | None = None,
           t_end: float = 1.0, max_value: float = 1.0) -> st.SearchStrategy:
    """``jetnh.Scene`` values over (0, ``t_end``): a system drawn from ``of`` (default
    :func:`systems`) under a principle drawn from ``under`` (default :func:`principles`),
    with an initial state (coordinates, independent velocities, multipliers) drawn in
    [-``max_value``, ``max_value``]; the dependent velocities follow from the
    constraints.  Building one derives nothing: its kernels compile on first use."""
    return _scenes(systems() if of is None else of, principles() if under is None else under,
                   float(t_end), float(max_value))


@st.composite
def _scenes(draw, of, under, t_end, max_value):
    from .numeric import Scene

    system = draw(of)
    principle = draw(under)
    names = ([q.name for q in system.J.q] + [v.name for v in system.independent_velocities]
             + [m.name for m in principle.multiplier_symbols(system)])
    value = st.floats(-max_value, max_value, allow_nan=False, allow_infinity=False)
    initial = {n: draw(value) for n in names}
    return Scene(system, principle, initial=initial, t_span=(0.0, t_end))
