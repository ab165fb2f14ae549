"""Scenes: a system, a principle, numbers, and a time span, ready to integrate::

    scene = Scene(system, "chetaev", params={R: 1.0}, initial={x: 0.0, phi_t: 1.0, ...},
                  t_span=(0.0, 10.0))
    traj = scene.run(rtol=1e-10, atol=1e-12)            # compiled DOP853
    traj = scene.run(method="dopri5")                   # compiled Dormand-Prince 5(4)
    traj = scene.run(method="rk4", n_steps=1000)        # compiled fixed-step RK4
    traj = scene.run(method="dla", h=0.01)              # discrete Lagrange-d'Alembert
    traj = scene.run(method="dla", h=0.01, projection=True)   # nodes on the constraints
    traj = scene.run(method="dvi", h=0.01)              # discrete vakonomic (variational)
    traj = scene.run(method="scipy-DOP853")             # scipy's solve_ivp, same kernels
    traj = scene.run(events=[y - 1, Event(x_t, terminal=True)])   # user events
    ens = scene.ensemble(initial={"phi_t": array}, params={"R": array}, save="final")

Every run stops at a singular configuration (``singular="stop"``, the default) with
``status`` SINGULAR and a ``stop_reason`` naming the indicator and the time; see
``run``.

A scene does only what it needs: it derives the equations of its own principle, and only
when its kernels are not in the disk cache; parameters are numbers substituted before
code generation (``runtime_params`` keeps some as run-time inputs for ensembles); output
is every step, the points of ``t_eval``, or only the end (``save="final"``).

State: every coordinate q^s, the independent velocities qdot^mu and the multipliers of
the principles that have them (vakonomic, Hoelder, Suslov).  Initial values are keyed by
Symbol or by name; the dependent velocities follow from the constraints.  If given, they
must agree with the constraints (else ``ConstraintError``), or ``project=True`` replaces
them by the values the constraints require.
"""

from __future__ import annotations

import time
from collections.abc import Mapping
from functools import cached_property

import numpy as np
import sympy as sp

from ..constraints import PRINCIPLES, System
from ..errors import ConstraintError, IntegrationError, JetnhError, PrincipleError
from ..jet import sympy_object
from . import arguments, interrupt
from . import cache as _cache
from . import codegen
from .integrators import ADAPTIVE, METHODS, STATUS_TEXT
from .integrators._common import (AT_T_EVAL, ENDPOINTS, EVENT, EVERY_STEP, NONFINITE,
                                  NOT_CONVERGED, SINGULAR, STOPPED)
from .trajectory import Trajectory

SCIPY_METHODS = ("RK45", "RK23", "DOP853", "Radau", "BDF", "LSODA")
DLA_NAMES = ("dla", "lda", "nh-midpoint")
DVI_NAMES = ("dvi", "vakonomic-midpoint")


def _timeout_reason(timeout, t) -> str:
    if timeout is None:
        return STATUS_TEXT[STOPPED]
    return (f"stopped at t = {float(t):.17g} by the wall-clock budget timeout = {timeout:g} s; "
            "raise timeout (or max_steps) to go further")


