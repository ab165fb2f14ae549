"""The unknowns and endpoint conditions of the two-point problem per principle: the
start, the (partial) end, the guess of the initial unknowns, the scene the runs use."""

from __future__ import annotations

import math
from types import MappingProxyType

import numpy as np

from ...errors import JetnhError
from .. import arguments
from ...algebra import dag

#: the principles whose multipliers are unknowns of the two-point problem
VARIATIONAL = ("vakonomic", "holder")
#: ``tol`` must be below this: an end missed by more (relative to its displacement) is no
#: connection
MAX_TOL = 1e-3


#: (id(system), principle, params, t_span) -> (system, Scene): a scene's kernel keys
#: take milliseconds to compute, so repeated problems on one system reuse its scene (the
#: runs give every initial value; the scene's own are those of the first problem)
_SCENES: dict = {}


def _scene(system, principle, params, initial, t_span):
    """The scene of the runs (kept, ``_SCENES``); ``initial``: its initial values, or a
    function that makes them (called only where the scene is made)."""
    from ..scene import Scene

    try:
        key = (id(system), principle, None if params is None else tuple(sorted(
            (arguments.name_of(k, "a parameter"), float(v)) for k, v in params.items())),
            t_span)
    except (AttributeError, TypeError, ValueError, JetnhError):
        key = None                       # Scene says what is wrong with params
    hit = _SCENES.get(key)
    if hit is not None and hit[0] is system:
        return hit[1]
    scene = Scene(system, principle, params=params,
                  initial=initial() if callable(initial) else initial, t_span=t_span)
    if key is not None:
        if len(_SCENES) >= 16:
            _SCENES.clear()
        _SCENES[key] = (system, scene)
    return scene


class Unknowns:
    """The shape of a system's two-point problem under a principle: the coordinates'
    names, the unknowns (the independent velocities, then for vakonomic and Hoelder
    the multipliers but those of g = 0, which enter the equations only through their
    rates: inert, kept at 0), the multipliers kept fixed at 0, and each unknown's
    coordinate (for the straight-line guess; None for a multiplier)."""

    __slots__ = ("system", "coords", "unknowns", "fixed", "bases")

    def __init__(self, system, principle):
        from .. import codegen

        self.system = system
        self.coords = tuple(s.name for s in system.J.q)
        velocities = tuple(v.name for v in system.independent_velocities)
        mults = codegen.multiplier_names(system, principle)
        inert = {mults[a] for a in system.holonomic_rows if a < len(mults)}
        self.unknowns = velocities + (tuple(m for m in mults if m not in inert)
                                      if principle in VARIATIONAL else ())
        self.fixed = MappingProxyType({m: 0.0 for m in mults if m in inert}
                                      if principle in VARIATIONAL
                                      else {m: 0.0 for m in mults})
        self.bases = tuple(
            next((system.J.split(s)[0].name for s in system.independent_velocities
                  if s.name == v), None) for v in self.unknowns)

    @classmethod
    def of(cls, system, principle) -> "Unknowns":
        """The shape of ``system``'s problem under ``principle`` (made once, kept
        for the last 16 pairs: repeated problems on one system derive nothing)."""
        hit = _UNKNOWNS.get((id(system), principle))
        if hit is not None and hit.system is system:
            return hit
        found = cls(system, principle)
        if len(_UNKNOWNS) >= 16:
            _UNKNOWNS.clear()
        _UNKNOWNS[id(system), principle] = found
        return found


_UNKNOWNS: dict = {}


