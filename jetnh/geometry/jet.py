"""The jet bundle J^k M of M = R x Q: coordinates, jets of any order, D and the Euler operator.

Jet coordinates are plain sympy Symbols named ``x``, ``x_t``, ``x_tt``, ... so that
expressions stay cheap to differentiate and to compile.  Besides the coordinates q^s a
jet space may carry *fields* (Lagrange multipliers lambda_a, variation components eta^s)
that have jets of their own, so that the total derivative acts on them too.

The Euler operator follows the paper's sign convention (Zhao et al. 2008, eq. (3) and
the definitions under (13)): for a first-order F, ``euler(F)[s]`` is
[F]_s = dF/dq^s - d/dt dF/dqdot^s.
"""

from __future__ import annotations

import operator
import re
from functools import cached_property
from typing import Iterable

import sympy as sp
from sympy.core.function import AppliedUndef

from ..algebra import dag
from ..algebra.dag import sympy_object
from ..errors import JetSpaceError

_NAME = re.compile(r"^[A-Za-z][A-Za-z0-9]*(?:_[A-Za-z0-9]+)*$")
_JET_SUFFIX = re.compile(r"^(.+)_(t+)$")

_LATEX_DOTS = {1: r"\dot", 2: r"\ddot", 3: r"\dddot", 4: r"\ddddot"}


def key_name(key) -> str | None:
    """The name a user means by ``key``, else None: a Symbol or a str, or a
    sympy.physics.mechanics dynamicsymbol ``x(t)`` ("x") or its derivative
    ``x(t).diff(t, k)`` ("x_t...t", the jet coordinate's name)."""
    if isinstance(key, sp.Symbol):
        return key.name
    if isinstance(key, str):
        return key
    from sympy.physics.vector import dynamicsymbols

    t = dynamicsymbols._t
    order = 0
    if isinstance(key, sp.Derivative) and all(v == t for v, _ in key.variable_count):
        order = sum(c for _, c in key.variable_count)
        key = key.expr
    if isinstance(key, AppliedUndef) and key.args == (t,):
        return key.func.__name__ + ("_" + "t" * order if order else "")
    return None


def _names(spec) -> tuple[str, ...]:
    """Names from ``"x y"``, ``"x, y"`` or an iterable of str / Symbol."""
    if isinstance(spec, str):
        return tuple(n for n in re.split(r"[\s,]+", spec.strip()) if n)
    if isinstance(spec, sp.Symbol):
        return (spec.name,)
    if not isinstance(spec, Iterable):
        raise JetSpaceError(f"coordinates must be names ('x y phi') or a list of names or "
                            f"Symbols, not {type(spec).__name__}")
    out = []
    for item in spec:
        name = key_name(item)
        if name is None:
            raise JetSpaceError(
                f"coordinate {item!r} is a {type(item).__name__}; give names (str) or "
                "sympy Symbols")
        out.append(name)
    return tuple(out)


def _free(expr) -> set:
    """``expr.free_symbols`` on its shared graph: the union of those of the subexpressions
    that define their own (Symbols, ``Indexed``, ``MatrixSymbol``, ...)."""
    own = [e for e in dag.nodes(expr) if type(e).free_symbols is not sp.Basic.free_symbols]
    return set().union(*(e.free_symbols for e in own))


def _plain_name(s) -> str:
    """A Symbol name for a non-Symbol free symbol (m[1] -> 'm_1')."""
    name = re.sub(r"[^A-Za-z0-9]+", "_", str(s)).strip("_")
    return name if _NAME.match(name) else "m_1"


def _order_arg(k, what) -> int:
    try:
        k = operator.index(k)
    except TypeError:
        raise JetSpaceError(f"{what} must be an integer >= 0, got {k!r}") from None
    if k < 0:
        raise JetSpaceError(f"{what} must be an integer >= 0, got {k}")
    return k


