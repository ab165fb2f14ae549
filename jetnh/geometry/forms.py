"""Sparse differential forms on jet space: d, wedge, interior product, pullback, contact forms.

What it is for
--------------
The geometry of constrained mechanics on J^k M (M = R x Q) is written with forms:

* the **contact forms** theta^s = dq^s - qdot^s dt (and theta^s_(k) = dq^s_(k) - q^s_(k+1) dt)
  that vanish exactly along prolonged curves t -> (t, c(t), c'(t), ...);
* the **constraint forms** omega^alpha = dq^alpha - B^alpha_mu dq^mu - B^alpha_0 dt of affine
  constraints qdot^alpha = B^alpha_mu(t, q) qdot^mu + B^alpha_0(t, q) (the paper's eqs.
  (33)-(34), with q^0 = t), built and decided integrable or not in
  ``jetnh.geometry.frobenius``;
* Cartan calculus (``d``, ``interior``, ``lie_derivative``, ``pullback``) for checking the
  identities the rest of the framework relies on.

Representation
--------------
A :class:`Form` is an immutable value: a jet space ``J``, a degree ``p`` and a sparse dict
mapping *sorted* tuples of coordinate Symbols (the basis p-form dx^{i1} ^ ... ^ dx^{ip}) to
sympy coefficients; exact zeros are dropped.  The canonical order of coordinates is: ``t``
first, then by ``(jet order, position of the base in J.q + J.fields)``, so on
``JetSpace("x y")`` it is ``t, x, y, x_t, y_t, x_tt, ...``.

Coordinates are ``t`` and every Symbol ``J.split`` recognises (coordinates, fields and
their jets of any order).  Every other Symbol is a constant parameter.  Coefficients are
never simplified on the hot paths; :meth:`Form.is_zero` decides zero-ness with
``sympy.expand`` (rational coefficients over a common denominator; see
``jetnh.algebra.zero.zero_residual``), :meth:`Form.is_zero_numeric` by evaluation at random
points.

Python precedence: ``^`` binds more loosely than ``+`` and ``*``; write ``(a ^ b) + c``.
"""

from __future__ import annotations

from functools import lru_cache
from types import MappingProxyType
from typing import Mapping

import sympy as sp

from ..algebra import dag
from ..algebra.zero import expr_is_zero
from ..errors import JetSpaceError
from .jet import JetSpace, sympy_object

__all__ = [
    "Form", "differential", "d", "wedge", "interior", "lie_derivative", "pullback",
    "contact_forms", "coordinate_key", "basis",
]


# ---------------------------------------------------------------------- ordering
class _Order:
    """Per-jet-space cache: Symbol -> canonical rank tuple (None for parameters)."""

    __slots__ = ("J", "pos", "rank")

    def __init__(self, J: JetSpace):
        self.J = J
        self.pos = {b: i for i, b in enumerate(J.q + J.fields)}
        self.rank: dict = {J.t: (0, 0, 0)}

    def key(self, sym):
        """Rank tuple of a coordinate Symbol, or None when it is a parameter."""
        try:
            return self.rank[sym]
        except KeyError:
            pass
        info = self.J.split(sym) if isinstance(sym, sp.Symbol) else None
        r = None if info is None else (1, info[1], self.pos[info[0]])
        self.rank[sym] = r
        return r

    def need(self, sym):
        r = self.key(sym)
        if r is None:
            raise JetSpaceError(
                f"{sym!r} is not a coordinate of {self.J!r} (t, q^s, fields or their jets); "
                "forms have differentials only of coordinates - other symbols are constant "
                "parameters")
        return r


@lru_cache(maxsize=128)
def _order(J: JetSpace) -> _Order:
    return _Order(J)


def coordinate_key(J: JetSpace, sym: sp.Symbol) -> tuple:
    """The canonical sort key of a coordinate Symbol: t first, then (jet order, position)."""
    return _order(J).need(sym)


def basis(J: JetSpace, syms) -> tuple[int, tuple] | None:
    """The basis p-form dsyms[0] ^ ... ^ dsyms[p-1] in the canonical order: (sign of the
    sorting permutation, sorted tuple), or None when a symbol repeats (the wedge is 0)."""
    return _canon(_order(J), syms)