def _configuration(values, coords, what, complete) -> dict[str, float]:
    if not hasattr(values, "items"):
        raise JetnhError(f"{what} must be a dict of coordinate values keyed by Symbol or "
                         f"name, got a {type(values).__name__}")
    out = {}
    for k, v in values.items():
        # (names and plain floats, the common case, taken as they are)
        name = k if type(k) is str else arguments.name_of(k, f"a coordinate of {what}")
        if name not in coords:
            raise JetnhError(f"{what} has {name!r}, which is not a coordinate of this "
                             f"system; its coordinates are {', '.join(coords)}")
        out[name] = v if type(v) is float else arguments.real(v, f"{what}[{name!r}]")
        if not math.isfinite(out[name]):
            raise JetnhError(f"{what}[{name!r}] is {out[name]}; give a finite value")
    missing = [c for c in coords if c not in out] if complete else ()
    if missing:
        raise JetnhError(f"start must give every coordinate; missing {', '.join(missing)}")
    if not out:
        raise JetnhError(f"{what} names no coordinate; give the end configuration "
                         f"(some of {', '.join(coords)})")
    return out


def on_manifold(system, params, q0, q1, t0, t1, complete) -> dict[str, float]:
    """``q0`` checked on the holonomic constraints g = 0 (or completed onto them with
    ``complete``, as ``Scene(complete=True)``), and ``q1`` too where it names every
    coordinate; else a ``ConstraintError`` naming g and the fix.  Unchecked where a
    parameter has no value (the scene then says so)."""
    from ...errors import ConstraintError
    from ...mechanics import holonomic

    given = {**{s.name: v for s, v in system.defaults.items()},
             **{arguments.name_of(k, "a parameter"): v for k, v in (params or {}).items()}}
    numbers = {}
    for s in system.parameters:
        if s.name not in given:
            return q0
        numbers[s] = arguments.real(given[s.name], f"parameter {s.name!r}")
    J = system.J

    def point(q, t):
        return {J.t: t, **numbers, **{c: q[c.name] for c in J.q}}

    try:
        done, changed = holonomic.check(system, point(q0, t0), complete=bool(complete))
    except ConstraintError as exc:
        raise ConstraintError(f"start: {exc}" + (
            "" if complete else " (connect(..., complete=True) completes the start)")
                              ) from None
    if changed:
        q0 = {**q0, **{c.name: float(done[c]) for c in J.q}}
    if all(c.name in q1 for c in J.q):
        try:
            holonomic.check(system, point(q1, t1))
        except ConstraintError as exc:
            raise ConstraintError(
                f"end: {exc}; the motions stay on the holonomic constraints, so give an "
                "end on g = 0, or name only the independent coordinates") from None
    return q0


def _holonomic_free(system, q1, free) -> list:
    """The free coordinates whose transversality conditions close a vakonomic or
    Hoelder end on a system with holonomic constraints g = 0: none where ``q1`` names
    as many coordinates as g = 0 has dimensions (the end is then a point of it), else
    ``free`` (``Momenta`` projects their momenta onto the tangent space of g = 0); a
    ``JetnhError`` where g does not let the free coordinates follow it (``tangent_split``
    finds none)."""
    dim = system.J.n - len(system.holonomic)
    if len(q1) >= dim:
        return []
    tangent_split(system, free)
    return list(free)


def tangent_split(system, free) -> tuple[list, list]:
    """The free coordinates split as ``(dependent, rest)``: g's h dependent ones (the
    system's own dependent coordinates first, then in order), whose minor of dg/dq is
    not identically singular, so that a variation of the rest moves them along g = 0;
    else a ``JetnhError``."""
    from itertools import combinations

    from ...algebra import linalg

    J, h = system.J, len(system.holonomic)
    names = [q.name for q in J.q]
    G = dag.jacobian(system.holonomic, list(J.q))
    own = [d.name for d in system.dependent]
    ordered = sorted(free, key=lambda c: (c not in own, names.index(c)))
    for dep in combinations(ordered, h):
        if linalg.numeric_rank(G[:, [names.index(c) for c in dep]]) == h:
            return list(dep), [c for c in free if c not in dep]
    raise JetnhError(
        f"end leaves {', '.join(free)} free, but the holonomic constraints g = 0 cannot be "
        "solved for any of them (dg/dq has no regular minor in their columns), so the "
        "named coordinates already fix g; name other coordinates of end")


