"""Vector fields on jet space: action on functions, Lie bracket, total derivative, prolongation.

A :class:`VectorField` is an immutable value ``sum_i X^i d/dz^i`` whose coordinates z^i are
the symbols of a :class:`~jetnh.geometry.jet.JetSpace` (time t, coordinates q^s, their jets
q^s_(k), fields and their jets) and whose components X^i are sympy expressions on it.

The module provides what the variation operators of ``variations.py`` are built from:

- :func:`total_derivative_field` -- d/dt truncated to a finite jet order, the field form
  of ``J.D``;
- :func:`prolong` -- the prolongation of a (generalized) vector field xi d_t + eta^s d_q^s
  (Olver, *Applications of Lie Groups to Differential Equations*, 2nd ed., Thm 2.36,
  eq. (2.50); for generalized fields Sec. 5.1).  For xi = 0 it is the free variation with
  q^s_(k) -> D^k eta^s, for which [d, delta] = 0;
- :func:`vertical_field` -- a variation eta^s d_q^s + zeta^s d_qdot^s that need not be a
  prolongation, and :func:`commutator`, its defect
  [d, delta] q^s = d/dt(delta q^s) - delta qdot^s (the bracket in the paper's eqs. (3),
  (13), (25): Zhao et al. 2008).

Nothing here calls ``simplify``: components are kept as sympy builds them (``Add`` merges
identical terms); use :meth:`VectorField.expand` for a canonical form.
"""

from __future__ import annotations

import functools
import numbers
from collections.abc import Iterable, Mapping
from types import MappingProxyType

import sympy as sp

from ..algebra import dag
from ..errors import JetSpaceError
from .jet import JetSpace

__all__ = ["VectorField", "total_derivative_field", "prolong", "vertical_field",
           "commutator"]


# ----------------------------------------------------------------------------- helpers
def _check_space(J) -> JetSpace:
    if not isinstance(J, JetSpace):
        raise JetSpaceError(f"expected a JetSpace, got {type(J).__name__} {J!r}")
    return J


def _bases(J: JetSpace) -> tuple[sp.Symbol, ...]:
    """The dependent variables of J: coordinates, then fields."""
    return J.q + J.fields


def _expr(J: JetSpace, value, what: str) -> sp.Expr:
    """``value`` checked as a scalar expression on ``J``."""
    try:
        e = J.check(value)
    except JetSpaceError as exc:
        raise JetSpaceError(f"{what}: {exc}") from None
    if not isinstance(e, sp.Expr) or getattr(e, "is_Matrix", False):
        raise JetSpaceError(
            f"{what} is {e!r}, a {type(e).__name__}; it must be a scalar sympy expression")
    return e


def _key(J: JetSpace, sym) -> sp.Symbol:
    """``sym`` checked as a coordinate of J (t, a jet of a coordinate, or a jet of a field)."""
    if not isinstance(sym, sp.Symbol):
        raise JetSpaceError(
            f"a vector field component is keyed by {sym!r} ({type(sym).__name__}); keys must "
            "be the Symbols of the jet space: J.t, J.q, J.qd, J.jet(base, k), fields")
    if sym == J.t:
        return sym
    if J.split(sym) is None:
        raise JetSpaceError(
            f"{sym} is not a coordinate of {J!r}: keys must be J.t, a coordinate q^s or a "
            "field, or one of their jets (J.jet(base, k)); parameters have no d/d component")
    return sym


def _base(J: JetSpace, sym, what: str) -> sp.Symbol:
    """``sym`` checked as a coordinate q^s or a field (jet order 0)."""
    if not isinstance(sym, sp.Symbol):
        raise JetSpaceError(f"{what}: {sym!r} is not a Symbol; use J.q or J.fields")
    info = J.split(sym)
    if info is None or info[1] != 0:
        raise JetSpaceError(
            f"{what}: {sym} is not a coordinate or field of {J!r} (jets such as x_t are not "
            "allowed here; give components on J.q / J.fields)")
    return sym


@functools.lru_cache(maxsize=64)
def _sort_key(J: JetSpace):
    """Key ordering t first, then jets by order and by base (coordinates, then fields)."""
    index = {b: i for i, b in enumerate(_bases(J))}

    def key(sym):
        if sym == J.t:
            return (0, 0, "")
        base, k = J.split(sym)
        return (1 + k, index[base], sym.name)
    return key


def _order_of(J: JetSpace, sym) -> int:
    """Jet order of a key: -1 for t, k for q_(k)."""
    return -1 if sym == J.t else J.split(sym)[1]