def _canon(order: _Order, syms) -> tuple[int, tuple] | None:
    """(sign, sorted tuple) of the wedge of dsyms, or None when a symbol repeats."""
    syms = tuple(syms)
    ranks = [order.need(s) for s in syms]
    if len(set(syms)) != len(syms):
        return None
    # sign of the sorting permutation by counting inversions (tiny tuples)
    inv = 0
    for i in range(len(ranks)):
        ri = ranks[i]
        for j in range(i + 1, len(ranks)):
            if ranks[j] < ri:
                inv += 1
    idx = sorted(range(len(syms)), key=ranks.__getitem__)
    return (-1 if inv & 1 else 1), tuple(syms[i] for i in idx)


def _merge(ka: tuple, kb: tuple, rank: dict):
    """Merge two sorted keys: (sign, merged) of dka ^ dkb, or None when they share a symbol."""
    if not ka:
        return 1, kb
    if not kb:
        return 1, ka
    la, lb = len(ka), len(kb)
    i = j = inv = 0
    out = []
    while i < la and j < lb:
        ra, rb = rank[ka[i]], rank[kb[j]]
        if ra < rb:
            out.append(ka[i])
            i += 1
        elif rb < ra:
            out.append(kb[j])
            inv += la - i
            j += 1
        else:
            return None
    if i < la:
        out.extend(ka[i:])
    if j < lb:
        out.extend(kb[j:])
    return (-1 if inv & 1 else 1), tuple(out)


def _collect(acc: dict) -> dict:
    """{key: [terms]} -> {key: Add(*terms)} without exact zeros."""
    out = {}
    for k, lst in acc.items():
        c = lst[0] if len(lst) == 1 else sp.Add(*lst)
        if c != 0:
            out[k] = c
    return out


def _components(X) -> Mapping:
    """The component mapping of a vector field: a Mapping or an object with .components."""
    comps = getattr(X, "components", X)
    if not isinstance(comps, Mapping):
        raise TypeError(
            f"a vector field must be a mapping {{coordinate Symbol: component}} or have a "
            f"'.components' mapping; got {type(X).__name__}")
    return comps


