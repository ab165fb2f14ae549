"""User events: zero crossings of functions of the state, located on the dense output.

Example::

    traj = scene.run(events=[y - 1, Event(x_t, terminal=True, direction=-1, name="turn")])
    traj.t_events[0], traj.y_events[0]          # as scipy's solve_ivp
    traj.events["turn"]                          # {"t": ..., "x": ..., "x_t": ..., ...}

An event is

- a sympy expression in t, the coordinates, the velocities (dependent ones follow from
  the constraints), the multipliers of the scene's principle and the parameters: it is
  compiled with the scene's kernels (``codegen.generate_events``; cached on disk);
- a callable ``g(t, y) -> float`` on the state vector ``y`` (ordered as
  ``scene.state_names``), as for scipy; it is compiled by numba (``numba.njit``), so it
  must be numba-compilable (numpy and math only); it is compiled once per process;
- an ``Event(expr_or_callable, terminal=..., direction=..., name=...)``.

Semantics are scipy's (``solve_ivp(events=...)``): ``direction`` > 0 triggers only on
crossings from negative to positive, < 0 only from positive to negative, 0 on both;
``terminal`` True (or a positive integer m) stops the integration at the first (m-th)
occurrence, at the located time; callables may carry ``terminal`` and ``direction`` as
attributes. One difference: a root exactly on a step's node (an event ``t - 1`` with
fixed steps h = 0.01) ends one step and starts the next; scipy counts it in both, jetnh
once (a zero at the start of a step other than the run's first is the root the previous
step ended on), so ``terminal=2`` stops at the second root, not at that one twice (the
``scipy-*`` methods too). Roots are found by Brent's method (scipy's
``brentq``, xtol = rtol = 4 eps) on the dense output of DOP853 / DOPRI5 / radau (the
cubic Hermite interpolant for RK4), inside the compiled loop (``methods._events``). dla
and dvi evaluate the events at every node as they go and end the run at the node after a
terminal one; the roots are then located on the linear interpolant between the nodes
(``discrete.node_events``).

An expression that depends on neither t nor the state is refused (constant along a run,
it never crosses zero); an event that is NaN or infinite at the initial state gets a
``JetnhWarning`` (it does not fire where it is not finite).  A function that stays
exactly zero over an interval is one root, at its first zero (by the rule above).

Resolution limit (as scipy's): an event is seen where its function changes sign between
the ends of an accepted step; an even number of crossings inside one step (an event on
``sin(1000 t)`` with steps longer than its half period pi/1000) cancels out and is not
reported.  The steps follow the motion, not the events: for an event that oscillates
faster than the motion, pass ``max_step`` below the spacing of its roots.
"""

from __future__ import annotations

import math
import warnings

import numpy as np
import sympy as sp

from ..errors import JetnhError, JetnhWarning
from ..frozen import Frozen
from . import codegen
from .kernels import load as load_kernels


class Event(Frozen):
    """One event function with scipy's options: see the module docstring.  Immutable."""

    def __init__(self, fun, terminal=False, direction=0, name=None):
        if isinstance(fun, Event):
            fun = fun.fun
        if isinstance(fun, str):
            raise JetnhError(
                f"event {fun!r} is a string; give a sympy expression (strings are not "
                "evaluated) or a callable g(t, y)")
        if not callable(fun) or isinstance(fun, sp.Basic):
            if isinstance(fun, sp.core.relational.Relational):
                raise JetnhError(
                    f"event {fun} is a relation; an event is an expression whose zero "
                    f"crossings are the events: write {fun.lhs - fun.rhs} instead")
            try:
                fun = sp.sympify(fun, strict=True)
            except (sp.SympifyError, TypeError):
                raise JetnhError(f"an event must be a sympy expression or a callable "
                                 f"g(t, y), not {type(fun).__name__}") from None
        self.fun = fun
        if isinstance(terminal, (bool, np.bool_)):
            self.max_events = 1 if terminal else 0
        elif isinstance(terminal, (int, np.integer)) and terminal >= 0:
            self.max_events = int(terminal)
        else:
            raise JetnhError(f"terminal must be a bool or a positive integer (stop at that "
                             f"occurrence), not {terminal!r}")
        try:
            d = float(direction)
        except (TypeError, ValueError):
            raise JetnhError(f"direction must be a number (-1, 0 or 1), not "
                             f"{direction!r}") from None
        self.direction = int(np.sign(d))
        self.terminal = terminal
        if name is None:
            name = sp.sstr(fun) if self.is_expression else getattr(fun, "__name__", "event")
        self.name = str(name)

    @property
    def is_expression(self) -> bool:
        return isinstance(self.fun, sp.Basic)

    def __repr__(self):
        return (f"Event({self.name}, terminal={self.terminal!r}, "
                f"direction={self.direction})")