# ------------------------------------------------------------------------- VectorField
class VectorField:
    """An immutable vector field ``sum_i X^i d/dz^i`` on a jet space.

    ``VectorField(J, {x: -y, y: x})`` is the rotation -y d_x + x d_y.  Keys are J.t,
    coordinates, fields and their jets; values are sympy expressions on J.  Components
    that are structurally zero are dropped.  ``X(f)`` applies the field to a function,
    ``X.bracket(Y)`` is the Lie bracket; ``+``, ``-``, ``f * X`` and ``X / f`` are
    module operations over functions; ``==`` compares components after ``expand``.
    """

    __slots__ = ("_J", "_c", "_hash", "__weakref__")

    def __init__(self, J: JetSpace, components: Mapping):
        J = _check_space(J)
        if isinstance(components, VectorField):
            components = components.components
        if not isinstance(components, Mapping):
            raise JetSpaceError(
                f"components must be a mapping {{Symbol: expression}}, got "
                f"{type(components).__name__}")
        comps = {}
        for sym, value in components.items():
            sym = _key(J, sym)
            comps[sym] = _expr(J, value, f"the component on {sym}")
        self._init(J, comps)

    def _init(self, J, comps):
        key = _sort_key(J)
        self._J = J
        self._c = {s: comps[s] for s in sorted(comps, key=key) if comps[s] != 0}
        self._hash = None

    @classmethod
    def _new(cls, J: JetSpace, comps: dict) -> "VectorField":
        """Construct without validation (components already on J)."""
        obj = cls.__new__(cls)
        obj._init(J, comps)
        return obj

    # ----------------------------------------------------------------- accessors
    @property
    def J(self) -> JetSpace:
        """The jet space the field lives on."""
        return self._J

    @property
    def components(self) -> Mapping:
        """Read-only mapping coordinate Symbol -> component (non-zero ones only)."""
        return MappingProxyType(self._c)

    def __getitem__(self, sym) -> sp.Expr:
        """The component on ``sym`` (0 when absent)."""
        return self._c.get(sym, sp.S.Zero)

    @property
    def order(self) -> int:
        """Highest jet order among the keys (-1 if only d_t or zero)."""
        return max((_order_of(self._J, s) for s in self._c), default=-1)

    @property
    def is_vertical(self) -> bool:
        """True when the field has no d_t component."""
        return self._J.t not in self._c

    @property
    def is_zero(self) -> bool:
        """True when every component expands to 0."""
        return all(sp.expand(c) == 0 for c in self._c.values())

    # ----------------------------------------------------------------- action
    def __call__(self, f) -> sp.Expr:
        """The derivative of ``f`` along the field: sum_i X^i df/dz^i."""
        return self._apply(_expr(self._J, f, "the function a vector field acts on"))

    def _apply(self, f: sp.Expr) -> sp.Expr:
        fs, cache = dag.free_symbols(f), {}
        return sp.Add(*[c * dag.diff(f, s, cache=cache) for s, c in self._c.items() if s in fs])

    def bracket(self, other: "VectorField") -> "VectorField":
        """The Lie bracket [X, Y] with components X(Y^i) - Y(X^i)."""
        self._same_space(other, "bracket")
        keys = set(self._c) | set(other._c)
        comps = {s: self._apply(other[s]) - other._apply(self[s]) for s in keys}
        return VectorField._new(self._J, comps)

    # ----------------------------------------------------------------- algebra
    def _same_space(self, other, op):
        if not isinstance(other, VectorField):
            raise TypeError(f"cannot {op} a VectorField and a {type(other).__name__}")
        if other._J != self._J:
            raise JetSpaceError(
                f"cannot {op} vector fields on different jet spaces {self._J!r} and "
                f"{other._J!r}")

    def __add__(self, other):
        if isinstance(other, (int, sp.Integer)) and other == 0:   # sum([...]) starts at 0
            return self
        if not isinstance(other, VectorField):
            return NotImplemented
        self._same_space(other, "add")
        keys = set(self._c) | set(other._c)
        return VectorField._new(self._J, {s: self[s] + other[s] for s in keys})

    __radd__ = __add__

    def __neg__(self):
        return VectorField._new(self._J, {s: -c for s, c in self._c.items()})

    def __sub__(self, other):
        if not isinstance(other, VectorField):
            return NotImplemented
        return self + (-other)

    def __mul__(self, f):
        if isinstance(f, VectorField):
            return NotImplemented
        f = _expr(self._J, f, "a vector field's scalar factor")
        return VectorField._new(self._J, {s: f * c for s, c in self._c.items()})

    __rmul__ = __mul__

    def __truediv__(self, f):
        if isinstance(f, VectorField):
            return NotImplemented
        f = _expr(self._J, f, "a vector field's scalar divisor")
        if f == 0:
            raise ZeroDivisionError("division of a vector field by 0")
        return VectorField._new(self._J, {s: c / f for s, c in self._c.items()})

    # ----------------------------------------------------------------- transforms
    def expand(self) -> "VectorField":
        """The field with ``sympy.expand``-ed components (zero ones dropped)."""
        return VectorField._new(self._J, {s: sp.expand(c) for s, c in self._c.items()})

    def xreplace(self, rule) -> "VectorField":
        """Components with ``xreplace(rule)`` applied (keys unchanged)."""
        return VectorField._new(self._J, {s: c.xreplace(rule) for s, c in self._c.items()})

    def subs(self, *args, **kwargs) -> "VectorField":
        """Components with ``subs(...)`` applied (keys unchanged)."""
        return VectorField._new(self._J, {s: c.subs(*args, **kwargs)
                                          for s, c in self._c.items()})

    def truncate(self, order: int) -> "VectorField":
        """The components on t and on jets of order <= ``order`` only."""
        return VectorField._new(self._J, {s: c for s, c in self._c.items()
                                          if _order_of(self._J, s) <= order})

    def prolong(self, order: int = 1) -> "VectorField":
        """The prolongation of this field (components on t and q^s/fields only); see prolong."""
        if self.order > 0:
            raise JetSpaceError(
                "only a field on t, q^s and fields (no jet components) can be prolonged; "
                f"this one has components on jets of order {self.order}")
        eta = {s: c for s, c in self._c.items() if s != self._J.t}
        return prolong(self._J, eta, xi=self[self._J.t], order=order)

    # ----------------------------------------------------------------- value semantics
    def __eq__(self, other):
        if not isinstance(other, VectorField):
            return NotImplemented
        if other._J != self._J:
            return False
        keys = set(self._c) | set(other._c)
        return all(sp.expand(self[s] - other[s]) == 0 for s in keys)

    def __hash__(self):
        # Equal fields have the same set of keys whose components do not expand to 0.
        if self._hash is None:
            live = frozenset(s for s, c in self._c.items() if sp.expand(c) != 0)
            self._hash = hash((self._J, live))
        return self._hash

    def __repr__(self):
        body = ", ".join(f"{s}: {c}" for s, c in self._c.items())
        return f"VectorField({self._J!r}, {{{body}}})"

    def __str__(self):
        if not self._c:
            return "0"
        return " + ".join(f"({c})*d/d{s}" for s, c in self._c.items())

    def latex(self) -> str:
        """LaTeX ``X^i \\frac{\\partial}{\\partial z^i}`` with dotted jets."""
        if not self._c:
            return "0"
        J = self._J
        parts = []
        for s, c in self._c.items():
            names = J.latex_names(c)
            names.update(J.latex_names(s))
            coord = sp.latex(s, symbol_names=names)
            comp = sp.latex(c, symbol_names=names)
            if c == 1:
                parts.append(rf"\frac{{\partial}}{{\partial {coord}}}")
            else:
                parts.append(rf"\left({comp}\right) \frac{{\partial}}{{\partial {coord}}}")
        return " + ".join(parts)


