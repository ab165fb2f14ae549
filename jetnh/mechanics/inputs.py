"""What a System accepts from its user, and how it is normalised.

The Lagrangian and each constraint are single real sympy expressions: ``Eq(lhs, rhs)``
means the constraint ``lhs - rhs``; one constraint need not be in a list, and a column
Matrix is read as its entries.  Strings are never parsed (that would execute code);
``None``, booleans, inequalities, containers and non-sympy objects are refused with what
to give instead.  sympy.physics.mechanics coordinates ``x(t)`` and their derivatives
become jet Symbols; ``Abs`` and ``sign`` of t, q, qdot are rewritten smoothly, with their
kink as a square-root argument (a singularity indicator of the compiled equations); other
non-smooth functions of t, q, qdot are refused.  Names a user might give a velocity by
hand (``xdot``, ``x_dot``, ...) are flagged, and numbers are finite and real.
Generalized forces come as a dict keyed by coordinate, each value checked like the
Lagrangian.
"""

from __future__ import annotations

import math
import numbers
import operator
import re
import warnings
from collections.abc import Mapping, Set

import sympy as sp
from sympy.core.function import AppliedUndef

from ..algebra import dag
from ..errors import ConstraintError, JetnhWarning, JetSpaceError, LagrangianError
from ..geometry.jet import key_name

# Functions that are not differentiable where their argument crosses a threshold.  Abs
# and sign are rewritten smoothly (sqrt(u**2), u/sqrt(u**2)), whose kink u = 0 the
# compiled integrators see as a singularity; these have no such form and are refused
# when their arguments depend on t, q or qdot.
NONSMOOTH = (sp.Piecewise, sp.Heaviside, sp.DiracDelta, sp.Max, sp.Min, sp.floor,
              sp.ceiling, sp.frac, sp.re, sp.im, sp.arg, sp.conjugate, sp.Mod)
JET_TAIL = re.compile(r"^(.*?)(_t+)?$")
# names a user may give a velocity by hand: x -> xdot, x_dot, dx, x_d, xp, ...
LOOKALIKE = ("{}dot", "{}_dot", "d{}", "d_{}", "{}_d", "{}d", "{}p", "{}_p", "{}prime",
              "{}_prime", "{}t", "{}dt", "{}_dt", "d{}dt", "d{}_dt", "d_{}_dt", "dot{}",
              "dot_{}", "{}'", "{}\u0307", "{}_v", "v_{}")


def constraint_list(constraints) -> list:
    """The constraints argument as a list of entries (each checked by ``scalar``)."""
    if constraints is None:
        return []
    if isinstance(constraints, str):
        raise JetSpaceError(
            f"constraints is the string {constraints!r}; jetnh never parses strings here "
            "(that would execute code). Build expressions from the Symbols of the jet space")
    if isinstance(constraints, sp.MatrixBase):
        if min(constraints.shape) > 1:
            raise ConstraintError(
                f"constraints is a {constraints.rows}x{constraints.cols} Matrix; give a list "
                "of expressions (or a column Matrix, read as its entries)")
        return list(constraints)
    if isinstance(constraints, (sp.Basic, bool, numbers.Number)):
        return [constraints]                    # one constraint, not in a list
    if isinstance(constraints, (Set, Mapping)):
        raise ConstraintError(
            f"constraints is a {type(constraints).__name__}; give a list (the order names "
            "the multipliers and pairs constraints with dependent coordinates)")
    try:
        return list(constraints)
    except TypeError:
        raise ConstraintError(
            f"constraints must be a list of sympy expressions, got a "
            f"{type(constraints).__name__}") from None