class OwnEvent(Event):
    """An event a run watches for itself, not one of the user's (the edge of a split's
    chart, ``numeric.atlas``): ``warn_not_finite`` does not look at it."""


def as_events(events) -> list[Event]:
    """A list of ``Event`` from what ``run(events=...)`` accepts (one item or a list)."""
    if events is None:
        return []
    if isinstance(events, (Event, sp.Basic, str)) or callable(events):
        events = [events]
    out = []
    for e in events:
        if isinstance(e, Event):
            out.append(e)
        elif callable(e) and not isinstance(e, sp.Basic):
            out.append(Event(e, terminal=getattr(e, "terminal", False) or False,
                             direction=getattr(e, "direction", 0)))
        else:
            out.append(Event(e))
    names = [e.name for e in out]
    for i, nm in enumerate(names):
        if nm in names[:i]:
            e = out[i]              # renamed in a copy: the caller's Event stays as given
            out[i] = Event(e.fun, e.terminal, e.direction, name=f"{nm}#{i}")
    return out


class CompiledEvents:
    """The compiled event function of one list of events (all of them in one kernel)."""

    def __init__(self, events, uev, python_funcs, sizes):
        self.events = events
        from .methods._common import FunctionAddress

        self.uev = FunctionAddress(uev)         # cfunc (t, y, p, out), by address
        self.names = tuple(e.name for e in events)
        self.direction = np.array([e.direction for e in events], dtype=np.int64)
        self.max_events = np.array([e.max_events for e in events], dtype=np.int64)
        self.python_funcs = python_funcs        # per event: f(t, y, p) -> float (scipy)
        self.sizes = sizes                      # (states, run-time parameters, events)
        self.user = tuple(i for i, e in enumerate(events) if not isinstance(e, OwnEvent))
        self._kernel = None

    def __len__(self):
        return len(self.events)

    def values(self, t, y, p) -> list[float]:
        """Every event's value at (t, y) with the parameters p, in one call of ``uev``
        (``y`` and ``p`` C-contiguous float64 arrays of at least ``sizes`` entries)."""
        if self._kernel is None:
            from .kernels.calls import Kernel

            self._kernel = Kernel(self.uev, self.sizes)
        out = np.empty(len(self.events))
        self._kernel(float(t), y, p, out)
        return out.tolist()


def _check_symbols(scene, expr, name):
    J = scene.system.J
    known = ({J.t.name} | {s.name for s in J.q + J.qd} | set(scene.multipliers)
             | set(scene.params))
    bad = sorted(s.name for s in expr.free_symbols if s.name not in known)
    if bad:
        raise JetnhError(
            f"event {name!r} contains {', '.join(bad)}, which are not states, velocities, "
            f"multipliers or parameters of this {scene.principle} scene; it may use t, "
            f"{', '.join(s.name for s in J.q + J.qd)}"
            + (f", {', '.join(scene.multipliers)}" if scene.multipliers else "")
            + (f" and the parameters {', '.join(sorted(scene.params))}" if scene.params else ""))


def check_varying(scene, events):
    """Refuse a user's event expression free of t and of the state (``run(events=...)``):
    constant along a run, it never changes sign (identically zero, it would be a root at
    every node)."""
    J = scene.system.J
    moving = {J.t.name} | {s.name for s in J.q + J.qd} | set(scene.multipliers)
    for e in as_events(events):
        if not e.is_expression:
            continue
        expr, name = J.from_dynamic(e.fun), e.name
        if any(s.name in moving for s in expr.free_symbols):
            continue
        raise JetnhError(
            f"event {name!r} is {expr}, which depends on neither t nor the state: it is "
            "constant along a run and never crosses zero (identically zero, it would be a "
            "root everywhere); give an expression in t, the coordinates, the velocities or "
            "the multipliers")