# --------------------------------------------------------------------- constructions
def total_derivative_field(J: JetSpace, order: int,
                           bases: Iterable[sp.Symbol] | None = None) -> VectorField:
    """d/dt truncated at ``order``: d_t + sum_{k<order} b_(k+1) d/db_(k) over the bases.

    Bases default to the coordinates and the fields of J, so on expressions whose jet
    order (coordinates and fields) is below ``order`` it agrees with ``J.D``.
    """
    J = _check_space(J)
    order = _order_arg(order)
    bs = _bases(J) if bases is None else tuple(_base(J, b, "total_derivative_field")
                                                for b in bases)
    comps = {J.t: sp.S.One}
    for b in bs:
        for k in range(order):
            comps[J.jet(b, k)] = J.jet(b, k + 1)
    return VectorField._new(J, comps)


def _order_arg(order) -> int:
    if isinstance(order, bool) or not isinstance(order, numbers.Integral) or order < 0:
        raise JetSpaceError(f"a jet order must be an integer >= 0, got {order!r}")
    return int(order)


def _eta_dict(J: JetSpace, eta, what: str) -> dict[sp.Symbol, sp.Expr]:
    """``eta`` (mapping over bases, or sequence over J.q or J.q + J.fields) as a dict."""
    if isinstance(eta, VectorField):
        raise JetSpaceError(f"{what}: give the components (a dict or a sequence), or use "
                            "VectorField.prolong")
    if isinstance(eta, Mapping):
        return {_base(J, b, what): _expr(J, v, f"{what}: the component on {b}")
                for b, v in eta.items()}
    if isinstance(eta, (str, bytes, set, frozenset)) or not isinstance(eta, Iterable):
        raise JetSpaceError(
            f"{what}: components must be a dict {{q^s: eta^s}} or a sequence over J.q, got "
            f"{type(eta).__name__}")
    eta = list(eta)
    bases = _bases(J)
    if len(eta) == J.n:
        bases = J.q
    elif len(eta) != len(bases):
        raise JetSpaceError(
            f"{what}: got {len(eta)} components, expected {J.n} (one per coordinate "
            f"{[str(s) for s in J.q]})"
            + (f" or {len(bases)} (coordinates and fields)" if J.fields else ""))
    return {b: _expr(J, v, f"{what}: the component on {b}") for b, v in zip(bases, eta)}