def scalar(expr, what: str, err) -> sp.Expr:
    """One finite real sympy expression from a user's Lagrangian or constraint entry:
    Eq(lhs, rhs) is the constraint lhs - rhs (an error for the Lagrangian); strings,
    None, booleans, relations other than Eq, containers and non-sympy objects are errors
    of class ``err`` that say what to give instead."""
    if expr is None:
        raise err(f"{what} is None; give a sympy expression")
    if isinstance(expr, str):
        raise JetSpaceError(
            f"{what} is the string {expr!r}; jetnh never parses strings here (that would "
            "execute code). Build expressions from the Symbols of the jet space (J.q, J.qd)")
    if isinstance(expr, (bool, sp.logic.boolalg.BooleanAtom)):
        raise err(
            f"{what} is the boolean {expr}: an equation sympy already decided (Eq of "
            "identical sides is True, of different numbers False); give an expression f "
            "meaning f = 0")
    if isinstance(expr, sp.Eq):
        if err is LagrangianError:
            raise err(
                f"the Lagrangian is the equation {expr}; give the expression L itself "
                "(e.g. T - V), not an equation")
        return scalar(expr.lhs - expr.rhs, what, err)
    if isinstance(expr, sp.core.relational.Relational):
        raise err(
            f"{what} is the relation {expr}; jetnh imposes equations f = 0 (give f, or "
            "Eq(lhs, rhs)); inequalities and Ne are not constraints it can impose")
    if isinstance(expr, (sp.MatrixBase, list, tuple, dict, Set)) or (
            type(expr).__module__ == "numpy" and getattr(expr, "ndim", 0) > 0):
        raise err(
            f"{what} is a {type(expr).__name__}, not one expression"
            + ("" if err is LagrangianError else "; give a flat list of expressions"))
    if isinstance(expr, sp.Basic):
        if not isinstance(expr, sp.Expr):
            raise err(f"{what} is a {type(expr).__name__} ({expr}), not an expression")
    elif isinstance(expr, numbers.Number):
        expr = sp.sympify(expr, strict=True)
    else:
        raise err(f"{what}, {expr!r}, is of type {type(expr).__name__}, not a sympy expression")
    if dag.has(expr, sp.oo, -sp.oo, sp.zoo, sp.nan):
        raise err(f"{what}, {expr}, contains an infinity or nan")
    if dag.has(expr, sp.I):
        raise err(f"{what}, {expr}, contains the imaginary unit; jetnh's Lagrangians and "
                  "constraints are real")
    for e in dag.nodes(expr):
        if e.is_Pow and e.exp.is_Number and abs(e.exp) > MAX_POWER and e.base.free_symbols:
            raise err(f"{what} has the power {_clip(e)} with exponent {_clip(e.exp)}, beyond "
                      f"the budget of |exponent| <= {MAX_POWER} (its derivatives and their "
                      "code grow with it); rescale the model")
    return expr


#: the largest |exponent| of a power of a variable in L, the constraints and the forces
MAX_POWER = 64


def _clip(e, width=60) -> str:
    text = str(e)
    return text if len(text) <= width else text[:width - 4] + " ..."


def convert_dynamic(expr, J):
    """sympy.physics.mechanics style coordinates x(t) and x(t).diff(t, k) (functions named
    after a coordinate, of the jet space's time) as the jet Symbols x, x_t, ...;
    explicit functions of other names (a forcing u(t)) stay."""
    names = {s.name: s for s in J.q}

    def coord(f):
        return isinstance(f, AppliedUndef) and f.func.__name__ in names and f.args == (J.t,)

    repl = {}
    for der in expr.atoms(sp.Derivative):
        if coord(der.expr) and all(v == J.t for v, _ in der.variable_count):
            repl[der] = J.jet(names[der.expr.func.__name__],
                              sum(c for _, c in der.variable_count))
    for f in expr.atoms(AppliedUndef):
        if coord(f):
            repl[f] = names[f.func.__name__]
    return expr.xreplace(repl) if repl else expr


def on_jets(e, J) -> bool:
    """Whether ``e`` depends on time or a jet coordinate (or an explicit function)."""
    return dag.has(e, AppliedUndef) or any(
        s == J.t or J.split(s) for s in dag.free_symbols(e))


def refuse_specials(expr, J, what: str, err):
    """Non-smooth functions of t, q, qdot, and unevaluated derivatives, are errors."""
    for e in dag.nodes(expr):
        if isinstance(e, NONSMOOTH) and on_jets(e, J):
            raise err(
                f"{what} contains {e}, which is not differentiable where its argument "
                "crosses a threshold, so the equations of motion do not exist there; write a "
                "smooth expression (a smooth approximation such as tanh(u/eps) for a sign), "
                "or Abs/sign, which jetnh supports and whose kink the integrators stop at")
        if isinstance(e, sp.Derivative) and not isinstance(e.expr, AppliedUndef):
            raise err(
                f"{what} contains the unevaluated derivative {e}; evaluate it (.doit()), or "
                "write J.D(expr) for the total time derivative of an expression")
        if isinstance(e, sp.Integral):
            raise err(f"{what} contains the integral {e}; jetnh needs explicit expressions")


