"""The Frobenius test for affine (possibly time-dependent) constraints on R x Q.

Affine constraints (the paper's eqs. (33)-(34), with q^0 = t)::

    qdot^alpha = B^alpha_mu(t, q) qdot^mu + B^alpha_0(t, q) = B^alpha_rho qdot^rho

say that the tangent (1, qdot) of a motion t -> (t, q(t)) of the extended configuration
space R x Q lies in the distribution::

    Delta = span{ X_rho = d_rho + B^alpha_rho d_alpha },  rho = 0 (time), independent mu,

which is the annihilator of the constraint one-forms
omega^alpha = dq^alpha - B^alpha_mu dq^mu - B^alpha_0 dt (``constraint_forms``; B from
explicit constraints by ``affine_coefficients``).  The constraints are *integrable*
(holonomic) iff Delta is involutive (Frobenius): then R x Q is foliated by submanifolds
g^alpha(t, q) = c^alpha whose prolongations are the constraints.  Two independent routes:

* ``method="brackets"``: [X_rho, X_sigma] = (X_rho B^alpha_sigma - X_sigma B^alpha_rho) d_alpha.
  The brackets have only d_alpha components while Delta contains no nonzero vector of the
  form c^alpha d_alpha, so Delta is involutive iff every component vanishes.  These
  components, for rho < sigma and every alpha, are the obstructions.  (This is the correct
  form of the condition the paper's (39) refers to,
  d_rho B^a_s - d_s B^a_rho + B^b_rho d_b B^a_s - B^b_s d_b B^a_rho = 0; as printed,
  (39) has mu twice in one product and cannot be read literally.)
* ``method="forms"``: Delta is involutive iff d omega^alpha ^ omega^1 ^ ... ^ omega^k = 0
  for every alpha.  The whole (k+2)-form is tested; the obstructions are read off its
  components on dq^1 ^ ... ^ dq^k ^ dx^rho ^ dx^sigma, which equal
  d omega^alpha(X_rho, X_sigma) = -omega^alpha([X_rho, X_sigma]) (sign normalised so
  that both routes report identical obstruction dicts).

Deciding zero
-------------
A candidate obstruction over ``zero.TREE_MAX`` tree nodes (the coefficients of a long
chain of constraints nest) is decided by evaluation at random points on its shared
graph (``zero.vanishes``), and the result says so (``decided_by``).  Each smaller one is
expanded (``sympy.expand``; a rational one is not expanded
but kept for step 3).  It is then evaluated once at a random point: a clearly nonzero
value proves it nonzero and ends the test, so nonintegrable systems cost no symbolic
simplification.  A rational obstruction is put over a common denominator (``together``
of the unexpanded expression) and its numerator tested with ``sympy.Poly``.  Only terms
that are numerically zero but still not proven zero (trigonometric identities such as
sin^2 + cos^2 - 1) are passed to ``sympy.simplify``, so simplify runs on few, small
expressions and never on the hot path.  With ``numeric=True`` such terms are instead
decided by evaluation at several random points (probabilistic, never calls simplify);
``simplify=False`` reports them as obstructions.  The verdict is local: it holds where
the coefficients (and denominators) are defined.
"""

from __future__ import annotations

from dataclasses import dataclass, field, replace
from typing import Mapping, Sequence

import sympy as sp

from ..algebra import dag, zero
from ..algebra.zero import zero_residual
from ..errors import ConstraintError
from .forms import Form, basis, d, wedge
from .jet import JetSpace, sympy_object

__all__ = ["FrobeniusResult", "frobenius", "frobenius_from_constraints", "decide_zero",
           "bracket_components", "affine_coefficients", "constraint_forms"]

_METHODS = ("brackets", "forms")