class JetSpace:
    """Coordinates (t, q^s) and their jets q^s_t, q^s_tt, ...; optional fields with jets.

    ``JetSpace("x y phi psi")`` has ``t``, ``q = (x, y, phi, psi)``, ``qd = (x_t, ...)``,
    ``qdd = (x_tt, ...)``; ``jet(x, 3)`` is ``x_ttt``.  Instances are immutable values;
    ``with_fields`` returns a larger space.

    Parameters
    ----------
    coordinates : str or sequence of str or Symbol
        The coordinates q^s: names separated by spaces (``"x y phi psi"``), or a list.
    t : str or Symbol, default "t"
        The time.
    fields : sequence of str or Symbol, optional
        Functions of t with jets of their own (the variation components, for instance).

    Examples
    --------
    >>> import jetnh as jn
    >>> J = jn.JetSpace("x y")
    >>> J.q, J.qd, J.qdd
    ((x, y), (x_t, y_t), (x_tt, y_tt))
    >>> J.jet(J.q[0], 3)
    x_ttt
    """

    def __init__(self, coordinates, t: str | sp.Symbol = "t", fields=()):
        t_name = t.name if isinstance(t, sp.Symbol) else str(t)
        coords = _names(coordinates)
        extra = _names(fields)
        if not coords:
            raise JetSpaceError("a jet space needs at least one coordinate, e.g. JetSpace('x y')")
        seen: set[str] = set()
        for name in (t_name,) + coords + extra:
            if not _NAME.match(name):
                raise JetSpaceError(
                    f"{name!r} is not a usable name: use letters, digits and single "
                    "underscores, starting with a letter (e.g. 'phi', 'q_1')")
            if name in seen:
                raise JetSpaceError(f"the name {name!r} is given twice; names must be distinct")
            seen.add(name)
        for name in (t_name,) + coords + extra:
            m = _JET_SUFFIX.match(name)
            if m:
                raise JetSpaceError(
                    f"the name {name!r} ends in '_{m.group(2)}', which jetnh reserves for jets "
                    f"(it would be a derivative of {m.group(1)!r}); rename it")
        self._t = sp.Symbol(t_name)
        self._coords = tuple(sp.Symbol(n) for n in coords)
        self._fields = tuple(sp.Symbol(n) for n in extra)
        self._base_by_name = {s.name: s for s in self._coords + self._fields}
        self._split_cache: dict[sp.Symbol, tuple[sp.Symbol, int] | None] = {}

    # ----------------------------------------------------------------- value semantics
    def _key(self):
        return (self._t.name, tuple(s.name for s in self._coords),
                tuple(s.name for s in self._fields))

    def __eq__(self, other):
        return isinstance(other, JetSpace) and self._key() == other._key()

    def __hash__(self):
        return hash(self._key())

    def __repr__(self):
        f = f", fields={[s.name for s in self._fields]}" if self._fields else ""
        return f"JetSpace({[s.name for s in self._coords]}{f})"

    # ------------------------------------------------------------------- coordinates
    @property
    def t(self) -> sp.Symbol:
        """The time symbol."""
        return self._t

    @property
    def q(self) -> tuple[sp.Symbol, ...]:
        """The coordinates q^s."""
        return self._coords

    @property
    def n(self) -> int:
        """The number of coordinates."""
        return len(self._coords)

    @property
    def fields(self) -> tuple[sp.Symbol, ...]:
        """Extra fields with jets of their own (multipliers, variation components)."""
        return self._fields

    @cached_property
    def qd(self) -> tuple[sp.Symbol, ...]:
        """First jet coordinates q^s_t (velocities)."""
        return self.jets(1)

    @cached_property
    def qdd(self) -> tuple[sp.Symbol, ...]:
        """Second jet coordinates q^s_tt (accelerations)."""
        return self.jets(2)

    def jets(self, k: int, of: Iterable[sp.Symbol] | None = None) -> tuple[sp.Symbol, ...]:
        """The k-th jets of the coordinates (or of the given bases)."""
        return tuple(self.jet(b, k) for b in (self._coords if of is None else of))

    def jet(self, base: sp.Symbol | str, k: int) -> sp.Symbol:
        """The k-th jet of a coordinate or field: ``jet(x, 2)`` is ``x_tt``."""
        name = base.name if isinstance(base, sp.Symbol) else str(base)
        if name not in self._base_by_name:
            raise JetSpaceError(
                f"{name!r} is not a coordinate or field of {self!r}; jets exist only of those")
        k = _order_arg(k, "jet order")
        return self._base_by_name[name] if k == 0 else sp.Symbol(f"{name}_{'t' * k}")

    def with_fields(self, fields) -> "JetSpace":
        """A jet space with the same coordinates and these fields added."""
        return JetSpace(self._coords, self._t, self._fields + tuple(sp.Symbol(n) for n in _names(fields)))

    def split(self, sym: sp.Symbol) -> tuple[sp.Symbol, int] | None:
        """``(base, k)`` when ``sym`` is the k-th jet of a coordinate or field, else None.

        A symbol that carries a jet name but differs from the jet (e.g. it has
        assumptions such as ``real=True``) is an error: it would silently be a constant.
        """
        try:
            return self._split_cache[sym]
        except KeyError:
            pass
        name = sym.name
        if name == self._t.name:
            if sym != self._t:
                raise JetSpaceError(
                    f"the symbol {name!r} clashes with the time symbol of the jet space (it has "
                    f"assumptions {sym.assumptions0}); use J.t")
            self._split_cache[sym] = None
            return None
        if name in self._base_by_name:
            base, k = self._base_by_name[name], 0
        else:
            m = _JET_SUFFIX.match(name)
            if not (m and m.group(1) in self._base_by_name):
                self._split_cache[sym] = None
                return None
            base, k = self._base_by_name[m.group(1)], len(m.group(2))
        if sym != self.jet(base, k):
            raise JetSpaceError(
                f"the symbol {name!r} clashes with the jet coordinate of the same name "
                f"(it has assumptions {sym.assumptions0}); use the plain Symbols of the jet "
                "space (J.q, J.qd, J.jet(...)) or rename the symbol")
        self._split_cache[sym] = (base, k)
        return base, k

    def order(self, expr, of: Iterable[sp.Symbol] | None = None) -> int:
        """The highest jet order of the coordinates (or given bases) in ``expr``; -1 if none."""
        bases = set(self._coords if of is None else of)
        best = -1
        for s in dag.free_symbols(sympy_object(expr)):
            info = self.split(s)
            if info and info[0] in bases:
                best = max(best, info[1])
        return best

    # ------------------------------------------------------------------- validation
    def check(self, expr) -> sp.Expr:
        """``expr`` as a sympy expression on this jet space, or a JetSpaceError.

        Refuses strings, free symbols that are not Symbols (``Indexed`` such as ``m[1]``),
        symbols that clash with jet names, and coordinates written as
        sympy.physics.mechanics dynamicsymbols such as ``x(t)`` (convert those with
        ``from_dynamic``).  Undefined functions of other names, such as a forcing ``u(t)``
        or a generic ``f(t, x, x_t)``, are explicit functions and allowed.
        """
        expr = sympy_object(expr)
        if not isinstance(expr, sp.Basic):
            raise JetSpaceError(f"{expr!r} is not a sympy expression")
        for s in _free(expr):
            if not isinstance(s, sp.Symbol):
                raise JetSpaceError(
                    f"{s} (of type {type(s).__name__}) is not a Symbol; jetnh's parameters are plain "
                    f"Symbols: write e.g. sp.Symbol({_plain_name(s)!r}) instead")
            self.split(s)
        for f in dag.atoms(expr, AppliedUndef):
            if f.func.__name__ in self._base_by_name:
                raise JetSpaceError(
                    f"{f} is a function of time in dynamicsymbols style; convert the "
                    "expression with J.from_dynamic(expr) first")
        return expr

    # ------------------------------------------------------------------- calculus
    def D(self, expr, cache: dict | None = None) -> sp.Expr:
        """Total time derivative d/dt = d_t + sum_k q_(k+1) d/dq_(k), on coordinates and
        fields; the partial derivatives on the shared graph (``dag.diff``, whose
        ``cache`` it takes)."""
        expr = sympy_object(expr)
        cache = {} if cache is None else cache
        terms = []
        for s in sorted(dag.free_symbols(expr), key=lambda s: s.name):
            if s == self._t:
                terms.append(dag.diff(expr, s, cache=cache))
                continue
            info = self.split(s)
            if info is not None:
                terms.append(dag.mul(dag.diff(expr, s, cache=cache),
                                     self.jet(info[0], info[1] + 1)))
        return dag.build(sp.Add, terms)

    def Dk(self, expr, k: int) -> sp.Expr:
        """The k-th total derivative."""
        k = _order_arg(k, "the order of a total derivative")
        for _ in range(k):
            expr = self.D(expr)
        return expr

    def euler(self, expr, wrt: Iterable[sp.Symbol] | None = None) -> tuple[sp.Expr, ...]:
        """Euler operators sum_k (-D)^k d expr / d q^s_(k), one per coordinate (or per ``wrt``).

        For first-order ``expr`` this is the paper's [expr]_s = d/dq^s - d/dt d/dqdot^s.
        """
        expr = sympy_object(expr)
        bases = self._coords if wrt is None else tuple(wrt)
        for b in bases:
            if not (isinstance(b, sp.Symbol) and self.split(b) and self.split(b)[1] == 0):
                raise JetSpaceError(f"euler(..., wrt=...) takes coordinates or fields, not {b!r}")
        cache: dict = {}            # derivatives of shared subexpressions, computed once
        out = []
        for b in bases:
            top = self.order(expr, of=(b,))
            if top < 0:
                out.append(sp.S.Zero)
                continue
            e = dag.diff(expr, self.jet(b, top), cache=cache)
            for k in range(top - 1, -1, -1):          # Horner form of sum (-D)^k d/db_(k)
                e = dag.diff(expr, self.jet(b, k), cache=cache) - self.D(e, cache)
            out.append(e)
        return tuple(out)

    # ------------------------------------------------------ sympy.physics.mechanics
    def from_dynamic(self, expr) -> sp.Expr:
        """Replace dynamicsymbols ``x(t)``, ``x(t).diff(t, k)`` by jet Symbols ``x``, ``x_t...``."""
        from sympy.physics.vector import dynamicsymbols

        expr = sympy_object(expr)
        t_dyn = dynamicsymbols._t
        repl = {}
        for der in expr.atoms(sp.Derivative):
            f = der.expr
            if isinstance(f, AppliedUndef) and f.args == (t_dyn,) and all(
                    v == t_dyn for v, _ in der.variable_count):
                repl[der] = self.jet(self._dyn_base(f), sum(c for _, c in der.variable_count))
        for f in expr.atoms(AppliedUndef):
            if f.args == (t_dyn,):
                repl[f] = self._dyn_base(f)
        if t_dyn != self._t:
            repl[t_dyn] = self._t
        return self.check(expr.xreplace(repl))     # one pass: no replacement is re-replaced

    def _dyn_base(self, f) -> sp.Symbol:
        name = f.func.__name__
        if name not in self._base_by_name:
            raise JetSpaceError(
                f"{f} is not a coordinate or field of {self!r}; add {name!r} to the jet "
                "space or substitute it before converting")
        return self._base_by_name[name]

    def to_dynamic(self, expr) -> sp.Expr:
        """Replace jet Symbols by sympy.physics.mechanics dynamicsymbols and derivatives."""
        from sympy.physics.vector import dynamicsymbols

        expr = sympy_object(expr)
        t_dyn = dynamicsymbols._t
        repl = {}
        for s in expr.free_symbols:
            if s == self._t:
                repl[s] = t_dyn
                continue
            info = self.split(s) if isinstance(s, sp.Symbol) else None
            if info:
                f = dynamicsymbols(info[0].name)
                repl[s] = f if info[1] == 0 else f.diff(t_dyn, info[1])
        return expr.xreplace(repl)

    # ------------------------------------------------------------------- printing
    def latex_names(self, expr) -> dict[sp.Symbol, str]:
        """``symbol_names`` for ``sympy.latex`` that print jets with dots (x_tt -> \\ddot{x})."""
        out = {}
        for s in sympy_object(expr).free_symbols:
            info = self.split(s) if isinstance(s, sp.Symbol) else None
            if info and info[1] > 0:
                base = sp.latex(info[0])
                k = info[1]
                out[s] = (f"{_LATEX_DOTS[k]}{{{base}}}" if k in _LATEX_DOTS
                          else f"{base}^{{({k})}}")
        return out

    def latex(self, expr) -> str:
        """LaTeX of a jet expression with dotted jets."""
        return sp.latex(expr, symbol_names=self.latex_names(expr))