def smooth_kinks(expr, J, what: str, err):
    """Abs(u) -> sqrt(u**2) and sign(u) -> u/sqrt(u**2) for u depending on t, q, qdot:
    the same functions, whose derivatives away from u = 0 (sign(u) du, and 0) sympy and
    symengine take, and whose kink u = 0 is a square-root argument, hence a singularity
    indicator of the compiled equations."""
    def kink(e):
        return isinstance(e, (sp.Abs, sp.sign)) and on_jets(e.args[0], J)

    def smooth(e):
        u = e.args[0]
        return sp.sqrt(u**2) if isinstance(e, sp.Abs) else u / sp.sqrt(u**2)

    for _ in range(4):
        if not dag.has(expr, sp.Abs, sp.sign):
            break
        new = expr.replace(kink, smooth)
        if new == expr:
            break
        expr = new
    for e in dag.nodes(expr):
        if kink(e):
            raise err(f"{what} contains {e}, which jetnh cannot rewrite smoothly; write "
                      "sqrt(u**2) for Abs(u) and u/sqrt(u**2) for sign(u)")
    return expr


def velocity_lookalikes(J) -> dict:
    """Names a user might give the velocity of a coordinate by hand -> the coordinate
    (those that are no symbol of J)."""
    own = {s.name for s in (J.t, *J.q, *J.fields)}
    out = {}
    for q in J.q:
        for pattern in LOOKALIKE:
            name = pattern.format(q.name)
            if name not in own and not J.split(sp.Symbol(name)):
                out.setdefault(name, q)
    return out


def branch_arg(branch):
    if branch is None:
        return None
    if isinstance(branch, (bool, sp.logic.boolalg.BooleanAtom)):
        raise ConstraintError(f"branch must be an integer >= 0, got {branch!r}")
    try:
        branch = operator.index(branch)
    except TypeError:
        raise ConstraintError(
            f"branch must be an integer >= 0 (which solution of nonlinear constraints), got "
            f"{branch!r}") from None
    if branch < 0:
        raise ConstraintError(f"branch counts from 0; got {branch}")
    return branch


def single_root_warning(branch):
    warnings.warn(
        f"branch={branch} is ignored: the constraints have one solution for the dependent "
        "velocities (branch selects among several)", JetnhWarning, stacklevel=4)


def real_number(val, what: str) -> float:
    """A finite real number from a user's value (no strings, booleans or symbols)."""
    if isinstance(val, (str, bool)) or val is None or type(val).__name__ == "bool_":
        raise ConstraintError(f"{what} must be a real number, got {val!r}")
    if isinstance(val, sp.Basic):
        if not (isinstance(val, sp.Expr) and val.is_number):
            raise ConstraintError(f"{what} must be a number, got the expression {val}")
        z = complex(val.evalf(30))
    elif isinstance(val, numbers.Complex):
        z = complex(val)
    else:
        raise ConstraintError(f"{what} must be a real number, got a {type(val).__name__}")
    if z.imag != 0:
        raise ConstraintError(f"{what} must be real, got {val}")
    if not math.isfinite(z.real):
        raise ConstraintError(f"{what} must be finite, got {val}")
    return float(z.real)


def force_items(forces, J) -> list:
    """``forces`` ({coordinate: Q}, coordinates as Symbols or names) as (coordinate, value)
    pairs in the order of the coordinates; the values are checked by the caller."""
    if forces is None:
        return []
    if not isinstance(forces, Mapping):
        raise ConstraintError(
            f"forces must be a dict {{coordinate: Q(t, q, qdot)}}, got a "
            f"{type(forces).__name__}")
    by_name = {q.name: q for q in J.q}
    given = {}
    for key, val in forces.items():
        if isinstance(key, AppliedUndef):             # a dynamicsymbol x(t)
            key = convert_dynamic(key, J)
        name = key_name(key)
        if name not in by_name:
            info = J.split(sp.Symbol(name)) if name else None
            hint = (f" ({name} is a jet of {info[0].name}: key the force by the coordinate)"
                    if info else "")
            raise ConstraintError(
                f"forces key {key!r} is not a coordinate of {J!r}{hint}; key each force by "
                f"a coordinate (Symbol or name: {', '.join(by_name)})")
        q = by_name[name]
        if isinstance(val, sp.core.relational.Relational):
            raise ConstraintError(
                f"the force on {name} is the relation {val}; give the expression Q_{name} "
                "itself")
        if q in given:
            raise ConstraintError(f"two forces given for the coordinate {name!r}")
        given[q] = val
    return [(q, given[q]) for q in J.q if q in given]