@dataclass(frozen=True)
class FrobeniusResult:
    """Verdict of the Frobenius test.

    ``integrable``: whether the constraint distribution is involutive (the constraints are
    holonomic).  ``obstructions``: {(x_rho, x_sigma, q_alpha): nonzero expression} with
    x_rho, x_sigma among (t, independent coordinates), rho before sigma, the component
    [X_rho, X_sigma]^alpha; for constraints whose fibres are not affine, a single entry
    {"fibres": explanation}.  ``method``: "brackets", "forms" or "affinity".
    ``decided_by``: "symbolic", or how many components, too large to expand
    (``zero.TREE_MAX``), were decided by evaluation at random points (``zero.vanishes``;
    a nonzero value is confirmed at two precisions, a zero is probabilistic).
    ``bool(result)`` is ``result.integrable``.
    """

    integrable: bool
    obstructions: dict = field(default_factory=dict)
    method: str = "brackets"
    decided_by: str = "symbolic"

    def __bool__(self):
        return self.integrable

    def __repr__(self):
        from ..algebra.singular import label

        shown = [f"{k}: {label(v, 60) if isinstance(v, sp.Basic) else str(v)[:300]}"
                 for k, v in list(self.obstructions.items())[:4]]
        more = len(self.obstructions) - len(shown)
        return (f"FrobeniusResult(integrable={self.integrable}, method={self.method!r}, "
                f"decided_by={self.decided_by!r}, obstructions={{{', '.join(shown)}"
                f"{f', ... ({more} more)' if more > 0 else ''}}})")


def decide_zero(expr, *, numeric: bool = False, simplify: bool = True, samples: int = 3,
                seed: int = 0, tol: float = 1e-9):
    """None when ``expr`` is (decided) zero, else the nonzero expression to report.

    :func:`jetnh.algebra.zero.zero_residual` with ``simplify`` on by default: expand -> one
    numeric evaluation as a witness of non-zeroness -> numerator over a common
    denominator (rational expressions) -> ``sympy.simplify`` (only for terms still
    numerically zero) or, with ``numeric=True``, evaluation at ``samples`` points.
    """
    return zero_residual(expr, numeric=numeric, simplify=simplify, samples=samples,
                         seed=seed, tol=tol)


def _symbols(J: JetSpace, seq, what: str) -> tuple[sp.Symbol, ...]:
    out = []
    for s in seq:
        if isinstance(s, str):
            s = sp.Symbol(s)
        if s not in J.q:
            raise ConstraintError(f"{s!r} ({what}) is not a coordinate of {J!r}")
        out.append(s)
    if len(set(out)) != len(out):
        raise ConstraintError(f"the {what} coordinates repeat: {tuple(out)}")
    return tuple(out)


def _split(J: JetSpace, dependent, independent) -> tuple[tuple, tuple]:
    """The dependent and independent coordinates (default: the others, in J.q order)."""
    dep = _symbols(J, dependent, "dependent")
    if independent is None:
        return dep, tuple(s for s in J.q if s not in dep)
    ind = _symbols(J, independent, "independent")
    both = set(ind) & set(dep)
    if both:
        raise ConstraintError(f"{both} are both dependent and independent")
    return dep, ind


def _check_B(J: JetSpace, B, k: int, m: int) -> sp.Matrix:
    B = sp.Matrix(B)
    if B.shape != (k, 1 + m):
        raise ConstraintError(
            f"B must have one row per dependent coordinate and 1 + (number of independent) "
            f"columns (time first): expected {(k, 1 + m)}, got {B.shape}")
    for e in B:
        J.check(e)
        for s in dag.free_symbols(e):
            info = J.split(s)
            if info and (info[1] > 0 or info[0] in J.fields):
                raise ConstraintError(
                    f"B^alpha_rho = {e} depends on {s}; the coefficients of affine constraints "
                    "live on R x Q (t and q only)")
    return B


def frobenius(J: JetSpace, B, dependent: Sequence, independent: Sequence | None = None,
              method: str = "brackets", *, numeric: bool = False, simplify: bool = True,
              samples: int = 3, seed: int = 0) -> FrobeniusResult:
    """Frobenius test of qdot^alpha = B^alpha_0(t,q) + B^alpha_mu(t,q) qdot^mu on R x Q.

    ``B``: sympy Matrix, rows = dependent alpha, columns = rho = 0 (time) then the
    independent mu in the order of ``independent`` (default: the other coordinates of J
    in J.q order).  ``method``: "brackets" or "forms" (see the module docstring; both
    give the same obstruction dict).  ``numeric``/``simplify``/``samples``/``seed``: how
    zero is decided (:func:`decide_zero`).
    """
    if method not in _METHODS:
        raise ValueError(f"method must be one of {_METHODS}, got {method!r}")
    dep, ind = _split(J, dependent, independent)
    B = _check_B(J, B, len(dep), len(ind))
    opts = dict(numeric=numeric, simplify=simplify, samples=samples, seed=seed)
    with zero.decisions() as evaluated:
        out = (_brackets if method == "brackets" else _forms)(J, B, dep, ind, opts)
    if evaluated:
        out = replace(out, decided_by=(
            f"evaluation at random points ({len(evaluated)} component"
            f"{'s' if len(evaluated) > 1 else ''} over the size budget)"))
    return out