def warn_not_finite(ce, t, y, p):
    """A ``JetnhWarning`` for every user's event of ``ce`` that is NaN or infinite at the
    start (t, y) of a run with the parameters p: such a function has no sign there, and
    an event whose value is never finite never fires."""
    if not ce.user:
        return
    values = ce.values(t, y, p)
    if all(map(math.isfinite, values)):
        return
    bad = [ce.names[i] for i in ce.user if not math.isfinite(values[i])]
    if bad:
        warnings.warn(f"the events {', '.join(map(repr, bad))} are NaN or infinite at the "
                      f"initial state (t = {t:.17g}): they do not fire where they are not "
                      "finite", JetnhWarning, stacklevel=3)


def compile_events(scene, events: list[Event]) -> CompiledEvents:
    """One kernel computing every event of ``events`` (expressions compiled with the
    scene's conventions and cached on disk; callables compiled by numba)."""
    import numba

    from .methods._common import RHS_SIGNATURE

    J = scene.system.J
    exprs = [(i, J.from_dynamic(e.fun)) for i, e in enumerate(events) if e.is_expression]
    calls = [(i, e.fun) for i, e in enumerate(events) if not e.is_expression]
    for i, expr in exprs:
        _check_symbols(scene, expr, events[i].name)
    kernel = None
    if exprs:
        spec = scene.spec.but(variant="events", events=tuple(exprs))
        layout = scene.kernels.layout
        kernel = load_kernels(spec.key, lambda: codegen.generate_events(spec, layout),
                              persistent=scene.cache)
    jitted = []
    for i, f in calls:
        try:
            g = f if isinstance(f, numba.core.dispatcher.Dispatcher) else numba.njit(f)
        except Exception as exc:  # numba raises many kinds
            raise JetnhError(f"event {events[i].name!r} cannot be compiled by numba "
                             f"({exc}); write it with math/numpy only, or give a sympy "
                             "expression") from None
        jitted.append((i, g))
    if kernel is not None and not jitted:
        uev = kernel.events_c
    else:
        # our own text: a function that calls the compiled pieces (no user text in it)
        lines = ["def ev(t, y, p, out):"]
        glb = {}
        if kernel is not None:
            glb["E"] = kernel.events
            lines.append("    E(t, y, p, out)")
        for j, (i, g) in enumerate(jitted):
            glb[f"f{j}"] = g
            lines.append(f"    out[{i}] = f{j}(t, y)")
        exec("\n".join(lines), glb)  # noqa: S102 - generated source, see above
        try:
            uev = numba.cfunc(RHS_SIGNATURE, error_model="numpy")(glb["ev"])
        except Exception as exc:
            names = ", ".join(repr(events[i].name) for i, _ in jitted)
            raise JetnhError(
                f"the event callables {names} cannot be compiled by numba as g(t, y) -> "
                f"float with y a float64 array: {str(exc).splitlines()[0]}. Write them "
                "with math/numpy only, or give sympy expressions") from None
    python_funcs = []
    for i, e in enumerate(events):
        if e.is_expression:
            python_funcs.append(_expr_caller(kernel.events, i, len(events)))
        else:
            python_funcs.append(lambda t, y, p, f=e.fun: float(f(t, y)))
    return CompiledEvents(events, uev, python_funcs,
                          (len(scene.state_names), len(scene.runtime_params), len(events)))


def _expr_caller(kernel, i, n):
    out = np.zeros(n)

    def f(t, y, p):
        kernel(float(t), np.ascontiguousarray(y, dtype=float), p, out)
        return float(out[i])
    return f


def split_records(n_events, ev_t, ev_i, ev_y):
    """Per event: the times (array) and states (rows) of its occurrences, in order."""
    t_events, y_events = [], []
    for k in range(n_events):
        mask = ev_i == k
        t_events.append(np.ascontiguousarray(ev_t[mask]))
        y_events.append(np.ascontiguousarray(ev_y[mask]))
    return t_events, y_events