def _guess(guess, unknowns, fixed, bases, q0, q1, T):
    """The starting unknowns (and Suslov's fixed multipliers) from ``guess`` or the
    straight line (``bases``: each unknown's coordinate, ``Unknowns.bases``)."""
    if guess is None:
        return np.array([(q1[base] - q0[base]) / T if base in q1 else 0.0
                         for base in bases], dtype=float), fixed
    if hasattr(guess, "items"):
        u = {}
        for k, val in guess.items():
            name = arguments.name_of(k, "a guess")
            if name in fixed:
                fixed = {**fixed, name: arguments.real(val, f"guess[{name!r}]")}
                continue
            if name not in unknowns:
                raise JetnhError(f"guess has {name!r}, which is not an unknown of this "
                                 f"problem; the unknowns are {', '.join(unknowns)}")
            u[name] = arguments.real(val, f"guess[{name!r}]")
        missing = [n for n in unknowns if n not in u]
        if missing:
            raise JetnhError(f"guess lacks {', '.join(missing)}; give every unknown "
                             f"({', '.join(unknowns)}) or pass guess=None")
        vec = np.array([u[n] for n in unknowns], dtype=float)
    else:
        vec = np.asarray(guess, dtype=float) if np.ndim(guess) == 1 else None
        if vec is None or vec.shape != (len(unknowns),):
            raise JetnhError(f"guess must hold {len(unknowns)} values (the unknowns "
                             f"{', '.join(unknowns)}), got shape {np.shape(guess)}; pass a "
                             "dict by name, a sequence of that length, or None")
    if not np.all(np.isfinite(vec)):
        raise JetnhError(f"guess has a non-finite value: {vec.tolist()}")
    return vec, fixed


def transversality(system, principle, free) -> tuple:
    """The end conditions of the free coordinates ``free`` (names): the coefficient of
    eta^i in the boundary term P_s eta^s of the composite action's variation (13)
    (``mechanics.equations.action_variation`` under the principle's variation, every eta
    independent), i.e. the momentum P_i = d(L + lambda f)/dqdot^i, which must vanish at
    t1 where q^i(t1) is free; the dependent velocities replaced by phi (the state's
    functions).  Expressions in t, q, the independent velocities, the multipliers and
    the parameters."""
    from ...mechanics import equations, principles, variations

    p = principles.get(principle)
    mults = p.multiplier_symbols(system)
    variation = variations.make(system, p.variation, extra_fields=mults)
    boundary = equations.action_variation(system, variation, mults).boundary
    eta = {q.name: e for q, e in zip(system.J.q, variation.eta)}
    phi = dict(system.phi)
    return tuple(dag.xreplace(dag.diff(boundary, eta[c]), phi) for c in free)


def tangent_transversality(system, principle, free) -> tuple:
    """The transversality conditions of the free coordinates ``free`` on a system with
    holonomic constraints g = 0, and the coordinates they belong to: the boundary term
    P_s eta^s vanishes for every variation eta tangent to g = 0 (G eta = 0, G = dg/dq)
    that leaves the named coordinates fixed.  With ``free`` split into g's dependent
    coordinates D and the rest R (``tangent_split``), eta_D = -G_D^-1 G_R eta_R, so the
    conditions are the reduced momenta P_R - G_R^T G_D^-T P_D = 0 (the multipliers of g,
    which weigh G, drop out).  Returns ``(conditions, R)``."""
    from ...algebra import linalg
    import sympy as sp

    dep, rest = tangent_split(system, free)
    P = dict(zip(dep + rest, transversality(system, principle, dep + rest)))
    names = [q.name for q in system.J.q]
    G = dag.jacobian(system.holonomic, list(system.J.q))
    mu = linalg.solve(G[:, [names.index(c) for c in dep]].T,
                      sp.Matrix([P[c] for c in dep]))
    return tuple(P[c] - sum((G[a, names.index(c)] * mu[a] for a in range(len(dep))),
                            sp.S.Zero) for c in rest), rest