class Scene:
    """``Scene(system, principle, params, initial, t_span)``: see the module docstring.

    ``params`` default to ``system.defaults`` (the catalogue models carry them).
    Options: ``form``/``convention`` are passed to ``system.equations``; ``integrals``
    maps names to sympy expressions (first integrals to monitor); ``runtime_params``
    names parameters read at run time instead of compiled in; ``project`` replaces
    inconsistent dependent velocities; ``consistency_tol`` is the relative tolerance of
    that check; ``cache=False`` keeps compiled kernels out of the disk cache.
    """

    def __init__(self, system: System, principle: str = "chetaev", params=None, initial=None,
                 t_span=(0.0, 1.0), *, form=None, convention="paper", integrals=None,
                 runtime_params=(), project=False, consistency_tol=1e-9, cache=True):
        if not isinstance(system, System):
            raise JetnhError(f"a Scene needs a jetnh System, got {type(system).__name__}")
        if principle not in PRINCIPLES:
            raise PrincipleError(f"unknown principle {principle!r}; choose one of {PRINCIPLES}")
        self.system = system
        self.principle = principle
        self.form = form
        self.convention = convention
        self.cache = cache
        for what, value in (("params", params), ("initial", initial),
                            ("integrals", integrals)):
            if not isinstance(value, (Mapping, type(None))):
                raise JetnhError(f"{what} must be a dict keyed by Symbol or name, got a "
                                 f"{type(value).__name__}")
        self.integrals = {str(k): sympy_object(v) for k, v in (integrals or {}).items()}
        self.t_span = self._t_span(t_span)
        self.multipliers = codegen.multiplier_names(system, principle)
        self.params = self._params(params or {})
        if isinstance(runtime_params, (str, sp.Symbol)):
            runtime_params = (runtime_params,)
        self.runtime_params = tuple(arguments.name_of(k, "a runtime parameter")
                                    for k in runtime_params)
        for name in self.runtime_params:
            if name not in self.params:
                raise JetnhError(f"runtime parameter {name!r} needs a value in params=")
        J = system.J
        self.coordinates = tuple(s.name for s in J.q)
        self.velocities = tuple(v.name for v in system.independent_velocities)
        self.dependent_velocities = tuple(v.name for v in system.dependent_velocities)
        self.state_names = self.coordinates + self.velocities + self.multipliers
        self.consistency_tol = arguments.positive(consistency_tol, "consistency_tol")
        self.projected: dict[str, tuple[float, float]] = {}
        self.initial = self._initial(initial or {}, project)
        self.y0 = np.array([self.initial[n] for n in self.state_names], dtype=float)

    # ------------------------------------------------------------------ input checks
    @staticmethod
    def _t_span(t_span):
        try:
            t0, t1 = t_span
        except (TypeError, ValueError):
            raise JetnhError(f"t_span must be a pair (t0, t1), got {t_span!r}") from None
        t0, t1 = arguments.real(t0, "t_span[0]"), arguments.real(t1, "t_span[1]")
        if not (np.isfinite(t0) and np.isfinite(t1)):
            raise JetnhError(f"t_span must be finite, got {t_span!r}")
        return (t0, t1)

    def _params(self, params) -> dict[str, float]:
        needed = {s.name for s in self.system.parameters}
        J = self.system.J
        known = {s.name for s in J.q + J.qd} | {J.t.name} | set(self.multipliers)
        for expr in self.integrals.values():
            needed |= {s.name for s in expr.free_symbols if s.name not in known}
        out = {}
        given = {**{s.name: v for s, v in self.system.defaults.items()}, **dict(params)}
        for k, v in given.items():
            name = arguments.name_of(k, "a parameter")
            if name not in needed:
                raise JetnhError(
                    f"params has {name!r}, which is not a parameter of this system; its "
                    f"parameters are {sorted(needed) or 'none'}")
            out[name] = arguments.real(v, f"parameter {name!r}")
            if not np.isfinite(out[name]):
                raise JetnhError(f"parameter {name!r} is {out[name]}; give a finite value")
        missing = sorted(needed - set(out))
        if missing:
            raise JetnhError(f"missing parameter values: {', '.join(missing)}; give them in "
                             "params={...} (or as the system's defaults)")
        return out

    def _initial(self, initial, project) -> dict[str, float]:
        given = {}
        allowed = set(self.state_names) | set(self.dependent_velocities)
        for k, v in initial.items():
            name = arguments.name_of(k, "an initial value")
            if name not in allowed:
                raise JetnhError(
                    f"initial has {name!r}, which is not a state of this {self.principle} "
                    f"scene; the states are {', '.join(self.state_names)} (and the dependent "
                    f"velocities {', '.join(self.dependent_velocities) or 'none'})")
            given[name] = arguments.real(v, f"initial value of {name!r}")
            if not np.isfinite(given[name]):
                raise JetnhError(f"initial value of {name!r} is {given[name]}")
        missing = [n for n in self.state_names if n not in given]
        if missing:
            raise JetnhError(
                f"missing initial values: {', '.join(missing)}"
                + ("" if not self.multipliers else
                   f" (the {self.principle} state includes the multipliers "
                   f"{', '.join(self.multipliers)})")
                + "; give them in initial={...}")
        required = self._dependent_velocity_values(given)
        bad = []
        for name, value in required.items():
            if not np.isfinite(value):
                raise ConstraintError(
                    f"the constraints give no finite value for {name} at the initial state "
                    f"({value}): the initial configuration is singular for the split "
                    f"{[s.name for s in self.system.dependent]}")
            if name in given:
                g = given[name]
                if abs(g - value) > self.consistency_tol * max(1.0, abs(value)):
                    bad.append((name, g, value))
        if bad:
            listing = "; ".join(f"{n} = {g!r} but the constraints give {v!r}"
                                for n, g, v in bad)
            if not project:
                raise ConstraintError(
                    f"initial dependent velocities inconsistent with the constraints: "
                    f"{listing}. Omit them (they follow from the constraints) or pass "
                    "project=True to replace them")
            self.projected = {n: (g, v) for n, g, v in bad}
        out = dict(given)
        out.update(required)
        return out

    def _dependent_velocity_values(self, given, t0=None, params=None) -> dict[str, float]:
        """qdot^alpha = phi^alpha at the initial state (or at ``t0`` with ``params``
        overriding the scene's), by sympy with numbers (small)."""
        sys_ = self.system
        if not sys_.k:
            return {}
        J = sys_.J
        sub = {J.t: sp.Float(self.t_span[0] if t0 is None else t0)}
        by_name = {s.name: s for s in J.q + J.qd}
        for name, v in given.items():
            if name in by_name:
                sub[by_name[name]] = sp.Float(v)
        values = {**self.params, **(params or {})}
        for s in sys_.parameters:
            sub[s] = sp.Float(values[s.name])
        out = {}
        for v in sys_.dependent_velocities:
            val = sys_.phi[v].xreplace(sub)
            try:
                out[v.name] = float(sp.N(val, 17))
            except TypeError:
                out[v.name] = float("nan")
        return out

    # ------------------------------------------------------------------ kernels
    @cached_property
    def key(self) -> str:
        compiled_params = {k: v for k, v in self.params.items()
                           if k not in self.runtime_params}
        return codegen.symbolic_key(self.system, self.principle, compiled_params,
                                    self.runtime_params, self.integrals, self.form,
                                    self.convention)

    @property
    def kernels(self):
        """The compiled kernels (from memory, the disk cache, or generated now)."""
        compiled_params = {k: v for k, v in self.params.items()
                           if k not in self.runtime_params}
        return _cache.load(self.key, lambda: codegen.generate(
            self.system, self.principle, compiled_params, self.runtime_params,
            self.integrals, self.form, self.convention, key=self.key), persistent=self.cache)

    def replace(self, **changes) -> "Scene":
        """A scene equal to this one except for ``changes`` (constructor arguments:
        params, initial, t_span, runtime_params, integrals, ...).  The initial values
        are the states' (dependent velocities follow from the constraints again)."""
        args = dict(system=self.system, principle=self.principle, params=self.params,
                    initial={n: self.initial[n] for n in self.state_names},
                    t_span=self.t_span, form=self.form, convention=self.convention,
                    integrals=self.integrals, runtime_params=self.runtime_params,
                    consistency_tol=self.consistency_tol, cache=self.cache)
        unknown = set(changes) - set(args) - {"project"}
        if unknown:
            raise JetnhError(f"Scene.replace: unknown arguments {sorted(unknown)}")
        args.update(changes)
        system = args.pop("system")
        principle = args.pop("principle")
        return Scene(system, principle, **args)

    def ensemble(self, initial=None, params=None, **options):
        """Many runs in one call: ``jetnh.numeric.ensemble.run_ensemble(self, initial,
        params, **options)`` (arrays [n_runs, n_times, n_states] and per-run
        diagnostics; parallel over the cores)."""
        from .ensemble import run_ensemble

        return run_ensemble(self, initial, params, **options)

    def compile(self) -> "Scene":
        """Build (or load) the kernels now rather than at the first run."""
        self.kernels
        return self

    @property
    def p(self) -> np.ndarray:
        return np.array([self.params[n] for n in self.runtime_params], dtype=float)

    # ------------------------------------------------------------------ run
    def run(self, rtol=1e-9, atol=1e-12, t_eval=None, method="dop853", *, backend=None,
            save="steps", first_step=None, max_step=None, max_steps=10_000_000,
            n_steps=None, h=None, t_span=None, y0=None, params=None, newton_tol=None,
            max_newton=None, events=None, singular="stop", singular_tol=1e-10,
            projection=False, timeout=None) -> Trajectory:
        """Integrate and return a ``Trajectory``.

        ``method``: "dop853" (default), "dopri5" (alias "RK45"), "rk4" (fixed step: give
        ``n_steps`` or ``h``), "dla" (the structure-preserving discrete
        Lagrange-d'Alembert midpoint integrator, Chetaev only, fixed step, Newton tolerance
        ``newton_tol`` (1e-13) in at most ``max_newton`` (50) iterations;
        ``projection=True`` projects every node velocity onto the constraints), "dvi" (the
        discrete vakonomic midpoint variational integrator, vakonomic dynamics, fixed
        step), or "scipy-<M>" for scipy's ``solve_ivp(method=M)`` on the same compiled
        right-hand side (also ``backend="scipy"``).  ``t_eval``: output times (dense
        output); else every accepted step, or the two ends with ``save="final"``.
        ``atol`` may be a scalar or one value per state; adaptive steps are bounded by
        ``first_step`` (default automatic) and ``max_step`` (default none).

        ``y0`` replaces the initial state: a dict keyed by Symbol or name (the other
        states keep the scene's values; dependent velocities, if given, must agree with
        the constraints) or a sequence in the order ``scene.state_names``.  ``params``
        gives the run-time parameters (``runtime_params``): a dict, or a sequence in the
        order ``scene.runtime_params``.  Every argument is checked before it reaches
        compiled code (``numeric.arguments``).

        Budgets: at most ``max_steps`` steps (the fixed-step methods refuse more up
        front); ``timeout`` seconds of wall-clock time, after which the run returns what
        it has with status ``STOPPED``.  Ctrl-C stops a compiled run within one step
        (``numeric.interrupt``).

        ``events``: user events (sympy expressions, callables g(t, y) or ``Event``; see
        ``jetnh.numeric.events``), located on the dense output with scipy's semantics;
        the trajectory reports ``t_events``, ``y_events`` and ``events``.

        ``singular="stop"`` (default) stops at a singular configuration: where a
        singularity indicator of the scene (``kernels.layout.indicators``: the
        determinant of df/dqdot^alpha, denominators and square-root arguments of phi and
        of the accelerations) crosses zero or falls below ``singular_tol`` times its
        initial size; the point is located on the dense output, ``status`` is
        ``SINGULAR`` and ``stop_reason`` names the indicator, the time and the way out.
        ``singular="ignore"`` skips the check.  NaN or infinity that no indicator
        explains stops with an ``IntegrationError`` naming the time and the state.  dla
        and dvi check the indicators of the constraints and the Lagrangian as written
        (``codegen.discrete_indicators``; never the split) at every node and stop at the
        last regular one; a failed step next to a vanishing indicator, or where the
        Lagrangian is degenerate on the constraints, is a singular stop too.
        """
        t0, t1 = self._t_span(t_span) if t_span is not None else self.t_span
        p = self._run_params(params)
        y_init = self._run_state(y0, t0, p)
        if singular not in ("stop", "ignore"):
            raise JetnhError(f"singular must be 'stop' or 'ignore', not {singular!r}")
        singular_tol = arguments.real(singular_tol, "singular_tol")
        if not 0.0 <= singular_tol < 1.0:
            raise JetnhError(f"singular_tol must be in [0, 1) (a fraction of each "
                             f"indicator's initial size), not {singular_tol}")
        if save not in ("steps", "final"):
            raise JetnhError(f"save must be 'steps' or 'final', not {save!r}")
        budget = arguments.count(max_steps, "max_steps")
        limit = arguments.timeout(timeout)
        n = y_init.shape[0]
        rtol, atol_v = arguments.tolerances(rtol, atol, n)
        name = str(method)
        key = name.lower()
        if backend == "scipy" or key.startswith("scipy"):
            m = name.split("-", 1)[1] if "-" in name else name
            m = {"dop853": "DOP853", "dopri5": "RK45", "rk45": "RK45"}.get(m.lower(), m)
            self._unused(f"scipy-{m}", n_steps=n_steps, h=h, newton_tol=newton_tol,
                         max_newton=max_newton, timeout=timeout,
                         projection=projection or None)
            first, mx = arguments.step_limits(first_step, np.inf if max_step is None
                                              else max_step)
            te = None if t_eval is None else arguments.times(t_eval, t0, t1)
            return self._run_scipy(m, rtol, atol_v, te, t0, t1, y_init, p, first or None, mx,
                                   events, singular, singular_tol)
        if backend not in (None, "numba"):
            raise JetnhError(f"unknown backend {backend!r}; choose 'numba' or 'scipy'")
        if key in DLA_NAMES or key in DVI_NAMES:
            if events:
                raise JetnhError(f"events need dense output, which the {key} integrator does "
                                 "not have; use dop853, dopri5 or rk4")
            self._unused(key, t_eval=t_eval, first_step=first_step, max_step=max_step)
            steps = arguments.fixed_steps(n_steps, h, t0, t1, key, budget)
            arguments.output_rows(steps, 3 * self.system.J.n + 2 * self.system.k, save)
            tol = 1e-13 if newton_tol is None else arguments.positive(newton_tol,
                                                                     "newton_tol")
            iters = 50 if max_newton is None else arguments.count(max_newton, "max_newton",
                                                                  limit=10_000)
            sing = singular_tol if singular == "stop" else None
            # the scene's initial dependent velocities hold for its own parameters only
            own = y0 is None and params is None
            if key in DVI_NAMES:
                if projection:
                    raise JetnhError("projection= is an option of the dla integrator")
                return self._run_dvi(t0, t1, y_init, own, p, steps, save, tol, iters, sing,
                                     limit)
            return self._run_dla(t0, t1, y_init, own, p, steps, save, tol, iters,
                                 bool(projection), sing, limit)
        if projection:
            raise JetnhError("projection= is an option of the dla integrator; the "
                             "Runge-Kutta methods follow the constraints to their tolerance")
        if key not in METHODS:
            raise JetnhError(
                f"unknown method {method!r}; choose one of {sorted(set(METHODS))}, dla, dvi "
                f"or scipy-<{'|'.join(SCIPY_METHODS)}>")
        self._unused(key, newton_tol=newton_tol, max_newton=max_newton)
        method = METHODS[key]
        if method in ADAPTIVE:
            self._unused(method, n_steps=n_steps, h=h)
            first, mx = arguments.step_limits(first_step, np.inf if max_step is None
                                              else max_step)
            mode = EVERY_STEP if save == "steps" else ENDPOINTS
            te = np.zeros(0)
            if t_eval is not None:
                te = arguments.times(t_eval, t0, t1)
                mode = AT_T_EVAL
            settings = (rtol, atol_v, first, mx, budget, te, mode)
            dense = {"rtol": rtol, "atol": atol_v, "mode": mode}
        else:
            if t_eval is not None:
                raise JetnhError("rk4 is a fixed-step method without dense output; pass "
                                 "n_steps or h and read every step, or use dop853 with t_eval")
            self._unused(method, first_step=first_step, max_step=max_step)
            steps = arguments.fixed_steps(n_steps, h, t0, t1, "rk4", budget)
            arguments.output_rows(steps, n, save)
            settings = (steps, EVERY_STEP if save == "steps" else ENDPOINTS)
            dense = {"mode": settings[1]}
        kern = self.kernels
        solve = kern.integrator(method)
        ce = self.compile_events(events)
        n_sing = len(kern.layout.indicators) if singular == "stop" else 0
        uev = ce.uev if ce is not None else kern.sing_fp
        ev_dir = ce.direction if ce is not None else np.zeros(0, dtype=np.int64)
        ev_max = ce.max_events if ce is not None else np.zeros(0, dtype=np.int64)
        halt = interrupt.flag()
        tic = time.perf_counter()
        out = interrupt.call(lambda: solve(kern.rhs_fp, kern.sing_fp, uev, t0, t1, y_init, p,
                                           *settings, n_sing, singular_tol, ev_dir, ev_max,
                                           halt), halt, limit)
        wall = time.perf_counter() - tic
        dense["partial_last"] = int(out[0]) in (EVENT, SINGULAR)    # stopped inside a step
        return self._trajectory(method, out, wall, kern, ce, p, t0, y_init, singular_tol,
                                singular == "stop", limit, dense)

    # ------------------------------------------------------------------ run helpers
    @staticmethod
    def _unused(method, **options):
        """Refuse options that ``method`` does not use (rather than ignore them)."""
        given = [k for k, v in options.items() if v is not None]
        if given:
            raise JetnhError(f"{', '.join(given)} {'is' if len(given) == 1 else 'are'} not an "
                             f"option of the {method} method; remove "
                             f"{'it' if len(given) == 1 else 'them'}")

    def _run_params(self, params) -> np.ndarray:
        """The run-time parameters of one run (``run(params=...)``), checked."""
        if params is None:
            return self.p
        if isinstance(params, dict):
            for k in params:
                name = arguments.name_of(k, "params")
                if name not in self.runtime_params:
                    if name in self.params:
                        raise JetnhError(
                            f"parameter {name!r} is compiled into this scene's kernels "
                            f"(value {self.params[name]!r}), so run(params=...) cannot change "
                            f"it; build the scene with runtime_params=[{name!r}] (or use "
                            f"scene.replace(params={{{name!r}: ...}}))")
                    raise JetnhError(f"params has {name!r}, which is not a parameter of this "
                                     f"system; its parameters are {sorted(self.params)}")
        p, _ = arguments.keyed_or_sequence(params, self.runtime_params, self.p, "params",
                                           "scene.runtime_params")
        return p

    def _run_state(self, y0, t0, p) -> np.ndarray:
        """The initial state of one run (``run(y0=...)``), checked."""
        if y0 is None:
            return self.y0
        if not isinstance(y0, dict):
            y, _ = arguments.keyed_or_sequence(y0, self.state_names, self.y0, "y0",
                                               "scene.state_names")
            return y
        allowed = self.state_names + self.dependent_velocities
        for k in y0:
            name = arguments.name_of(k, "y0")
            if name not in allowed:
                raise JetnhError(f"y0 has {name!r}, which is not a state of this "
                                 f"{self.principle} scene; the states are "
                                 f"{', '.join(self.state_names)}")
        y, given = arguments.keyed_or_sequence(
            y0, allowed, [self.initial[nm] for nm in allowed], "y0", "")
        y = np.ascontiguousarray(y[:len(self.state_names)])
        dep = {nm: v for nm, v in given.items() if nm in self.dependent_velocities}
        if dep:
            vals = dict(zip(self.state_names, y.tolist()))
            required = self._dependent_velocity_values(
                vals, t0, dict(zip(self.runtime_params, p.tolist())))
            for nm, v in dep.items():
                if abs(v - required[nm]) > self.consistency_tol * max(1.0, abs(required[nm])):
                    raise ConstraintError(
                        f"y0 gives {nm} = {v!r} but the constraints give {required[nm]!r}; "
                        "omit it (dependent velocities follow from the constraints)")
        return y

    def compile_events(self, events):
        """The compiled form of ``events`` (``events.CompiledEvents``), or None; kept per
        scene so repeated runs with the same events compile nothing."""
        from .events import as_events, compile_events

        evs = as_events(events)
        if not evs:
            return None
        memo = tuple((sp.srepr(e.fun) if e.is_expression else id(e.fun), e.direction,
                      e.max_events, e.name) for e in evs)
        store = self.__dict__.setdefault("_compiled_events", {})
        if memo not in store:
            store[memo] = compile_events(self, evs)
        return store[memo]

    def _trajectory(self, method, out, wall, kern, ce, p, t0, y_init, singular_tol, checked,
                    timeout=None, dense=None):
        """A Trajectory from the result tuple of a compiled solve (or an error)."""
        from .events import split_records

        (status, ts, ys, n_out, stats, t_last, y_last, ev_t, ev_i, ev_y, n_ev,
         sing_index) = out
        status = int(status)
        singularity = None
        if status == NONFINITE:
            sing_index = (self._explain_nonfinite(kern, t_last, y_last, p, t0, y_init,
                                                  singular_tol) if checked else -1)
            if sing_index < 0:
                self._raise_nonfinite(method, t_last, y_last, kern, p, t0, y_init,
                                      checked=checked)
            status = SINGULAR
            singularity = self._singularity(kern, int(sing_index), t_last, y_last, p, t0,
                                            y_init, singular_tol, nonfinite=True)
        elif status == SINGULAR:
            singularity = self._singularity(kern, int(sing_index), t_last, y_last, p, t0,
                                            y_init, singular_tol)
        if singularity is not None:
            reason = singularity["reason"]
        elif status == EVENT:
            k = int(ev_i[n_ev - 1])
            reason = (f"terminal event {ce.names[k]!r} at t = {float(ev_t[n_ev - 1]):.17g}")
        elif status == STOPPED:
            reason = _timeout_reason(timeout, t_last)
        else:
            reason = STATUS_TEXT[status]
        kw = {}
        if ce is not None:
            t_events, y_events = split_records(len(ce), ev_t[:n_ev], ev_i[:n_ev], ev_y[:n_ev])
            kw["events"] = (ce.names, t_events, y_events)
        return Trajectory(self, ts[:n_out], ys[:n_out], p, method=method, status=status,
                          stop_reason=reason, steps=int(stats[0]), rejected=int(stats[1]),
                          nfev=int(stats[2]), wall_time=wall, kernels=kern,
                          projected=self.projected, singularity=singularity, dense=dense,
                          **kw)

    # ------------------------------------------------------------------ singularities
    def indicators(self, t, y, p=None) -> dict[str, float]:
        """The singularity indicators at (t, y): expression -> value."""
        kern = self.kernels
        g = np.empty(len(kern.layout.indicators))
        kern.sing(float(t), np.ascontiguousarray(y, dtype=float),
                  self.p if p is None else np.ascontiguousarray(p, dtype=float), g)
        return dict(zip(kern.layout.indicators, g.tolist()))

    def _explain_nonfinite(self, kern, t, y, p, t0, y_init, tol) -> int:
        """Index of an indicator that explains a NaN/inf in the step after (t, y): small
        there (below max(tol, 1e-3) of its initial size), or violated along an Euler
        probe of the step, else -1."""
        lay = kern.layout
        m = len(lay.indicators)
        if not m:
            return -1
        g0 = np.empty(m)
        g = np.empty(m)
        kern.sing(t0, y_init, p, g0)
        kern.sing(t, y, p, g)
        with np.errstate(all="ignore"):
            rel = np.abs(g) / np.abs(g0)
            bad = ~np.isfinite(g) | (np.sign(g) != np.sign(g0)) | (rel < max(tol, 1e-3))
        if bad.any():
            return int(np.argmax(bad))
        f = np.empty_like(y)
        kern.rhs(t, y, p, f)
        if not np.all(np.isfinite(f)):
            # no indicator is small here: blame the one nearest to vanishing only if one
            # has moved at all (at the initial state nothing has)
            i = int(np.argmin(rel))
            return i if rel[i] < 1.0 else -1
        span = abs(self.t_span[1] - self.t_span[0]) or 1.0
        for s in np.geomspace(1e-12, 1.0, 25):
            for hh in (s * span, -s * span):
                kern.sing(t + hh, y + hh * f, p, g)
                with np.errstate(all="ignore"):
                    viol = ~np.isfinite(g) | (np.sign(g) != np.sign(g0))
                if viol.any():
                    return int(np.argmax(viol))
        return -1

    def _singularity(self, kern, idx, t, y, p, t0, y_init, tol, nonfinite=False) -> dict:
        """What the stop at a singular configuration was: indicator, kind, time, value,
        and a reason with the way out."""
        lay = kern.layout
        expr, kind = lay.indicators[idx], lay.indicator_kinds[idx]
        g0 = np.empty(len(lay.indicators))
        g = np.empty(len(lay.indicators))
        kern.sing(t0, y_init, p, g0)
        kern.sing(float(t), np.ascontiguousarray(y), p, g)
        value, initial = float(g[idx]), float(g0[idx])
        if not np.isfinite(initial) or initial == 0.0:
            where = (f"the initial state (t = {t:.17g}) is singular: {expr} = {initial:.6g}")
        elif (np.sign(value) == np.sign(initial) and abs(value) > 4 * tol * abs(initial)
              and abs(value) > 1e-12 * abs(initial) and not nonfinite):
            where = (f"the fixed step after t = {t:.17g} jumps over a kink of the right-hand "
                     f"side next to a zero of {expr} = {value:.6g} (initially {initial:.6g}); "
                     "the run stops at the last regular point (an adaptive method such as "
                     "dop853 locates the singular time)")
        elif nonfinite:
            where = (f"the right-hand side became NaN or infinite in the step after "
                     f"t = {t:.17g}, where {expr} = {value:.6g} (initially {initial:.6g}) "
                     "is about to vanish or change sign")
        else:
            where = (f"at t = {t:.17g}, {expr} fell to {value:.6g} (initially "
                     f"{initial:.6g}; the threshold is singular_tol = {tol:g} of that)")
        dep = [s.name for s in self.system.dependent]
        ratio = (self._split_det_ratio(t, y, p, t0, y_init)
                 if kind != "split" and self.system.k > 3 else None)
        if ratio is not None and ratio < 1e-6:
            kind = "split"      # for k > 3 the split's determinant is no indicator of its own
        if kind == "split":
            alt = self._regular_split(t, y, p)
            hint = (f"The determinant of df/dqdot^alpha vanishes: the constraints cannot be "
                    f"solved for the velocities of the dependent coordinates {dep} here. The "
                    "split is singular, not necessarily the motion: use another split"
                    + (f" (here dependent={alt} is regular)" if alt else ""))
        elif kind == "constraint":
            hint = ("The explicit form of the constraints qdot^alpha = phi^alpha(t, q, "
                    "qdot^mu) is singular or not differentiable here, so the dynamics "
                    "have no unique continuation (e.g. the Appell-Hamel constraint at "
                    "zero horizontal speed)")
        else:
            hint = ("A denominator (or a square-root argument) of the accelerations "
                    "vanishes: the reduced mass matrix or the multiplier equations are "
                    "singular here, so the accelerations are not determined")
        if ratio is not None and ratio > 1e-3 and kind == "constraint":
            hint = (f"The split is regular here (det df/dqdot^alpha is {ratio:.3g} of its "
                    "initial value), but with more than 3 constraints phi^alpha comes from a "
                    f"symbolic LU solve, and {expr} is a denominator of it -- likely a pivot "
                    "that vanishes where the matrix does not: a singularity of the "
                    "expressions, not of the motion. Order the constraints so that the solve "
                    "can pivot on constants, or pass it")
        reason = (f"singular configuration: {where}. {hint}. (If the singularity is removable "
                  "-- a 0/0 that cancels -- run with singular='ignore'.)")
        return {"indicator": expr, "kind": kind, "index": idx, "t": float(t),
                "value": value, "initial": initial, "reason": reason}

    def _jacobian_at(self, t, y, p):
        """df/dqdot (k x n) at the state (t, y), numerically, or None."""
        sys_ = self.system
        J = sys_.J
        try:
            aux = np.empty(self.kernels.layout.n_aux)
            self.kernels.aux(float(t), np.ascontiguousarray(y, dtype=float), p, aux)
            vals = {J.t: t}
            vals.update(zip(J.q, y[:J.n]))
            vals.update(zip(sys_.independent_velocities, y[J.n:J.n + J.n - sys_.k]))
            vals.update(zip(sys_.dependent_velocities, aux[:sys_.k]))
            vals.update({s: self.params[s.name] for s in sys_.parameters})
            for i, nm in enumerate(self.runtime_params):
                vals.update({s: p[i] for s in sys_.parameters if s.name == nm})
            A = np.array(sys_.jacobian.xreplace({k: sp.Float(v) for k, v in vals.items()})
                         .evalf(), dtype=float)
        except (TypeError, ValueError):
            return None
        return A if np.all(np.isfinite(A)) else None

    def _split_det_ratio(self, t, y, p, t0, y0):
        """|det df/dqdot^alpha| at (t, y) over its value at (t0, y0), or None."""
        cols = [self.system.J.q.index(s) for s in self.system.dependent]
        A, A0 = self._jacobian_at(t, y, p), self._jacobian_at(t0, y0, p)
        if A is None or A0 is None:
            return None
        d0 = abs(np.linalg.det(A0[:, cols]))
        return float(abs(np.linalg.det(A[:, cols])) / d0) if d0 else None

    def _regular_split(self, t, y, p):
        """A choice of dependent coordinates for which df/dqdot is invertible at (t, y)."""
        from itertools import combinations

        sys_ = self.system
        J = sys_.J
        A = self._jacobian_at(t, y, p)
        if A is None:
            return None
        best, choice = 0.0, None
        for cols in combinations(range(J.n), sys_.k):
            d = abs(np.linalg.det(A[:, list(cols)]))
            if d > best:
                best, choice = d, [J.q[c].name for c in cols]
        norm = max(np.prod(np.linalg.norm(A, axis=1)), 1e-300)
        if choice is None or best < 1e-3 * norm or choice == [s.name for s in sys_.dependent]:
            return None
        return choice

    def _discrete_kernels(self, kind):
        compiled_params = {k: v for k, v in self.params.items()
                           if k not in self.runtime_params}
        principle = "chetaev" if kind == "dla" else "vakonomic"
        key = codegen.symbolic_key(self.system, principle, compiled_params,
                                   self.runtime_params, self.integrals, extra=kind)
        return _cache.load(key, lambda: codegen.generate_dla(
            self.system, compiled_params, self.runtime_params, key=key, kind=principle,
            integrals=self.integrals), persistent=self.cache)

    @property
    def dla_kernels(self):
        """Kernels of the discrete Lagrange-d'Alembert step (``codegen.generate_dla``)."""
        return self._discrete_kernels("dla")

    @property
    def dvi_kernels(self):
        """Kernels of the discrete vakonomic step (``codegen.generate_dla(kind=
        "vakonomic")``)."""
        return self._discrete_kernels("dvi")

    def _run_dla(self, t0, t1, y_init, default_y0, p, n_steps, save, tol, max_iter,
                 projection, singular_tol, timeout):
        from .integrators import dla

        if self.principle != "chetaev":
            raise PrincipleError(
                "the discrete Lagrange-d'Alembert integrator discretizes Chetaev "
                f"(Lagrange-d'Alembert) dynamics, not {self.principle}; use dop853"
                + (", or dvi (the discrete vakonomic integrator)"
                   if self.principle in ("vakonomic", "holder") else ""))
        n = self.system.J.n
        q0 = np.ascontiguousarray(y_init[:n])
        v0 = self._full_velocities(t0, y_init, p, default_y0)
        kern = self.dla_kernels
        mode = EVERY_STEP if save == "steps" else ENDPOINTS
        n_sing = len(kern.layout.indicators) if singular_tol is not None else 0
        v0 = np.ascontiguousarray(v0, dtype=float)
        solve = dla.solver()
        constrained = self._degenerate_off_constraints(kern, t0, q0, v0, p)
        halt = interrupt.flag()
        tic = time.perf_counter()
        out = interrupt.call(lambda: solve(
            kern.step_residual, kern.momentum, kern.legendre, kern.nodal, kern.constraint_jac,
            kern.sing, t0, t1, q0, v0, p, n_steps, self.system.k, tol, max_iter, mode,
            projection, n_sing, float(singular_tol or 0.0), len(kern.layout.integrals),
            constrained, halt), halt, timeout)
        return self._discrete_trajectory(
            "dla" + ("+projection" if projection else ""), kern, out,
            time.perf_counter() - tic, p, t0, t1, n_steps, singular_tol, timeout)

    def _run_dvi(self, t0, t1, y_init, default_y0, p, n_steps, save, tol, max_iter,
                 singular_tol, timeout):
        from .integrators import dvi

        if not (self.principle == "vakonomic" or
                (self.principle == "holder" and self.convention == "paper")):
            raise PrincipleError(
                "the discrete vakonomic integrator discretizes vakonomic dynamics (and "
                "Hoelder's in the paper's convention, which has the same equations), not "
                f"{self.principle}" + ("; use dla for Chetaev" if self.principle == "chetaev"
                                       else "; use dop853"))
        if self.form not in (None, "multiplier"):
            raise PrincipleError(
                f"dvi uses the multipliers of the constraints as written (the 'multiplier' "
                f"form); the scene's form {self.form!r} scales them differently: omit form=")
        J = self.system.J
        n, k = J.n, self.system.k
        q0 = np.ascontiguousarray(y_init[:n])
        lam0 = np.ascontiguousarray(y_init[n + n - k:])
        v0 = self._full_velocities(t0, y_init, p, default_y0)
        kern = self.dvi_kernels
        mode = EVERY_STEP if save == "steps" else ENDPOINTS
        n_sing = len(kern.layout.indicators) if singular_tol is not None else 0
        solve = dvi.solver()
        halt = interrupt.flag()
        tic = time.perf_counter()
        out = interrupt.call(lambda: solve(
            kern.step_residual, kern.momentum, kern.legendre, kern.nodal, kern.sing, t0, t1,
            q0, v0, lam0, p, n_steps, tol, max_iter, mode, n_sing,
            float(singular_tol or 0.0), len(kern.layout.integrals), halt), halt, timeout)
        return self._discrete_trajectory("dvi", kern, out, time.perf_counter() - tic, p, t0,
                                         t1, n_steps, singular_tol, timeout)

    def _discrete_trajectory(self, method, kern, out, wall, p, t0, t1, n_steps, singular_tol,
                             timeout=None):
        """A Trajectory from the result of a dla/dvi solve; a failed Newton step next to a
        singular configuration becomes a singular stop, any other failure an error."""
        status, ts, rows, n_out, stats, t_last, y_last, sing_index, t_prev, y_prev = out
        status = int(status)
        J = self.system.J
        n, k = J.n, self.system.k
        k_lam = k if method == "dvi" else 0
        name = method.split("+")[0]
        singularity = None
        if status == SINGULAR:
            singularity = self._discrete_singularity(kern, int(sing_index), t_last, y_last, p,
                                                     rows[0], t0, singular_tol)
        elif status in (NONFINITE, NOT_CONVERGED):
            singularity = self._explain_discrete(kern, t_last, y_last, t_prev, y_prev, p,
                                                 rows[0], t0, singular_tol, n_out)
            if singularity is None:
                what = ("the state became NaN or infinite" if status == NONFINITE else
                        "Newton's method did not converge")
                raise IntegrationError(
                    f"{name}: {what} in the step from t = {t_last:.17g} "
                    f"(h = {(t1 - t0) / n_steps:.3g}); take a smaller step, or the discrete "
                    "constraint has no nearby solution there")
            status = SINGULAR
        rows = rows[:n_out]
        ind = [J.q.index(s) for s in self.system.independent]
        ys = np.ascontiguousarray(np.hstack([rows[:, :n], rows[:, [n + i for i in ind]],
                                             rows[:, 2 * n:2 * n + k_lam]]))
        c = 2 * n + k_lam
        own = {"velocities": {v.name: rows[:, n + i] for i, v in enumerate(J.qd)},
               "residual": rows[:, c:c + k], "energy": rows[:, c + k],
               "integrals": {nm: rows[:, c + k + 1 + i]
                             for i, nm in enumerate(kern.layout.integrals)}}
        return Trajectory(self, ts[:n_out], ys, p, method=method, status=status,
                          stop_reason=(singularity["reason"] if singularity else
                                       _timeout_reason(timeout, t_last) if status == STOPPED
                                       else STATUS_TEXT[status]),
                          steps=int(stats[0]), rejected=0, nfev=int(stats[1]), wall_time=wall,
                          kernels=kern, projected=self.projected, own=own,
                          singularity=singularity)

    def _node(self, y):
        """(q for the node kernels, v) from a discrete state (q, v[, lambda])."""
        n = self.system.J.n
        return (np.ascontiguousarray(np.concatenate([y[:n], y[2 * n:]])),
                np.ascontiguousarray(y[n:2 * n]))

    def _node_indicators(self, kern, t, y, p):
        g = np.empty(len(kern.layout.indicators))
        kern.sing(float(t), *self._node(y), p, g)
        return g

    def _saddle(self, kern, t, q, v, p):
        """M = d^2F/dqdot^2 and S = [[M, A^T], [A, 0]], A = df/dqdot, at a node: S is the
        matrix the discrete step inverts as h -> 0."""
        n, k = self.system.J.n, self.system.k
        M, mom = np.empty((n, n)), np.empty(n)
        A, f = np.empty((k, n)), np.empty(k)
        kern.legendre(float(t), q, v, p, mom, M)
        kern.constraint_jac(float(t), q, v, p, f, A)
        return M, np.block([[M, A.T], [A, np.zeros((k, k))]])

    def _saddle_condition(self, kern, t, y, p) -> float:
        """Condition number of S (``_saddle``) at a node (infinite where S is singular)."""
        _, S = self._saddle(kern, t, *self._node(y), p)
        with np.errstate(all="ignore"):
            c = np.linalg.cond(S) if np.all(np.isfinite(S)) else np.inf
        return float(c) if np.isfinite(c) else np.inf

    def _degenerate_off_constraints(self, kern, t, q, v, p) -> bool:
        """Whether dla should take node velocities from the constrained Legendre transform:
        ||M^-1|| > 100 ||S^-1|| at the initial node (see ``integrators.dla``)."""
        M, S = self._saddle(kern, t, q, v, p)
        if not (np.all(np.isfinite(M)) and np.all(np.isfinite(S))):
            return False
        smin = lambda X: np.linalg.svd(X, compute_uv=False)[-1]  # noqa: E731
        return bool(smin(S) > 100 * smin(M))

    def _explain_discrete(self, kern, t, y, t_prev, y_prev, p, row0, t0, tol, n_out):
        """The singularity next to which a dla/dvi step failed (Newton did not converge or
        the state became NaN), or None: an indicator below 1 % of its initial size at the
        last regular node, or one whose linear trend over the last two nodes reaches its
        threshold within two steps; else a singular matrix [[F_vv, A^T], [A, 0]]."""
        y0 = row0[:y.shape[0]]
        if kern.layout.indicators:
            g0 = self._node_indicators(kern, t0, y0, p)
            with np.errstate(all="ignore"):
                sg = np.sign(g0) / np.abs(g0)
                rel = sg * self._node_indicators(kern, t, y, p)
                rel_prev = sg * self._node_indicators(kern, t_prev, y_prev, p)
                bad = (~np.isfinite(rel) | (rel <= max(tol or 0.0, 1e-2))
                       | (rel + 2 * (rel - rel_prev) <= (tol or 0.0)))
            if bad.any():
                return self._discrete_singularity(kern, int(np.argmax(bad)), t, y, p, row0,
                                                  t0, tol, failed=True)
        cond = self._saddle_condition(kern, t, y, p)
        if cond > 1e12:
            return self._discrete_singularity(kern, -1, t, y, p, row0, t0, tol, failed=True,
                                              cond=(cond, self._saddle_condition(
                                                  kern, t0, y0, p)))
        return None

    def _discrete_singularity(self, kern, idx, t, y, p, row0, t0, tol, failed=False,
                              cond=None) -> dict:
        """The stop of a dla/dvi run at a singular configuration, as ``_singularity``."""
        lay = kern.layout
        y0 = row0[:y.shape[0]]
        if cond is not None:
            expr, kind = "cond([[d2F/dqdot2, (df/dqdot)^T], [df/dqdot, 0]])", "degenerate"
            value, initial = cond
        else:
            expr, kind = lay.indicators[idx], lay.indicator_kinds[idx]
            initial = float(self._node_indicators(kern, t0, y0, p)[idx])
            value = float(self._node_indicators(kern, t, y, p)[idx])
        if cond is None and (not np.isfinite(initial) or initial == 0.0):
            where = f"the initial state (t = {t:.17g}) is singular: {expr} = {initial:.6g}"
        elif failed:
            where = (f"the step after the node t = {t:.17g} failed (Newton's method did not "
                     f"converge) where {expr} = {value:.6g} (initially {initial:.6g})"
                     + (" is singular" if cond is not None else
                        " is about to vanish or change sign"))
        else:
            where = (f"after the node t = {t:.17g}, {expr} (there {value:.6g}, initially "
                     f"{initial:.6g}) crosses zero or falls below singular_tol = {tol:g} of "
                     "its initial size; the run stops at that last regular node")
        hint = {
            "constraint": "The constraints f^a as written are singular or not differentiable "
                          "here (e.g. the Appell-Hamel constraint at zero horizontal speed), "
                          "so the motion has no unique continuation",
            "lagrangian": "The Lagrangian is singular or not differentiable here",
            "degenerate": "The Lagrangian is degenerate on the constraints here, or the "
                          "constraints lose rank: the discrete step (like the accelerations) "
                          "is not determined"}[kind]
        reason = f"singular configuration: {where}. {hint}."
        return {"indicator": expr, "kind": kind, "index": idx, "t": float(t),
                "value": value, "initial": initial, "reason": reason}

    def _full_velocities(self, t0, y_init, p, default_y0) -> np.ndarray:
        """Every velocity at the initial state (the dependent ones from the constraints)."""
        J = self.system.J
        n = J.n
        if default_y0:
            v0 = [self.initial[v.name] for v in J.qd]
        else:
            vals = dict(zip(self.coordinates + self.velocities, y_init[:2 * n - self.system.k]))
            vals.update(self._dependent_velocity_values(
                vals, t0, dict(zip(self.runtime_params, p))))
            v0 = [vals[v.name] for v in J.qd]
        return np.ascontiguousarray(v0, dtype=float)

    def _raise_nonfinite(self, method, t, y, kern=None, p=None, t0=None, y_init=None,
                         checked=True):
        state = ", ".join(f"{n} = {v:.17g}" for n, v in zip(self.state_names, y))
        extra = ""
        if kern is not None and kern.layout.indicators:
            g = np.empty(len(kern.layout.indicators))
            kern.sing(float(t), np.ascontiguousarray(y, dtype=float), p, g)
            extra = ("; singularity indicators there: "
                     + ", ".join(f"{e} = {v:.6g}" for e, v in zip(kern.layout.indicators, g)))
        why = ("No singularity indicator explains it: the solution blows up, or an "
               "expression leaves its domain; check the model and the initial values, or "
               "integrate a shorter span" if kern is not None and checked else
               "The singularity checks were off (singular='ignore'); run with "
               "singular='stop' to stop at singular configurations" if kern is not None else
               "The equations are singular there (a vanishing denominator of the dependent "
               "velocities or of the reduced mass matrix), or the solution blows up")
        raise IntegrationError(
            f"{method}: the right-hand side or the state became NaN or infinite in the step "
            f"from t = {t:.17g}; state there: {state}{extra}. {why}")

    def _run_scipy(self, method, rtol, atol, t_eval, t0, t1, y_init, p, first_step,
                   max_step, events=None, singular="stop", singular_tol=1e-10) -> Trajectory:
        """scipy's ``solve_ivp`` on the compiled right-hand side; user events and the
        singularity indicators become scipy events (the indicators terminal, direction -1,
        on ``s_i g_i - singular_tol |g_i(t0)|``)."""
        from scipy.integrate import solve_ivp

        if method not in SCIPY_METHODS:
            raise JetnhError(f"unknown scipy method {method!r}; choose one of {SCIPY_METHODS}")
        kern = self.kernels
        rhs = kern.rhs
        n = y_init.shape[0]

        def fun(t, y):
            out = np.empty(n)
            rhs(float(t), np.ascontiguousarray(y, dtype=float), p, out)
            return out

        ce = self.compile_events(events)
        scipy_events = []
        if ce is not None:
            for f, ev in zip(ce.python_funcs, ce.events):
                def g(t, y, f=f):
                    return f(t, y, p)
                g.terminal = ev.max_events if ev.max_events > 0 else False
                g.direction = ev.direction
                scipy_events.append(g)
        n_user = len(scipy_events)
        m = len(kern.layout.indicators) if singular == "stop" else 0
        if m:
            g0 = np.empty(m)
            kern.sing(t0, y_init, p, g0)
            bad = ~np.isfinite(g0) | (g0 == 0.0)
            if bad.any():
                idx = int(np.argmax(bad))
                info = self._singularity(kern, idx, t0, y_init, p, t0, y_init, singular_tol)
                return Trajectory(self, [t0], [y_init], p, method=f"scipy-{method}",
                                  status=SINGULAR, stop_reason=info["reason"], steps=0,
                                  rejected=0, nfev=0, wall_time=0.0, kernels=kern,
                                  projected=self.projected, singularity=info)
            sig, thr = np.sign(g0), singular_tol * np.abs(g0)
            work = np.empty(m)
            for i in range(m):
                def gs(t, y, i=i):
                    kern.sing(float(t), np.ascontiguousarray(y, dtype=float), p, work)
                    v = sig[i] * work[i] - thr[i]
                    return v if np.isfinite(v) else -1.0
                gs.terminal = True
                gs.direction = -1
                scipy_events.append(gs)
        kw = {}
        if first_step:
            kw["first_step"] = first_step
        if not np.all(np.isfinite(fun(t0, y_init))):
            self._raise_nonfinite(f"scipy-{method}", t0, y_init, kern, p, t0, y_init)
        tic = time.perf_counter()
        sol = solve_ivp(fun, (t0, t1), y_init, method=method, t_eval=t_eval, rtol=rtol,
                        atol=atol, max_step=max_step, events=scipy_events or None, **kw)
        wall = time.perf_counter() - tic
        ys = np.ascontiguousarray(sol.y.T)
        if ys.size and not np.all(np.isfinite(ys)):
            bad = int(np.argmax(~np.all(np.isfinite(ys), axis=1)))
            i = max(bad - 1, 0)
            self._raise_nonfinite(f"scipy-{method}", sol.t[i], ys[i], kern, p, t0, y_init)
        status, reason, singularity = (0 if sol.status == 0 else 2), sol.message, None
        kw = {}
        if sol.status == 1:
            hit = [(sol.t_events[k][-1], k) for k in range(len(scipy_events))
                   if len(sol.t_events[k]) and getattr(scipy_events[k], "terminal", False)]
            t_hit, k = min(hit, key=lambda x: x[0] * (1 if t1 >= t0 else -1))
            if k < n_user:
                status, reason = EVENT, f"terminal event {ce.names[k]!r} at t = {t_hit:.17g}"
            else:
                status = SINGULAR
                y_hit = sol.y_events[k][-1]
                singularity = self._singularity(kern, k - n_user, t_hit, y_hit, p, t0,
                                                y_init, singular_tol)
                reason = singularity["reason"]
        if ce is not None:
            kw["events"] = (ce.names, [np.asarray(sol.t_events[k]) for k in range(n_user)],
                            [np.asarray(sol.y_events[k]).reshape(-1, n) for k in range(n_user)])
        return Trajectory(self, sol.t, ys, p, method=f"scipy-{method}", status=status,
                          stop_reason=reason, steps=None, rejected=None, nfev=int(sol.nfev),
                          wall_time=wall, kernels=kern, projected=self.projected,
                          singularity=singularity, **kw)

    def __repr__(self):
        return (f"Scene({self.principle}, states={list(self.state_names)}, "
                f"t_span={self.t_span})")