def bracket_components(J: JetSpace, B, dep, ind) -> dict:
    """Every K^alpha_{rho sigma} = X_rho B^alpha_sigma - X_sigma B^alpha_rho, rho < sigma over
    (t, independent), keyed (x_rho, x_sigma, q_alpha); not reduced, zeros included."""
    xs = (J.t,) + tuple(ind)
    k = len(dep)
    cache: dict = {}        # derivatives of the shared subexpressions of B, once

    def X(rho, f):
        out = [dag.diff(f, xs[rho], cache=cache)]
        for a in range(k):
            c = B[a, rho]
            if c != 0:
                out.append(c * dag.diff(f, dep[a], cache=cache))
        return sp.Add(*out)

    return {(xs[r], xs[s], dep[a]): X(r, B[a, s]) - X(s, B[a, r])
            for r in range(len(xs)) for s in range(r + 1, len(xs)) for a in range(k)}


def _brackets(J, B, dep, ind, opts) -> FrobeniusResult:
    obstructions = {}
    for key, component in bracket_components(J, B, dep, ind).items():
        res = decide_zero(component, **opts)
        if res is not None:
            obstructions[key] = res
    return FrobeniusResult(not obstructions, obstructions, "brackets")


def _forms(J, B, dep, ind, opts) -> FrobeniusResult:
    xs = (J.t,) + ind
    omegas = _omegas(J, B, dep, ind)
    if not omegas:
        return FrobeniusResult(True, {}, "forms")
    Omega = wedge(*omegas)
    obstructions = {}
    whole_zero = True
    for a, qa in enumerate(dep):
        P = d(omegas[a]) ^ Omega
        nonzero = {}
        for key, c in P.terms.items():
            res = decide_zero(c, **opts)
            if res is not None:
                nonzero[key] = res
        if not nonzero:
            continue
        whole_zero = False
        for r in range(len(xs)):
            for s in range(r + 1, len(xs)):
                sign, key = basis(J, dep + (xs[r], xs[s]))
                if key in nonzero:
                    obstructions[(xs[r], xs[s], qa)] = -sign * nonzero[key]
    if not whole_zero and not obstructions:       # cannot happen (see module docstring)
        raise AssertionError("forms route: nonzero (k+2)-form without a read-off obstruction")
    return FrobeniusResult(whole_zero, obstructions, "forms")