def prolong(J: JetSpace, eta, xi=0, order: int = 1) -> VectorField:
    """The prolongation to jets of order ``order`` of xi d_t + eta^s d/dq^s.

    ``eta`` is a dict over coordinates (and fields) or a sequence over ``J.q``; eta^s and
    xi may depend on t, q, jets of any order and fields (generalized vector fields).  The
    jet components follow Olver, *Applications of Lie Groups to Differential Equations*
    (2nd ed.), Thm 2.36, eq. (2.50), valid verbatim for generalized fields (Sec. 5.1)::

        eta^s_(k) = D^k(eta^s - xi q^s_t) + xi q^s_(k+1),   k = 1..order

    with Q^s = eta^s - xi q^s_t the characteristic; the result equals pr v_Q + xi D.
    Coordinates and fields are the dependent variables; those missing from ``eta`` have
    eta = 0 (so fields get components only through xi).  For xi = 0 (evolutionary,
    vertical) eta^s_(k) = D^k eta^s: the free variation, for which [d, delta] = 0.
    """
    J = _check_space(J)
    order = _order_arg(order)
    eta = _eta_dict(J, eta, "prolong")
    xi = _expr(J, xi, "prolong: xi")
    comps: dict = {}
    if xi != 0:
        comps[J.t] = xi
    for b in _bases(J):
        e = eta.get(b, sp.S.Zero)
        if xi == 0 and e == 0:
            continue
        comps[b] = e
        Q = e - xi * J.jet(b, 1)
        for k in range(1, order + 1):
            Q = J.D(Q)
            comps[J.jet(b, k)] = Q + xi * J.jet(b, k + 1)
    return VectorField._new(J, comps)


def vertical_field(J: JetSpace, eta, velocity_components=None, *, defect=None) -> VectorField:
    """The vertical field eta^s d/dq^s + zeta^s d/dqdot^s (a variation delta).

    ``eta`` (delta q^s) and ``velocity_components`` (zeta^s = delta qdot^s) are dicts over
    the coordinates (and fields) or sequences over ``J.q``.  When ``velocity_components``
    is None, zeta^s = D(eta^s) - c^s with ``defect`` c^s (default 0, i.e. the first
    prolongation, [d, delta] = 0); :func:`commutator` of the result returns c.
    """
    J = _check_space(J)
    eta = _eta_dict(J, eta, "vertical_field")
    if velocity_components is not None and defect is not None:
        raise JetSpaceError("vertical_field: give velocity_components or defect, not both "
                            "(defect c fixes zeta^s = D(eta^s) - c^s)")
    if velocity_components is not None:
        zeta = _eta_dict(J, velocity_components, "vertical_field velocity components")
    else:
        c = {} if defect is None else _eta_dict(J, defect, "vertical_field defect")
        zeta = {b: J.D(eta.get(b, sp.S.Zero)) - c.get(b, sp.S.Zero)
                for b in set(eta) | set(c)}
    comps = dict(eta)
    for b, z in zeta.items():
        comps[J.jet(b, 1)] = z
    return VectorField._new(J, comps)


def commutator(J: JetSpace, field: VectorField, k: int = 0,
               bases: Iterable[sp.Symbol] | None = None) -> tuple[sp.Expr, ...]:
    """The defect [d, delta] q^s_(k) = D(field(q^s_(k))) - field(q^s_(k+1)), one per base.

    For k = 0 this is d/dt(delta q^s) - delta qdot^s of the paper's eq. (13), over
    ``J.q`` (or ``bases``).  It vanishes for prolonged evolutionary fields; for
    ``vertical_field(J, eta, zeta)`` it is D(eta^s) - zeta^s.
    """
    J = _check_space(J)
    if not isinstance(field, VectorField):
        raise JetSpaceError(f"commutator: expected a VectorField, got {type(field).__name__}")
    if field.J != J:
        raise JetSpaceError(f"commutator: the field lives on {field.J!r}, not on {J!r}")
    k = _order_arg(k)
    bs = J.q if bases is None else tuple(_base(J, b, "commutator") for b in bases)
    return tuple(J.D(field[J.jet(b, k)]) - field[J.jet(b, k + 1)] for b in bs)