# ---------------------------------------------------------------------- the Form value
class Form:
    """An immutable sparse differential p-form on a jet space.

    ``Form(J, p, terms)`` takes ``terms`` mapping tuples of coordinate Symbols (any order;
    the sign of the sorting permutation is applied, repeated symbols give zero) to
    coefficients.  Prefer the constructors :meth:`zero`, :meth:`function`,
    :func:`differential` and the operations ``+ - * ^``, :func:`d`, :func:`interior`,
    :func:`pullback`.

    ``form.terms`` is a read-only mapping {sorted key: coefficient}; ``form[key]`` returns
    the coefficient of any ordering of a key (with sign), 0 when absent.  ``len(form)`` is
    the number of stored terms.  ``a == b`` compares with :meth:`is_zero` of ``a - b``
    (expand-based); ``form == 0`` is ``form.is_zero()``.
    """

    __slots__ = ("_J", "_p", "_terms", "_order")

    def __init__(self, J: JetSpace, p: int, terms: Mapping | None = None):
        if not isinstance(J, JetSpace):
            raise TypeError(f"Form needs a JetSpace, got {type(J).__name__}")
        if not isinstance(p, int) or p < -1:
            raise ValueError(f"form degree must be an int >= -1 (-1 only for the zero form); got {p!r}")
        order = _order(J)
        acc: dict = {}
        for key, c in (terms or {}).items():
            if isinstance(key, sp.Symbol):
                key = (key,)
            key = tuple(key)
            if len(key) != p:
                raise ValueError(f"the key {key} has {len(key)} differentials in a {p}-form")
            can = _canon(order, key)
            if can is None:
                continue
            sign, k = can
            c = sympy_object(c)
            acc.setdefault(k, []).append(c if sign > 0 else -c)
        self._init(J, p, _collect(acc), order)

    def _init(self, J, p, terms, order):
        object.__setattr__(self, "_J", J)
        object.__setattr__(self, "_p", p)
        object.__setattr__(self, "_terms", terms)
        object.__setattr__(self, "_order", order)

    @classmethod
    def _raw(cls, J, p, terms, order=None) -> "Form":
        """Build from an already canonical {sorted key: nonzero coefficient} dict."""
        f = object.__new__(cls)
        f._init(J, p, terms, order or _order(J))
        return f

    def __setattr__(self, name, value):
        raise AttributeError("Form is immutable")

    # ------------------------------------------------------------------ constructors
    @classmethod
    def zero(cls, J: JetSpace, p: int) -> "Form":
        """The zero p-form (p = -1 is allowed: the interior product of a 0-form)."""
        if not isinstance(p, int) or p < -1:
            raise ValueError(f"form degree must be an int >= -1; got {p!r}")
        return cls._raw(J, p, {})

    @classmethod
    def function(cls, J: JetSpace, f) -> "Form":
        """The 0-form f."""
        f = sympy_object(f)
        return cls._raw(J, 0, {(): f} if f != 0 else {})

    # ------------------------------------------------------------------ accessors
    @property
    def J(self) -> JetSpace:
        """The jet space."""
        return self._J

    @property
    def degree(self) -> int:
        """The degree p."""
        return self._p

    @property
    def terms(self) -> Mapping:
        """Read-only {sorted tuple of Symbols: coefficient}."""
        return MappingProxyType(self._terms)

    def __len__(self):
        return len(self._terms)

    def __iter__(self):
        return iter(self._terms.items())

    def __getitem__(self, key):
        if isinstance(key, sp.Symbol):
            key = (key,)
        can = _canon(self._order, key)
        if can is None or len(key) != self._p:
            return sp.S.Zero
        sign, k = can
        c = self._terms.get(k, sp.S.Zero)
        return c if sign > 0 else -c

    def coordinates(self) -> set:
        """The coordinates whose differentials appear."""
        return {s for k in self._terms for s in k}

    @property
    def free_symbols(self) -> set:
        """Free symbols of the coefficients and the differentials."""
        out = self.coordinates()
        for c in self._terms.values():
            out |= c.free_symbols
        return out

    def map(self, fn) -> "Form":
        """Apply ``fn`` to every coefficient (e.g. ``sympy.simplify`` off the hot path)."""
        return Form._raw(self._J, self._p,
                         {k: v for k, c in self._terms.items() if (v := sympy_object(fn(c))) != 0},
                         self._order)

    def expand(self) -> "Form":
        """Coefficients expanded; terms that expand to zero are dropped."""
        return self.map(sp.expand)

    def subs(self, *args, **kwargs) -> "Form":
        """``sympy.subs`` on the coefficients only (the differentials are untouched).

        To change coordinates, including the differentials, use :func:`pullback`.
        """
        return self.map(lambda c: c.subs(*args, **kwargs))

    # ------------------------------------------------------------------ zero tests
    def is_zero(self) -> bool:
        """True when every coefficient is zero, decided without ``simplify``.

        ``sympy.expand`` (rational coefficients: numerator over a common denominator);
        a nonzero value at a random point proves a coefficient nonzero quickly (see
        ``jetnh.algebra.zero.zero_residual``).  Identities that need trigonometric
        simplification are not proven: use :meth:`is_zero_numeric` or
        ``form.map(sympy.simplify).is_zero()``.
        """
        return all(expr_is_zero(c) for c in self._terms.values())

    def is_zero_numeric(self, samples: int = 3, seed: int = 0, tol: float = 1e-9) -> bool:
        """True when every coefficient vanishes at ``samples`` random points (probabilistic)."""
        return all(expr_is_zero(c, numeric=True, samples=samples, seed=seed, tol=tol)
                   for c in self._terms.values())

    # ------------------------------------------------------------------ arithmetic
    def _check_same(self, other: "Form"):
        if other._J != self._J:
            raise JetSpaceError(f"forms live on different jet spaces: {self._J!r} and {other._J!r}")
        if other._p != self._p:
            raise ValueError(f"cannot add a {self._p}-form and a {other._p}-form")

    def __add__(self, other):
        if not isinstance(other, Form):
            if self._p == 0:
                other = Form.function(self._J, other)
            else:
                return NotImplemented
        self._check_same(other)
        if not other._terms:
            return self
        if not self._terms:
            return other
        acc = {k: [c] for k, c in self._terms.items()}
        for k, c in other._terms.items():
            acc.setdefault(k, []).append(c)
        return Form._raw(self._J, self._p, _collect(acc), self._order)

    __radd__ = __add__

    def __neg__(self):
        return Form._raw(self._J, self._p, {k: -c for k, c in self._terms.items()}, self._order)

    def __sub__(self, other):
        if not isinstance(other, Form):
            if self._p == 0:
                other = Form.function(self._J, other)
            else:
                return NotImplemented
        return self + (-other)

    def __rsub__(self, other):
        return (-self) + other

    def __mul__(self, other):
        if isinstance(other, Form):
            if other._p == 0 or self._p == 0:
                return wedge(self, other)
            raise TypeError("use ^ (or wedge) to multiply forms of positive degree")
        f = sympy_object(other)
        if f == 0:
            return Form.zero(self._J, self._p)
        if f == 1:
            return self
        return Form._raw(self._J, self._p,
                         {k: v for k, c in self._terms.items() if (v := f * c) != 0},
                         self._order)

    __rmul__ = __mul__

    def __truediv__(self, other):
        return self * (sp.S.One / sympy_object(other))

    def __xor__(self, other):
        if not isinstance(other, Form):
            return self * other
        return wedge(self, other)

    def __rxor__(self, other):
        return self * other

    def __eq__(self, other):
        if isinstance(other, Form):
            if other._J != self._J or other._p != self._p:
                return False
            return (self - other).is_zero()
        try:
            if sympy_object(other) == 0:
                return self.is_zero()
        except (sp.SympifyError, TypeError):
            return NotImplemented
        if self._p == 0:
            return (self - other).is_zero()
        return False

    def __ne__(self, other):
        r = self.__eq__(other)
        return r if r is NotImplemented else not r

    def __hash__(self):
        # equality is up to expansion, so only the invariants below are hashable
        return hash((self._J, self._p))

    # ------------------------------------------------------------------ printing
    def _sorted_items(self):
        o = self._order
        return sorted(self._terms.items(), key=lambda kv: [o.rank[s] for s in kv[0]])

    def __str__(self):
        if not self._terms:
            return "0"
        parts = []
        for k, c in self._sorted_items():
            basis = "^".join(f"d{s}" for s in k)
            if not k:
                parts.append(f"{c}")
            elif c == 1:
                parts.append(basis)
            elif c == -1:
                parts.append(f"-{basis}")
            else:
                parts.append(f"({c})*{basis}")
        return " + ".join(parts)

    def __repr__(self):
        return f"Form(degree={self._p}: {self})"

    def _repr_latex_(self):
        return f"${self.latex()}$"

    def latex(self) -> str:
        """LaTeX with dotted jets."""
        if not self._terms:
            return "0"
        parts = []
        for k, c in self._sorted_items():
            basis = r" \wedge ".join(f"d{self._J.latex(s)}" for s in k)
            coef = self._J.latex(c)
            parts.append(basis if (k and c == 1) else
                         f"\\left({coef}\\right) {basis}" if k else coef)
        return " + ".join(parts)