def frobenius_from_constraints(J: JetSpace, constraints: Sequence, dependent: Sequence, *,
                               method: str = "brackets", numeric: bool = False,
                               simplify: bool = True) -> FrobeniusResult:
    """Frobenius test of implicit constraints f^a(t, q, qdot) = 0 (one per dependent coordinate).

    Affine constraints f = A qdot_dep + C qdot_ind + c_0 (checked: the Hessian in the
    velocities vanishes) are solved linearly, qdot_dep = -A^{-1}(C qdot_ind + c_0)
    (``Matrix.LUsolve``; ConstraintError when A is singular for this split), and passed to
    :func:`frobenius`.

    Constraints that are not affine in the velocities are solved for the dependent
    velocities with ``sympy.solve``: a unique real solution that is affine in the
    independent velocities goes to :func:`frobenius` (e.g. (xdot - y ydot)^3 = 0).
    Otherwise the fibres of the constraint set over (t, q) are not affine subspaces (a
    graph qdot^alpha = phi^alpha(qdot^mu) with phi not affine, or a union of several
    branches) and the result is ``integrable=False`` with a ``"fibres"`` obstruction.
    Reason: holonomic constraints g^a(t, q) = 0 constrain velocities through their
    derivatives D g^a = d_t g^a + d_s g^a qdot^s = 0, which are affine in qdot; so the
    set of admissible velocities over each point of a leaf g^a = c^a is an affine
    subspace.  A constraint set whose fibres are not affine subspaces therefore cannot be
    the prolongation of holonomic constraints: it is genuinely nonholonomic (each branch
    of a multi-branch set can still be tested on its own with :func:`frobenius`).
    Solutions containing the imaginary unit are discarded as non-real.  When sympy cannot
    solve the constraints a ConstraintError asks for the explicit form.
    """
    dep = _symbols(J, dependent, "dependent")
    ind = tuple(s for s in J.q if s not in dep)
    fs = [J.check(f) for f in constraints]
    if len(fs) != len(dep):
        raise ConstraintError(
            f"{len(fs)} constraints for {len(dep)} dependent coordinates; give one dependent "
            "coordinate per (independent) constraint")
    for f in fs:
        for s in f.free_symbols:
            info = J.split(s) if isinstance(s, sp.Symbol) else None
            if info and (info[1] > 1 or info[0] in J.fields):
                raise ConstraintError(
                    f"the constraint {f} = 0 depends on {s}; constraints live on J^1 "
                    "(t, q, qdot)")
    v_dep = [J.jet(a, 1) for a in dep]
    v_ind = [J.jet(m, 1) for m in ind]
    vel = v_dep + v_ind
    opts = dict(numeric=numeric, simplify=simplify)
    cache: dict = {}
    affine = all(decide_zero(dag.diff(f, v, w, cache=cache), **opts) is None
                 for f in fs for i, v in enumerate(vel) for w in vel[i:])
    if affine:
        # unexpanded on purpose: the structure keeps the rational zero tests cheap
        A = dag.jacobian(fs, v_dep)
        C = dag.jacobian(fs, v_ind)
        c0 = sp.Matrix([f.xreplace({v: 0 for v in vel}) for f in fs])
        if any(s in sp.expand(e).free_symbols for e in list(A) + list(C) for s in vel):
            affine = False        # affine only up to identities expand cannot see
    if affine:
        if decide_zero(A.det(), **opts) is None:
            raise ConstraintError(
                f"the constraints cannot be solved for the velocities of {dep}: the Jacobian "
                f"d f / d qdot_dep = {A.tolist()} is singular (a constraint without velocities "
                "is holonomic: differentiate it with J.D first); choose another split")
        rhs = sp.Matrix.hstack(c0, C) if C.cols else c0
        B = -A.LUsolve(rhs)
        return frobenius(J, B, dep, ind, method, numeric=numeric, simplify=simplify)

    try:
        sols = sp.solve(fs, v_dep, dict=True)
    except (NotImplementedError, ValueError) as exc:
        raise ConstraintError(
            f"cannot solve the non-affine constraints {fs} for {v_dep} ({exc}); give them in "
            "explicit form qdot^alpha - phi^alpha = 0") from None
    sols = [s for s in sols if all(v in s for v in v_dep)
            and not any(s[v].has(sp.I) for v in v_dep)]
    if not sols:
        raise ConstraintError(
            f"sympy finds no real explicit solution of {fs} for {v_dep}; give the constraints "
            "in explicit form qdot^alpha - phi^alpha = 0")
    if len(sols) == 1:
        phi = [sols[0][v] for v in v_dep]
        try:
            B, _ = affine_coefficients(J, phi, dep, ind)
        except ConstraintError:
            return FrobeniusResult(False, {"fibres": (
                f"solving for {v_dep} gives qdot = {phi}, not affine in the independent "
                f"velocities {v_ind}: the admissible velocities over a point of R x Q form a "
                "curved (non-affine) set, while the prolongation of holonomic constraints has "
                "affine fibres (D g = d_t g + d_s g qdot^s is affine in qdot); the "
                "constraints are nonholonomic")}, "affinity")
        return frobenius(J, B, dep, ind, method, numeric=numeric, simplify=simplify)
    branches = [[s[v] for v in v_dep] for s in sols]
    return FrobeniusResult(False, {"fibres": (
        f"the constraints have {len(sols)} branches qdot_dep = {branches}: the admissible "
        "velocities over a point of R x Q are a union of several pieces, not one affine "
        "subspace as for the prolongation of holonomic constraints; test each branch with "
        "frobenius()")}, "affinity")