class Momenta:
    """The transversality conditions (``transversality``; on a system with holonomic
    constraints, ``tangent_transversality``) of a scene as numbers: their values at a
    state and their derivatives by the state (from the graph).  ``free``: the
    coordinates they belong to.  The conditions and their derivatives are derived once
    per system, principle and free coordinates (``_derived``); their straight-line
    evaluation is prepared once per Momenta (``straight_line``), the graph walked
    (``walk``) only where it cannot be (a head without a float function) or where a
    float operation raises (a division by zero, a logarithm of a negative number:
    numpy's inf or nan then, as before)."""

    def __init__(self, scene, free):
        system = scene.system
        self.states, self.free, self.exprs, self.jacobian = _derived(
            system, scene.principle, tuple(free), scene.state_names)
        self._all = [*self.exprs, *self.jacobian]
        self.t = system.J.t
        self.params = {s: scene.params[s.name] for s in system.parameters}
        self._shape = (len(self.exprs), len(self.states))
        self._line = straight_line(self._all, self.t, self.states, self.params)
        self._scene = scene

    def scale(self, q0, q1, t0, T) -> np.ndarray:
        """Each transversality condition's scale, free of the units of the coordinates
        and of L: the momentum of the problem's own motion in the free coordinate's
        units, ``sqrt(D_ii) |v|_H`` -- H = d^2 L / dqdot^2 at the start (``verdicts``'
        kinetic Hessian), D its diagonal scale (``verdicts.unit_diagonal``), v the
        straight line's velocities (the named coordinates' displacements over T, 0 for
        the others), |v|_H = sqrt(|v^T H v|).  A change of a coordinate's unit q -> a q
        scales P_i and sqrt(D_ii) alike by 1 / a, and of L's by k both by k.  1 (as
        before) where L has no velocity term in a free coordinate, or where nothing
        moves: no scale of the problem's own."""
        from .verdicts import _diagonal_scale, _hessian

        scene = self._scene
        system = scene.system
        J = system.J
        _, v, H = _hessian(scene, multipliers=False)
        n = len(v)
        speed = {qd: (q1[q.name] - q0[q.name]) / T if q.name in q1 else 0.0
                 for q, qd in zip(J.q, J.qd)}
        point = {J.t: t0, **self.params, **{q: q0[q.name] for q in J.q}, **speed}
        try:
            with np.errstate(all="ignore"):
                Hm = np.array([float(h) for h in dag.evaluate_numpy(H, point)]).reshape(n, n)
        except (TypeError, ValueError, KeyError):
            return np.ones(len(self.free))
        Hm = 0.5 * (Hm + Hm.T)
        vel = np.array([speed[qd] for qd in J.qd])
        energy = math.sqrt(abs(float(vel @ Hm @ vel)))
        rows = np.abs(Hm).max(axis=1)
        names = [q.name for q in J.q]
        if not (math.isfinite(energy) and energy > 0 and np.all(np.isfinite(Hm))):
            return np.ones(len(self.free))
        D = _diagonal_scale(Hm)
        return np.array([math.sqrt(D[names.index(c)]) * energy
                         if rows[names.index(c)] > 0 else 1.0 for c in self.free])

    def __call__(self, t, y):
        """``(P_free(t, y), dP_free/dy)``."""
        line = self._line
        if line is not None:
            try:
                vals = np.array(line(float(t), y.tolist() if type(y) is np.ndarray
                                     else [float(v) for v in y]))
            except (ArithmeticError, ValueError):
                return self.walk(t, y)
            k, n = self._shape
            return vals[:k], vals[k:].reshape(k, n)
        return self.walk(t, y)

    def walk(self, t, y):
        """``__call__`` by a walk over the graph (``dag.evaluate_numpy``), numpy's
        float rules (inf and nan where Python's raise)."""
        point = {self.t: float(t), **self.params,
                 **{s: float(v) for s, v in zip(self.states, y)}}
        k, n = self._shape
        vals = dag.evaluate_numpy(self._all, point)
        values = np.array([float(v) for v in vals[:k]])
        G = np.array([float(v) for v in vals[k:]]).reshape(k, n)
        return values, G