# ---------------------------------------------------------------------- operations
def differential(J: JetSpace, sym) -> Form:
    """The 1-form d(sym) of a coordinate Symbol (t, q^s, fields or their jets)."""
    if isinstance(sym, str):
        sym = sp.Symbol(sym)
    _order(J).need(sym)
    return Form._raw(J, 1, {(sym,): sp.S.One})


def wedge(a: Form, *more: Form) -> Form:
    """The exterior product a ^ b ^ ... with the signs of the canonical order."""
    out = a
    for b in more:
        out = _wedge2(out, b)
    return out


def _wedge2(a: Form, b: Form) -> Form:
    if a._J != b._J:
        raise JetSpaceError(f"forms live on different jet spaces: {a._J!r} and {b._J!r}")
    p = a._p + b._p
    if a._p < 0 or b._p < 0:
        return Form.zero(a._J, max(p, -1))
    if not a._terms or not b._terms:
        return Form.zero(a._J, p)
    rank = a._order.rank
    acc: dict = {}
    for ka, ca in a._terms.items():
        for kb, cb in b._terms.items():
            m = _merge(ka, kb, rank)
            if m is None:
                continue
            sign, k = m
            c = ca * cb
            acc.setdefault(k, []).append(c if sign > 0 else -c)
    return Form._raw(a._J, p, _collect(acc), a._order)