# ---------------------------------------------------------------------- constraint forms
def affine_coefficients(J: JetSpace, phi, dependent, independent=None):
    """The matrix B of explicit constraints qdot^alpha = phi^alpha(t, q, qdot^mu) when affine.

    ``phi`` is a mapping {dependent coordinate: phi^alpha} or a sequence aligned with
    ``dependent``.  Returns ``(B, independent)`` where ``B`` is a sympy Matrix with one row
    per dependent alpha and columns rho = 0 (time) then the independent mu, such that
    phi^alpha = B^alpha_0 + B^alpha_mu qdot^mu.  Raises ConstraintError when some phi^alpha
    is not affine in the independent velocities (checked with expand), depends on a
    dependent velocity, or on jets of order >= 2.
    """
    dep, ind = _split(J, dependent, independent)
    if isinstance(phi, Mapping):
        try:
            phis = [sympy_object(phi[a] if a in phi else phi[a.name]) for a in dep]
        except KeyError as exc:
            raise ConstraintError(f"no phi given for the dependent coordinate {exc}") from None
    else:
        phis = [sympy_object(f) for f in phi]
        if len(phis) != len(dep):
            raise ConstraintError(f"{len(phis)} expressions phi for {len(dep)} dependent coordinates")
    qd_ind = [J.jet(m, 1) for m in ind]
    bad_vel = set(J.jet(a, 1) for a in dep)
    rows = []
    for a, f in zip(dep, phis):
        J.check(f)
        for s in f.free_symbols:
            info = J.split(s) if isinstance(s, sp.Symbol) else None
            if info is None:
                continue
            if s in bad_vel:
                raise ConstraintError(
                    f"phi^{a} = {f} contains the dependent velocity {s}; explicit constraints "
                    "qdot^alpha = phi^alpha may depend only on t, q and independent velocities")
            if info[1] >= 2 or (info[1] == 1 and s not in qd_ind) or info[0] in J.fields:
                raise ConstraintError(
                    f"phi^{a} = {f} depends on {s}; affine constraints live on J^1 and depend "
                    "only on t, q and the independent velocities")
        Bm = [sp.diff(f, v) for v in qd_ind]
        for v, b in zip(qd_ind, Bm):
            bx = sp.expand(b)
            if any(s in bx.free_symbols for s in qd_ind):
                raise ConstraintError(
                    f"the constraint qdot^{a} = {f} is not affine in the independent velocities: "
                    f"d phi/d {v} = {b} still depends on velocities. Frobenius applies to affine "
                    "constraints qdot^alpha = B^alpha_mu(t,q) qdot^mu + B^alpha_0(t,q) only")
        B0 = sp.expand(f - sum((b * v for b, v in zip(Bm, qd_ind)), sp.S.Zero))
        if any(s in B0.free_symbols for s in qd_ind):
            raise ConstraintError(f"the constraint qdot^{a} = {f} is not affine in the independent "
                                  "velocities")
        rows.append([B0] + [sp.expand(b) for b in Bm])
    return sp.Matrix(rows) if rows else sp.zeros(0, 1 + len(ind)), ind


def constraint_forms(J: JetSpace, phi, dependent, independent=None) -> tuple[Form, ...]:
    """One-forms omega^alpha = dq^alpha - B^alpha_mu dq^mu - B^alpha_0 dt on R x Q.

    For explicit constraints qdot^alpha = phi^alpha(t, q, qdot^mu) affine in the independent
    velocities (eq. (34) of the paper); see :func:`affine_coefficients` for the accepted
    ``phi`` and the ConstraintError raised when phi is not affine.  Their annihilator is the
    constraint distribution; a curve satisfies the constraints iff its tangent lies in it.
    """
    B, ind = affine_coefficients(J, phi, dependent, independent)
    return _omegas(J, B, _symbols(J, dependent, "dependent"), ind)


def _omegas(J: JetSpace, B, dep, ind) -> tuple[Form, ...]:
    """omega^alpha = dq^alpha - B^alpha_rho dx^rho, x^0 = t then the independent ``ind``."""
    xs = (J.t,) + tuple(ind)
    return tuple(Form(J, 1, {(qa,): sp.S.One,
                             **{(x,): -B[a, r] for r, x in enumerate(xs) if B[a, r] != 0}})
                 for a, qa in enumerate(dep))