#: the math module's functions a straight line calls by name (``straight_line``),
#: matched by sympy's own classes (a user's undefined function named "sin" is not sin)
_LINE_MATH = ("sin", "cos", "tan", "asin", "acos", "atan", "atan2", "sinh", "cosh", "tanh",
              "asinh", "acosh", "atanh", "exp", "log", "sqrt")


def straight_line(exprs, t, states, params):
    """``f(t, y) -> [values of exprs]``: the shared graph of ``exprs`` as straight-line
    Python on floats, each distinct node one assignment in dependency order (the order
    and operations of ``dag.evaluate_numpy``: sums and products left to right), with
    ``t`` the time, ``states`` the symbols of ``y``'s entries and ``params`` (Symbol ->
    value) fixed; None where a node has no float counterpart (a symbol without a value,
    a complex or infinite number, a head outside ``_LINE_MATH``).  The source is built
    from the graph's structure alone -- indices, operators, float literals and those
    function names, never a name or string from the model -- and compiled once."""
    import sympy as sp

    funcs = {getattr(sp, f): f for f in _LINE_MATH}
    index = {s: i for i, s in enumerate(states)}
    names: dict = {}
    lines = []
    for e in dag.nodes(list(exprs)):
        if id(e) in names:
            continue
        if e in index:
            text = f"y[{index[e]}]"
        elif e == t:
            text = "t"
        elif e in params or e.is_Number or e.is_NumberSymbol:
            value = float(params[e]) if e in params else None
            if value is None:
                if not (e.is_real and e.is_finite):
                    return None
                value = float(e)
            if not math.isfinite(value):
                return None
            text = repr(value)
        elif e.is_Add or e.is_Mul:
            text = (" + " if e.is_Add else " * ").join(names[id(a)] for a in e.args)
        elif e.is_Pow:
            base, exp = e.args
            text = (f"{names[id(base)]} ** {int(exp)}" if exp.is_Integer
                    else f"_pow({names[id(base)]}, {names[id(exp)]})")
        elif isinstance(e, sp.Abs):
            text = f"abs({names[id(e.args[0])]})"
        elif type(e) in funcs:
            text = f"_m.{funcs[type(e)]}({', '.join(names[id(a)] for a in e.args)})"
        else:
            return None
        names[id(e)] = f"v{len(lines)}"
        lines.append(f"    v{len(lines)} = {text}")
    body = "\n".join(lines) or "    pass"
    out = ", ".join(names[id(e)] for e in exprs)
    source = f"def line(t, y):\n{body}\n    return [{out}]\n"
    scope = {"_m": math, "_pow": math.pow}
    exec(compile(source, "<jetnh straight line>", "exec"), scope)
    return scope["line"]


#: (id(system), principle, free, state names) -> (system, what ``_derived`` returns):
#: the derivation takes milliseconds, so repeated free-end problems on one system
#: derive nothing
_MOMENTA: dict = {}


def _derived(system, principle, free, names) -> tuple:
    """``(states, free, conditions, their derivatives by the states)`` of the
    transversality conditions of ``free`` (a tuple of names) under ``principle``, in the
    state of the scenes with ``names``: tuples, made once (for the last 16 keys) and
    shared by every ``Momenta`` of the system."""
    key = (id(system), principle, free, names)
    hit = _MOMENTA.get(key)
    if hit is not None and hit[0] is system:
        return hit[1]
    if system.holonomic:
        exprs, free = tangent_transversality(system, principle, list(free))
    else:
        exprs = transversality(system, principle, list(free))
    by_name = {s.name: s for s in (*system.J.q, *system.independent_velocities)}
    from ...mechanics import principles
    by_name.update({s.name: s for s in
                    principles.get(principle).multiplier_symbols(system)})
    states = tuple(by_name[n] for n in names)
    exprs = tuple(exprs)
    found = (states, tuple(free), exprs, tuple(dag.jacobian(list(exprs), list(states))))
    if len(_MOMENTA) >= 16:
        _MOMENTA.clear()
    _MOMENTA[key] = (system, found)
    return found