def d(form: Form) -> Form:
    """The exterior derivative: d(c dx^I) = sum_y (dc/dy) dy ^ dx^I over coordinates y.

    Coordinates are t and the jet coordinates/fields of ``form.J`` in the coefficients;
    every other symbol is a constant parameter.  Undefined functions such as ``f(t, x)``
    are differentiated by the chain rule through their coordinate arguments.
    """
    order = form._order
    rank = order.rank
    acc: dict = {}
    cache: dict = {}          # derivatives of shared subexpressions of the coefficients
    for key, c in form._terms.items():
        for y in dag.free_symbols(c):
            r = order.key(y)
            if r is None or y in key:
                continue
            dc = dag.diff(c, y, cache=cache)
            if dc == 0:
                continue
            # insert dy in front: sign = (-1)^(number of key elements ranked before y)
            before = 0
            for s in key:
                if rank[s] < r:
                    before += 1
                else:
                    break
            k = key[:before] + (y,) + key[before:]
            acc.setdefault(k, []).append(-dc if before & 1 else dc)
    return Form._raw(form._J, form._p + 1, _collect(acc), order)


def interior(X, form: Form) -> Form:
    """The interior product i_X form (contraction in the first slot).

    ``X`` is a mapping {coordinate Symbol: component} or any object with a ``.components``
    mapping (``jetnh.geometry.fields.VectorField``).  i_X of a 0-form is the zero form of degree -1,
    so that the antiderivation rule i_X(a ^ b) = i_X a ^ b + (-1)^p a ^ i_X b holds
    degree-wise.
    """
    comps = _components(X)
    if form._p <= 0:
        return Form.zero(form._J, -1)
    acc: dict = {}
    for key, c in form._terms.items():
        for j, s in enumerate(key):
            x = comps.get(s)
            if x is None:
                continue
            x = sympy_object(x)
            if x == 0:
                continue
            v = c * x
            acc.setdefault(key[:j] + key[j + 1:], []).append(-v if j & 1 else v)
    return Form._raw(form._J, form._p - 1, _collect(acc), form._order)


def lie_derivative(X, form: Form) -> Form:
    """L_X form by Cartan's formula i_X d form + d i_X form."""
    out = interior(X, d(form))
    if form._p > 0:
        out = out + d(interior(X, form))
    return out


def pullback(form: Form, subs: Mapping, target: JetSpace | None = None) -> Form:
    """The pullback phi^* form along the map given by ``subs`` {coordinate: expression}.

    Coordinates not in ``subs`` are left as they are (the identity on them).  Coefficients
    are substituted simultaneously (``xreplace``) and each dx^i becomes d(phi^i) computed on
    ``target`` (default: the same jet space).  Example: a prolonged curve
    ``{x: c(t), x_t: c(t).diff(t)}``.
    """
    J = form._J
    tgt = target or J
    order = _order(J)
    smap = {}
    for k, v in subs.items():
        if isinstance(k, str):
            k = sp.Symbol(k)
        order.need(k)
        smap[k] = sympy_object(v)
    dcache: dict = {}

    def dphi(s):
        try:
            return dcache[s]
        except KeyError:
            pass
        if s in smap:
            r = d(Form.function(tgt, smap[s]))
        else:
            r = differential(tgt, s)
        dcache[s] = r
        return r

    out = Form.zero(tgt, form._p)
    for key, c in form._terms.items():
        coef = c.xreplace(smap) if smap else c
        if coef == 0:
            continue
        piece = Form.function(tgt, coef)
        for s in key:
            piece = _wedge2(piece, dphi(s))
            if not piece._terms:
                break
        else:
            out = out + piece
    return out


# ---------------------------------------------------------------------- contact forms
def contact_forms(J: JetSpace, order: int = 1) -> tuple[Form, ...]:
    """Contact forms theta^s_(k) = dq^s_(k) - q^s_(k+1) dt for k = 0 .. order-1.

    ``order=1`` gives theta^s = dq^s - qdot^s dt (one per coordinate); ``order=2`` adds
    theta^s_(1) = dqdot^s - qddot^s dt, and so on.  Ordered by k, then by s.
    """
    if not isinstance(order, int) or order < 1:
        raise ValueError(f"contact form order must be an int >= 1, got {order!r}")
    out = []
    o = _order(J)
    for k in range(order):
        for b in J.q:
            qk, qk1 = J.jet(b, k), J.jet(b, k + 1)
            o.need(qk)
            out.append(Form._raw(J, 1, {(J.t,): -qk1, (qk,): sp.S.One}, o))
    return tuple(out)
