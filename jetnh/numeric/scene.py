"""Scenes: a system, a principle, numbers, and a time span, ready to integrate::

    scene = Scene(system, "chetaev", params={R: 1.0}, initial={x: 0.0, phi_t: 1.0, ...},
                  t_span=(0.0, 10.0))
    traj = scene.run(rtol=1e-10, atol=1e-12)            # compiled DOP853
    traj = scene.run(method="dopri5")                   # compiled Dormand-Prince 5(4)
    traj = scene.run(method="rk4", n_steps=1000)        # compiled fixed-step RK4
    traj = scene.run(method="radau")                    # implicit Radau IIA (5), stiff
    traj = scene.run(method="dla", h=0.01)              # discrete Lagrange-d'Alembert
    traj = scene.run(method="dla", h=0.01, projection=True)   # nodes on the constraints
    traj = scene.run(method="dvi", h=0.01)              # discrete vakonomic (variational)
    traj = scene.run(method="scipy-DOP853")             # scipy's solve_ivp, same kernels
    traj = scene.run(events=[y - 1, Event(x_t, terminal=True)])   # user events
    ens = scene.ensemble(initial={"phi_t": array}, params={"R": array}, save="final")

Every run stops at a singular configuration (``singular="stop"``, the default) with
``status`` SINGULAR and a ``stop_reason`` naming the indicator and the time; see
``run``.  The singular set of the split is not one: at the edge of the split's chart
the run goes on in another regular split (``numeric.atlas``; ``split="fixed"`` keeps
the scene's split).

A scene does only what it needs: it derives the equations of its own principle, and only
when its kernels are not in the disk cache; a run's options are checked and planned once
(``numeric.solve``, the one driver of runs, ensembles and sweeps) and the plan kept for
the next run with the same options, also by the scenes ``replace`` makes with the same
kernels (other initial values, time span or run-time parameter values), which share the
charts of the split's edge too (``atlas.atlas``); parameters are numbers substituted
before code generation (``runtime_params`` keeps some as run-time inputs for ensembles);
output is every step, the points of ``t_eval``, or only the end (``save="final"``).

State: every coordinate q^s, the independent velocities qdot^mu and the multipliers of
the principles that have them (vakonomic, Hoelder, Suslov).  Initial values are keyed by
Symbol, by name or by sympy.physics.mechanics dynamicsymbol (``x(t)`` for x, ``x(t).diff()``
for x_t); the dependent velocities follow from the constraints.  If given, they
must agree with the constraints (else ``ConstraintError``), or ``project=True`` replaces
them by the values the constraints require.  A point the split cannot hold is refused
with the split, its measure and a regular split to build the scene in
(``numeric.regular``): where the split is singular (the constraints do not determine the
dependent velocities in the numbers given), or past the edge of its chart with dependent
velocities off f = 0 or not given back by phi; ``run(y0=...)`` and ensembles check
their initial states the same way.

Holonomic constraints g(t, q) = 0 (``system.holonomic``): the initial configuration must
satisfy them (else ``ConstraintError`` with the residual), or ``complete=True`` solves
them by Newton's method for the split's dependent coordinates (those making dg/dq over
them regular; ``complete=[z, ...]`` names others), recorded in ``scene.completed``.  The
compiled explicit and Radau runs project every accepted step back onto g = 0
(``methods.projection``); ``traj.diagnostics.holonomic_residual_max`` reports ``max |g|``.
"""

from __future__ import annotations

import functools
import math
import operator
from collections.abc import Mapping
import mpmath
import numpy as np
import sympy as sp

from ..algebra import dag
from ..mechanics import energy, holonomic, principles
from ..mechanics.system import System
from ..errors import ConstraintError, JetnhError
from ..geometry.jet import sympy_object
from . import arguments, regular, solve
from . import codegen
from . import discrete
from .ensemble import run_ensemble
from .kernels import jacobian_kernels, load as load_kernels, loader
from .kernels import initial as initial_check
from ..frozen import Frozen, FrozenDict, made, memo
from .options import options, typed
from .trajectory import Trajectory

#: an argument ``Scene.replace`` was not given (the scene's own kept)
_KEEP = object()


class Scene(Frozen):
    """A system under one principle with numbers and a time span, ready to integrate.

    Parameters
    ----------
    system : System
        The constrained system.
    principle : str, default "chetaev"
        "chetaev", "vakonomic", "holder" or "suslov" (or an alias).
    params : dict, optional
        Parameters (Symbols or names) -> numbers; default ``system.defaults`` (the
        catalogue models carry them).
    initial : dict, optional
        Initial values (Symbols or names) of the coordinates, independent velocities and
        multipliers; the dependent velocities follow from the constraints (if given,
        they must agree with them).
    t_span : tuple of float
        The time span of ``run``; default (0, 1).
    form, convention : str, optional
        Passed to ``system.equations``.
    integrals : dict, optional
        Names -> sympy expressions: first integrals to monitor (``traj[name]``, their
        drift in the diagnostics).
    runtime_params : sequence of str, optional
        Parameters read at run time instead of compiled in (ensembles, sweeps).
    project : bool, default False
        Replace inconsistent dependent velocities by the values the constraints require.
    consistency_tol : float, default 1e-9
        The relative tolerance of that check: a given dependent velocity may differ from
        the constraints' value by this fraction of the size of the terms that make that
        value (for affine constraints ``qdot^alpha = Phi qdot + phi0``: ``sum_s |Phi_s
        qdot^s| + |phi0|``), never of an absolute number, so that the verdict is the same
        in every unit of length and time; beyond it, by how far the value moves within
        the rounding of t, the coordinates and the parameters (a float stands for every
        number that rounds to it).
    complete : bool or list, default False
        Solve the holonomic constraints for these coordinates (True: chosen
        automatically) of an initial configuration off g = 0 (else it is refused).
    cache : bool, default True
        ``False`` keeps compiled kernels out of the disk cache.

    Notes
    -----
    A scene is immutable (``FrozenError`` on assignment; ``replace`` makes a changed
    copy); what it compiles lazily is kept in its private memo (``jetnh.frozen``).
    See the module docstring for the state and the methods.
    """

    _portable = ("key",)        # a pickled scene (a sweep's worker) keeps its kernels' key

    def __init__(self, system: System, principle: str = "chetaev", params=None, initial=None,
                 t_span=(0.0, 1.0), *, form=None, convention="paper", integrals=None,
                 runtime_params=(), project=False, consistency_tol=1e-9, cache=True,
                 complete=False):
        if not isinstance(system, System):
            raise JetnhError(f"a Scene needs a jetnh System, got {type(system).__name__}")
        principle = principles.canonical(principle)     # a name, an alias or a Principle
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
        self.integrals = FrozenDict({str(k): sympy_object(v)
                                     for k, v in (integrals or {}).items()})
        self.t_span = self._t_span(t_span)
        self.multipliers = codegen.multiplier_names(system, principle)
        self.params = FrozenDict(self._params(params or {}))
        if isinstance(runtime_params, (str, sp.Symbol)):
            runtime_params = (runtime_params,)
        self.runtime_params = tuple(arguments.name_of(k, "a runtime parameter")
                                    for k in runtime_params)
        for name in self.runtime_params:
            if name not in self.params:
                raise JetnhError(f"runtime parameter {name!r} needs a value in params=")
        #: the position of each run-time parameter in ``p``
        self._runtime_index = {n: i for i, n in enumerate(self.runtime_params)}
        #: the values of the parameters compiled into the kernels, of a dict of all
        self._compiled_of = _getter([n for n in self.params if n not in self.runtime_params])
        J = system.J
        self.coordinates = tuple(s.name for s in J.q)
        self.velocities = tuple(v.name for v in system.independent_velocities)
        self.dependent_velocities = tuple(v.name for v in system.dependent_velocities)
        self.state_names = self.coordinates + self.velocities + self.multipliers
        #: the names an initial value may have, the names of the states
        self._initial_names = frozenset(self.state_names + self.dependent_velocities)
        self._state_set = frozenset(self.state_names)
        #: the states' values of a dict of initial values, in order
        self._states_of = _getter(self.state_names)
        self.consistency_tol = arguments.positive(consistency_tol, "consistency_tol")
        self.projected: dict[str, tuple[float, float]] = {}
        #: coordinates moved onto the holonomic constraints: name -> (given, completed)
        self.completed: dict[str, tuple[float, float]] = {}
        self.initial = FrozenDict(self._initial(initial or {}, project, complete)[0])
        self.y0 = np.array([self.initial[n] for n in self.state_names], dtype=float)

    # ------------------------------------------------------------------ input checks
    @staticmethod
    def _t_span(t_span):
        return arguments.time_span(t_span)

    def _params(self, params) -> dict[str, float]:
        needed = self.__dict__.get("_param_names")
        if needed is None:      # (in ``__init__``: found once)
            needed = {s.name for s in self.system.parameters}
            J = self.system.J
            known = {s.name for s in J.q + J.qd} | {J.t.name} | set(self.multipliers)
            for expr in self.integrals.values():
                needed |= {s.name for s in expr.free_symbols if s.name not in known}
            #: the names of the parameters (of the system and of the integrals)
            self._param_names = needed = frozenset(needed)
            #: the system's defaults by name where every one is a finite float of a
            #: parameter (else None): what a dict of finite floats keyed by name adds to
            self._param_defaults = defaults = {
                s.name: v for s, v in self.system.defaults.items()}
            if not (defaults.keys() <= needed and _FLOAT.issuperset(map(type, defaults.values()))
                    and math.isfinite(sum(defaults.values()))):
                self._param_defaults = None
        elif (type(params) is dict and self._param_defaults is not None
              and params.keys() <= needed and _FLOAT.issuperset(map(type, params.values()))
              and math.isfinite(sum(params.values()))):
            # (after ``__init__``, a dict of finite floats keyed by name: what the general
            # route makes of it, at once, where it gives every parameter)
            out = {**self._param_defaults, **params}
            if len(out) == len(needed):
                return out
        out = {}
        given = {**{s.name: v for s, v in self.system.defaults.items()}, **dict(params)}
        for k, v in given.items():
            name = arguments.name_of(k, "a parameter")
            if name not in needed:
                raise JetnhError(
                    f"params has {name!r}, which is not a parameter of this system; its "
                    f"parameters are {sorted(needed) or 'none'}")
            out[name] = arguments.real(v, f"parameter {name!r}")
            if not math.isfinite(out[name]):
                raise JetnhError(f"parameter {name!r} is {out[name]}; give a finite value")
        missing = sorted(needed - set(out))
        if missing:
            raise JetnhError(f"missing parameter values: {', '.join(missing)}; give them in "
                             "params={...} (or as the system's defaults)")
        return out

    def _initial(self, initial, project, complete=False, kernels=None, p=None
                 ) -> tuple[dict[str, float], np.ndarray | None]:
        """The initial values (states and dependent velocities), checked, and the states
        as an array where the kernels gave the dependent velocities (else None);
        ``kernels``: the scene's compiled kernels if they are loaded, ``p`` its run-time
        parameters (``_dependent_velocity_floats``)."""
        allowed = self._initial_names
        if (type(initial) is dict and initial.keys() <= allowed
                and set(map(type, initial.values())) == _FLOAT
                and math.isfinite(sum(initial.values()))):
            # names and finite floats (a NaN or an infinity makes the sum not finite; an
            # overflow of finite values takes the general route, which says which is not)
            given, initial = dict(initial), {}
        else:
            given = {}
        for k, v in initial.items():
            name = k if type(k) is str else arguments.name_of(k, "an initial value")
            if name not in allowed:
                raise JetnhError(
                    f"initial has {name!r}, which is not a state of this {self.principle} "
                    f"scene; the states are {', '.join(self.state_names)} (and the dependent "
                    f"velocities {', '.join(self.dependent_velocities) or 'none'})")
            v = given[name] = v if type(v) is float else arguments.real(
                v, f"initial value of {name!r}")
            if not math.isfinite(v):
                raise JetnhError(f"initial value of {name!r} is {v}")
        if len(given) < len(self.state_names) or not given.keys() >= self._state_set:
            missing = [n for n in self.state_names if n not in given]
            raise JetnhError(
                f"missing initial values: {', '.join(missing)}"
                + ("" if not self.multipliers else
                   f" (the {self.principle} state includes the multipliers "
                   f"{', '.join(self.multipliers)})")
                + "; give them in initial={...} (initial= takes every state, in "
                "Scene.replace too; run(y0=...) changes some and keeps the others)")
        given = self._on_holonomic(given, complete)
        required = y = None
        if kernels is not None and given.keys().isdisjoint(self.dependent_velocities):
            y = np.array(self._states_of(given), dtype=float)
            required = self._dependent_velocity_floats(y, kernels, p)
        if required is None:
            y = None
            required = self._dependent_velocity_values(given)
            self._dependent_velocity_split(given, required, project=project)
        for name, value in required.items():
            if not math.isfinite(value):
                raise ConstraintError(
                    f"the constraints give no finite value for {name} at the initial state "
                    f"({value}): the initial configuration is singular for the split "
                    f"{[s.name for s in self.system.dependent]}")
        ok = self._agree(given, required)
        bad = [(name, given[name], value) for name, value in required.items()
               if not ok.get(name, True)]
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
        return out, y

    def _holonomic_point(self, values, t0=None, params=None) -> dict:
        """t, the coordinates (from ``values``, by name) and the parameters, keyed by
        Symbol (for ``mechanics.holonomic``)."""
        sys_ = self.system
        J = sys_.J
        point = {J.t: self.t_span[0] if t0 is None else t0}
        point.update((q, values[q.name]) for q in J.q)
        numbers = {**self.params, **(params or {})}
        point.update((s, numbers[s.name]) for s in sys_.parameters)
        return point

    def _on_holonomic(self, given, complete) -> dict[str, float]:
        """``given`` with the coordinates on the holonomic constraints: checked, or
        completed (``complete``), else a ConstraintError (``mechanics.holonomic.check``)."""
        if not self.system.holonomic:
            return given
        point, changed = holonomic.check(self.system, self._holonomic_point(given),
                                         complete)
        if not changed:
            return given
        self.completed = changed
        out = dict(given)
        out.update((q.name, float(point[q])) for q in self.system.J.q)
        return out

    def _dependent_velocity_values(self, given, t0=None, params=None) -> dict[str, float]:
        """qdot^alpha = phi^alpha at the initial state (or at ``t0`` with ``params``
        overriding the scene's), evaluated on the shared graph at 30 digits (NaN where
        phi is undefined or not real)."""
        sys_ = self.system
        if not sys_.k:
            return {}
        J = sys_.J
        point = {J.t: self.t_span[0] if t0 is None else t0}
        by_name = {s.name: s for s in J.q + J.qd}
        point.update((by_name[name], v) for name, v in given.items() if name in by_name)
        values = {**self.params, **(params or {})}
        point.update((s, values[s.name]) for s in sys_.parameters)
        vs = sys_.dependent_velocities
        phis = [sys_.phi[v] for v in vs]
        try:
            found = dag.evaluate(phis, point)
        except (ZeroDivisionError, ValueError):     # one undefined: each on its own
            found = []
            for e in phis:
                try:
                    found += dag.evaluate(e, point)
                except (ZeroDivisionError, ValueError):
                    found.append(None)
        return {v.name: _real(x) for v, x in zip(vs, found)}

    def _agree(self, values, required, t0=None, params=None) -> dict[str, bool]:
        """Whether each dependent velocity given in ``values`` (the point, by name)
        agrees with its value in ``required`` (at ``t0``, ``params`` overriding the
        scene's): ``regular.agree``, relative to the size of the terms that make it."""
        given = {n: values[n] for n in self.dependent_velocities if n in values}
        if not given:
            return {}
        return regular.agree(self.system, self.t_span[0] if t0 is None else t0, values,
                             given, required, {**self.params, **(params or {})},
                             self.consistency_tol)

    def _dependent_velocity_split(self, given, required, t0=None, params=None,
                                  where="initial", project=False):
        """Refuse a point the split cannot hold (``numeric.regular``): past the edge of
        its chart, dependent velocities given with the point are checked against f = 0
        itself (off it: a ConstraintError, unless ``project`` where the split still
        determines them); where the split is singular, a point without them, or one on
        f = 0 whose dependent velocities phi^alpha does not give back (the scene's state
        holds only the independent ones), is a ConstraintError naming the split, its
        measure and a regular one.  ``required``: phi^alpha at the point."""
        sys_ = self.system
        dep = self.dependent_velocities
        if not dep:
            return
        complete = all(n in given for n in dep)
        qd = {n: given[n] for n in self.velocities}
        qd.update((n, given[n] if complete else required[n]) for n in dep)
        values = {**self.params, **(params or {})}
        A, f = regular.at_point(sys_, self.t_span[0] if t0 is None else t0, given, qd,
                                values)
        m = float(regular.measure(sys_, A))
        if not regular.past_edge(sys_, m):
            return
        tol = self.consistency_tol
        ok, why, finite = regular.determined(
            sys_, self.t_span[0] if t0 is None else t0, given, qd, values, tol)
        singular = not ok
        if not complete:
            if singular:
                raise regular.singular(sys_, m, A, where, why, finite, give=False)
            return
        if not regular.on_constraints(sys_, self.t_span[0] if t0 is None else t0, given, qd,
                                      values, tol):
            if project and not singular:
                return
            raise regular.off(sys_, f, where)
        if not singular and all(self._agree(given, required, t0, params).values()):
            return
        split, mb = regular.best(sys_, A)
        raise ConstraintError(
            f"{where}: the point is on the constraints, but the split dependent="
            f"{[s.name for s in sys_.dependent]} is {'singular' if singular else 'past the edge of its chart'} "
            f"there (measure det(A_alpha)^2/det(A A^T) = {m:.3g}) and does not give back "
            f"{', '.join(f'{n} = {given[n]!r}' for n in dep)} from the other velocities "
            f"(a scene's state holds only the independent ones): build the scene for "
            f"system.with_split({split}) (measure {mb:.3g} here), where the point is regular")

    def _dependent_velocity_floats(self, y, kern, p) -> dict[str, float] | None:
        """qdot^alpha = phi^alpha at the initial state ``y`` (run-time parameters
        ``p``) by the compiled kernel ``kern.aux``: floats, in microseconds where the
        30-digit evaluation (``_dependent_velocity_values``) takes a tenth of a
        millisecond.  None unless every singularity indicator of ``kern.sing`` (among
        them the denominators and square-root arguments of phi) is finite and at least
        ``FLOAT_MARGIN`` from zero and every value is finite: there, the 30-digit
        evaluation is finite too and the two differ by rounding only; elsewhere (a
        configuration near or at a singular one) the caller evaluates at 30 digits."""
        values = self._dependent_velocity_list(y, self._dv_route(kern), p)
        if values is None:
            return None
        return dict(zip(self.dependent_velocities, values))

    def _dependent_velocity_list(self, y, route, p) -> list[float] | None:
        """``_dependent_velocity_floats`` by the kernels of ``route`` (``_dv_route``) in
        one compiled call (``kernels.initial``, which also finds ``y`` finite): the
        values in the order of ``dependent_velocities``, or None."""
        _, floats, addresses, n_aux, n_dep, _ = route
        if floats is None:
            return None
        aux = np.empty(n_aux)
        if not floats(addresses, self.t_span[0], y, p, aux):
            return None
        return aux.tolist()[:n_dep]

    def _dv_route(self, kern) -> tuple:
        """What ``_dependent_velocity_floats`` calls of ``kern``: (kern, the compiled
        check ``kernels.initial.floats()``, or None where it does not apply, its first
        argument (``kernels.initial.route_of``), the size of aux, the number of dependent
        velocities, an array of that size for the checks that keep no value
        (``_moved``: the check holds the GIL, so no other thread writes it meanwhile)),
        looked up once per kernels (memo ``dv_route``, shared by the copies ``replace``
        makes)."""
        route = self._memo.get("dv_route")
        if route is None or route[0] is not kern:
            lay = kern.layout
            sing = getattr(kern, "sing", None)
            n_ind, n_dep = len(lay.indicators), len(lay.dependent_velocities)
            applies = (lay.dependent_velocities == self.dependent_velocities
                       and (not n_ind or sing is not None))
            route = (kern, initial_check.floats() if applies else None,
                     initial_check.route_of(sing, kern.aux, n_ind, n_dep), lay.n_aux, n_dep,
                     np.empty(lay.n_aux))
            self._memo["dv_route"] = route
        return route

    # ------------------------------------------------------------------ kernels
    @memo
    def spec(self) -> codegen.KernelSpec:
        """The identity of the scene's kernels (``codegen.KernelSpec``) and its key."""
        return codegen.KernelSpec(self.system, self.principle, self.params,
                                  self.runtime_params, self.integrals, self.form,
                                  self.convention)

    @memo
    def key(self) -> str:
        return self.spec.key

    @property
    def kernels(self):
        """The compiled kernels (from memory, the disk cache, or generated now)."""
        return load_kernels(self.key, lambda: codegen.generate(self.spec),
                            persistent=self.cache)

    @property
    def jacobian(self):
        """``jac(t, y, p, J)``: writes ``J[i, j] = d rhs_i / d y_j`` (``J`` a C-contiguous
        float64 n_state x n_state array; ``y`` in the order ``state_names``, ``p`` the
        run-time parameters ``self.p``), the kernel generated from the derivation
        (``kernels.jacobian_kernels``, forward mode over the shared graph) that radau
        uses; ``jacobian.address`` is its C callback for compiled code."""
        return jacobian_kernels(self).jac

    def replace(self, *, initial=_KEEP, t_span=_KEEP, params=_KEEP, **changes) -> "Scene":
        """A scene equal to this one except for the arguments given (constructor
        arguments: params, initial, t_span, runtime_params, integrals, ...).  ``initial``
        replaces the initial values as a whole: it needs a value for every state
        (``run(y0=...)`` changes some and keeps the others); dependent velocities follow
        from the constraints again."""
        if not changes:         # (named: no dict of them to make and read)
            span = self.t_span if t_span is _KEEP else t_span
            if params is _KEEP:
                return self._moved({} if initial is None else initial, span)
            if self.runtime_params and (type(params) is dict  # (before the ABC's test)
                                        or isinstance(params, (Mapping, type(None)))):
                numbers = self._params(params or {})
                if self._compiled_of(numbers) == self._compiled_of(self.params):
                    # only run-time parameters changed: the same kernels (``_moved``)
                    return self._moved({} if initial is None else initial, span,
                                       FrozenDict(numbers))
        changes.update((k, v) for k, v in (("initial", initial), ("t_span", t_span),
                                           ("params", params)) if v is not _KEEP)
        args = dict(system=self.system, principle=self.principle, params=self.params,
                    initial={n: self.initial[n] for n in self.state_names},
                    t_span=self.t_span, form=self.form, convention=self.convention,
                    integrals=self.integrals, runtime_params=self.runtime_params,
                    consistency_tol=self.consistency_tol, cache=self.cache)
        unknown = set(changes) - set(args) - {"project", "complete"}
        if unknown:
            raise JetnhError(f"Scene.replace: unknown arguments {sorted(unknown)}")
        args.update(changes)
        system = args.pop("system")
        principle = args.pop("principle")
        new = Scene(system, principle, **args)
        if new._kernel_identity() == self._kernel_identity():
            # the same kernels: their key and the plans of runs go with them
            new._memo.update(self._shared_memo())
        return new

    def _moved(self, initial, t_span, params=None) -> "Scene":
        """``replace(initial=..., t_span=...)`` (``initial`` ``_KEEP``: this scene's),
        and ``params`` (checked) where only run-time parameters change: this scene with
        other initial values, time span and run-time parameter values, its other
        attributes (checked once) and its memo's shared values (``_SHARED``, and ``_p``)
        taken over rather than made anew (``_moving``).  The most common initial values
        (a dict of every state, no dependent velocity, as floats, or this scene's own
        states, on a scene without holonomic constraints whose kernels are loaded) are
        checked in one compiled call (``_dv_route``: where ``_initial`` would take the
        floats it finds, else the general route, which names what is wrong), the state
        array kept as it is (the direct runs' ``_y0``; this scene's own shared, as no run
        writes it) and ``initial`` (its dependent velocities found again by the same
        call) and ``y0`` made of them when first read (``frozen.made``); other initial
        values by ``_initial``."""
        own = self._memo
        hit = own.get("moved")
        if hit is None or hit[0] != len(own) or hit[1] is None:
            # (what the copies take over, looked up again when this memo grew, or until
            # the kernels are loaded)
            hit = self._moving()
        _, kern, p, shared, route, attributes = hit
        if t_span is not self.t_span:
            t_span = self._t_span(t_span)
        if params is not None:
            p = np.array([params[n] for n in self.runtime_params], dtype=float)
        given = y = None
        if route is not None:       # the route at once, where it applies
            if initial is _KEEP:
                y = own.get("_y0")
                if y is None:
                    y = self._y0
            elif type(initial) is dict and len(initial) == len(self.state_names):
                try:        # (every state, so nothing else: as many keys as states)
                    states = self._states_of(initial)
                except KeyError:
                    states = ()
                if states and _FLOAT.issuperset(map(type, states)):
                    y = np.array(states)
                    given = FrozenDict(initial)
            if y is not None and not route[1](route[2], t_span[0], y, p, route[5]):
                y = None
        # (the attributes set directly, not by ``_set``: a time span is a tuple of
        # floats, the initial values floats; ``_memo`` the copy's own, before anything
        # reads it)
        new = _new(Scene)
        d = new.__dict__
        d.update(attributes)    # (sooner than filling a dict)
        d["_memo"] = memo = shared.copy()   # (frozen from here: ``_initial`` sets nothing
        #                                     when it neither projects nor completes)
        if t_span is not self.t_span:
            d["t_span"] = t_span
            memo.pop("quick", None)     # (the quick plans: of this span)
        if params is not None:
            d["params"] = params
            memo["_p"] = p
        if y is not None:
            memo["_y0"] = y
            memo["_given"] = (given, route)
            return new
        if initial is _KEEP:
            initial = {n: self.initial[n] for n in self.state_names}
        elif type(initial) is not dict and not isinstance(initial, Mapping):
            raise JetnhError(f"initial must be a dict keyed by Symbol or name, got a "
                             f"{type(initial).__name__}")
        ini, y = new._initial(initial, False, False, kern, p)
        if y is None:
            y = np.array(self._states_of(ini), dtype=float)
        # (this copy's own state array: its direct runs' ``_y0``, y0 a read-only view)
        memo["_y0"] = y
        y0 = y.view()
        y0.setflags(write=False)
        d["initial"] = FrozenDict(ini)
        d["y0"] = y0
        return new

    def _moving(self) -> tuple:
        """What the copies ``_moved`` makes take over from this scene, kept in its memo
        (``moved``): (the memo's size, the kernels if loaded, ``_p``, the shared memo
        with the quick plans of this span, ``_dv_route`` where the kernels are loaded,
        its check applies and no holonomic constraint is to be checked (else None), the
        attributes of a copy but ``initial``, ``y0`` and ``_memo``)."""
        own = self._memo
        key = own.get("key")
        kern = None if key is None else _loaded_kernels(key, self.cache)
        route = (None if kern is None or self.system.holonomic
                 else self._dv_route(kern))       # (this scene's, shared below)
        if route is not None and route[1] is None:
            route = None
        p = own.get("_p")
        if p is None:
            p = self._p
        shared = self._shared_memo()
        shared["_p"] = p
        # (one store of quick plans for this scene and the copies on its span: a loop of
        # ``replace(initial=...).run()`` plans once though this scene never ran)
        shared["quick"] = own.setdefault("quick", {})
        attributes = {k: v for k, v in self.__dict__.items()
                      if k not in ("initial", "y0", "_memo")}
        attributes["projected"] = attributes["completed"] = _NOTHING
        own["moved"] = None
        hit = own["moved"] = (len(own), kern, p, shared, route, attributes)
        return hit

    @made
    def initial(self) -> FrozenDict:
        """The initial values of a copy ``_moved`` made (the scenes ``Scene(...)`` makes
        hold theirs in ``__dict__``): the states given (or the scene's, in the order of
        ``state_names``) and the dependent velocities the kernels gave, made when first
        read."""
        memo = self._memo
        given, route = memo["_given"]
        if given is None:
            given = FrozenDict(zip(self.state_names, memo["_y0"].tolist()))
        # (phi^alpha again, as the check found them: the same call)
        dict.update(given, zip(self.dependent_velocities, self._dependent_velocity_list(
            memo["_y0"], route, memo["_p"])))
        return given

    @made
    def y0(self) -> np.ndarray:
        """The initial state of a copy ``_moved`` made, a read-only view of its ``_y0``
        (the scenes ``Scene(...)`` makes hold theirs in ``__dict__``)."""
        y0 = self._memo["_y0"].view()
        y0.setflags(write=False)
        return y0

    def __getstate__(self):
        state = super().__getstate__()
        if "y0" not in state:           # (a copy ``_moved`` made: its values made now)
            state["initial"], state["y0"] = self.initial, self.y0
        return state

    def _shared_memo(self) -> dict:
        """What a scene with the same kernels takes over from this one's memo
        (``_SHARED``), the stores of plans and compiled events made here first, so that
        this scene, its copies and theirs fill one store (a copy made before this scene's
        first run plans nothing its siblings planned)."""
        memo = self._memo
        hit = memo.get("shared")
        if hit is not None and hit[0] == len(memo):    # (entries are only ever added)
            return dict(hit[1])
        memo.setdefault("plans", {})
        memo.setdefault("spans", {})
        memo.setdefault("quick_spans", {})
        memo.setdefault("events", {})
        memo.setdefault("atlases", [])
        shared = {k: memo[k] for k in _SHARED if k in memo}
        memo["shared"] = None
        memo["shared"] = (len(memo), shared)
        return dict(shared)

    def _kernel_identity(self) -> tuple:
        """What the compiled kernels of this scene are a function of."""
        return (self.system, self.principle, self.form, self.convention, self.cache,
                self.runtime_params, self.integrals,
                {k: v for k, v in self.params.items() if k not in self.runtime_params})

    #: ``scene.ensemble(initial, params, **options)``: many runs in one call,
    #: ``jetnh.numeric.ensemble.run_ensemble(scene, initial, params, **options)`` itself
    #: (arrays [n_runs, n_times, n_states] and per-run diagnostics; parallel over the
    #: cores)
    ensemble = run_ensemble

    def compile(self) -> "Scene":
        """Build (or load) the kernels now rather than at the first run."""
        self.kernels
        return self

    @property
    def p(self) -> np.ndarray:
        return np.array([self.params[n] for n in self.runtime_params], dtype=float)

    # ------------------------------------------------------------------ run
    def run(self, rtol=None, atol=None, t_eval=None, method="dop853", *, save="steps",
            events=None, t_span=None, y0=None, params=None, timeout=None, projection=False,
            backend=None, step=None, singular="stop", split=None, newton=None,
            sensitivities=False, sensitivity_error=True, **keywords) -> Trajectory:
        """Integrate and return a ``Trajectory``.

        Parameters
        ----------
        rtol, atol : float, optional
            Tolerances of the adaptive methods (1e-9, 1e-12; ``atol`` a scalar or one
            value per state); short for ``step=StepControl(rtol=..., atol=...)``.
        t_eval : array_like, optional
            Output times inside the span, from the dense output; default every step.
        method : str, default "dop853"
            "dop853", "dopri5" (alias "RK45"), "rk4" (fixed step), "radau" (implicit
            Radau IIA of order 5 for stiff problems, with the Jacobian from the symbolic
            derivation), "dla" (the structure-preserving discrete Lagrange-d'Alembert
            midpoint integrator, Chetaev only, fixed step), "dvi" (the discrete
            vakonomic midpoint variational integrator, fixed step), or "scipy-<M>" for
            scipy's ``solve_ivp(method=M)`` on the same compiled right-hand side.
        save : {"steps", "final"}, default "steps"
            Every step (or the points of ``t_eval``), or the two ends only; with
            ``t_eval`` both keep the points of ``t_eval`` (the rows asked for).  The
            diagnostics' residual and energy drift are taken over the stored rows
            (``Diagnostics.rows``, ``saved``): with "final" an end-point difference
            ``|E(t_final) - E(t0)|``, which can be far below the largest drift on the
            way.
        events : list, optional
            Sympy expressions, callables g(t, y) or ``Event`` (``jetnh.numeric.events``)
            with scipy's semantics, located on the dense output (dla and dvi: on the
            line between their nodes); the trajectory reports ``t_events``,
            ``y_events`` and ``events``; a terminal event ends the run.
        t_span : tuple of float, optional
            Replaces the scene's.
        y0 : dict or sequence, optional
            The initial state: a dict keyed by Symbol, name or dynamicsymbol (the other
            states keep the scene's values; dependent velocities, if given, must agree
            with the constraints) or a sequence in the order ``scene.state_names``.
        params : dict or sequence, optional
            The run-time parameters (``runtime_params``): a dict, or a sequence in the
            order ``scene.runtime_params``.
        timeout : float, optional
            Seconds of wall-clock time, after which the run returns what it has with
            status STOPPED.  Ctrl-C stops a compiled run within one step.
        projection : bool, default False
            dla: project every node velocity onto the constraints.
        backend : str, optional
            ``"scipy"`` for scipy's ``solve_ivp`` (as ``method="scipy-<M>"``).
        step : jetnh.numeric.options.StepControl, optional
            ``StepControl(rtol, atol, first_step, max_step, max_steps, n_steps, h)``
            (``numeric.options``), or those as keywords: the first and the largest
            adaptive step (automatic, none), the budget of steps (10^7; the fixed-step
            methods refuse more up front) and the fixed step of rk4, dla and dvi
            (``n_steps``, or ``h``: the step taken is span / ceil(span / h), at most h).
        singular : {"stop", "ignore"} or jetnh.numeric.options.Singular, default "stop"
            With ``singular_tol`` (or ``Singular(action, tol)``): "stop" ends the run at
            a singular configuration, where a singularity indicator of the scene
            (``kernels.layout.indicators``: the determinant of df/dqdot^alpha,
            denominators and square-root arguments of phi and of the accelerations)
            crosses zero or falls below ``tol`` (1e-10) times its initial size; the point
            is located on the dense output, ``status`` is SINGULAR and ``stop_reason``
            names the indicator, the time and the way out.  dla and dvi check the
            indicators of the constraints and the Lagrangian as written at every node
            and stop at the last regular one.
        split : {"switch", "fixed"}, default "switch"
            dop853, dopri5, rk4 and radau runs that reach the edge of the split's chart
            go on in another regular split (``numeric.atlas``: the switch located as an
            event, the state and multipliers mapped, one trajectory in the scene's
            states, ``traj.switches`` lists time, from and to); "fixed" keeps the
            scene's split, which stops at its singular set, as scipy's methods always do.
        newton : jetnh.numeric.options.Newton, optional
            ``Newton(tol, max_iter)`` or ``newton_tol``, ``max_newton``: the Newton
            iteration of radau (automatic, 7) and of dla and dvi (1e-13, 50).
        sensitivities : bool, default False
            dop853, dopri5, rk4, radau and scipy's methods: integrate with the state the
            variational equations ``S' = (df/dy) S + df/dp``, ``S(t0) = (I | 0)``, of
            ``S = dy(t)/d(y(t0), p)`` (the derivatives of the initial state and of the
            runtime parameters), df/dy and df/dp generated from the derivation (forward
            mode over the graph, compiled: ``kernels.sensitivity_kernels``);
            ``traj.sensitivity(of, to)`` reads them.  Such a run changes split as
            others do (``split``), S carried across (``numeric.atlas``).
        sensitivity_error : bool, default True
            Whether S is under the error control (its entry (i, k) with the tolerance of
            state i, so S is as accurate as the state); with False only the state is
            controlled (the steps of the run without sensitivities: cheaper, S
            uncontrolled).
        **keywords
            The fields of ``StepControl``, ``Singular`` and ``Newton`` by name.

        Returns
        -------
        Trajectory
            NaN or infinity that no indicator explains raises an ``IntegrationError``
            naming the time and the state instead.  Every argument is checked before it
            reaches compiled code (``numeric.arguments``).
        """
        if (events is None and timeout is None and projection is False
                and backend is None and step is None and newton is None
                and sensitivities is False and sensitivity_error is True
                and type(singular) is str and (t_span is None or type(t_span) is tuple)
                and (t_eval is None or (type(t_eval) is np.ndarray
                                        and t_eval.dtype is _FLOAT64))):
            # options that are numbers, strings and an array of times (most runs, and
            # every loop of runs): their plan kept in this scene's memo under them and
            # the types of the numbers (``True == 1``, but a bool is refused where 1 is
            # not), at once.  (What follows the first eight entries of a key starts with
            # bytes, a name or a number: times, a keyword, the time span, which is last.)
            span = None
            try:
                key = (method, save, rtol, atol, singular, split, type(rtol), type(atol))
                if t_eval is not None:
                    key += (t_eval.tobytes(), t_eval.shape)
                if keywords:
                    for k, v in keywords.items():
                        key += (k, v, type(v))
                if t_span is not None:
                    a, b = t_span
                    key += (a, b, type(a), type(b))
                plan = self._memo.get("quick", _NONE_KEPT).get(key)
            except (TypeError, ValueError):     # a key not hashable, or no pair of times
                plan = key = None
            if plan is None:                    # not planned yet (under this key)
                plan, span = self._kept_plan(key, rtol, atol, t_eval, method, save, t_span,
                                             singular, split, keywords)
        else:
            span = None
            plan = self._plan(rtol, atol, t_eval, method, save, events, t_span, timeout,
                              projection, backend, step, singular, split, newton,
                              sensitivities, sensitivity_error, keywords)
        memo = self._memo
        p = memo.get("_p") if params is None else self._run_params(params)
        if p is None:
            p = self._p
        if y0 is None:      # the scene's own (``own``: and its parameters' values)
            if params is not None:          # (its start checked at these values)
                self._own_start_at(plan.t0 if span is None else span[0], p)
            if plan.direct or plan.switch:  # (the loops read y0 into copies of their
                #                                 own, the atlas never writes it)
                y = memo.get("_y0")
                return solve.run(self, plan, self._y0 if y is None else y, p,
                                 params is None, span)
            return solve.run(self, plan, self.y0.copy(), p, params is None, span)
        return solve.run(self, plan, self._run_state(
            y0, plan.t0 if span is None else span[0], p), p, False, span)

    def _quick_plan(self, method, save, rtol, atol) -> solve.Plan:
        """The plan of ``run(method=method, save=save, rtol=rtol, atol=atol)`` (whose
        compiled loop the benchmarks call directly)."""
        return self._plan(rtol, atol, None, method, save, None, None, None, False, None,
                          None, "stop", None, None, False, True, {})

    def _kept_plan(self, key, rtol, atol, t_eval, method, save, t_span, singular, split,
                   keywords) -> tuple[solve.Plan, tuple[float, float] | None]:
        """The plan of a run whose options are numbers, strings and an array of times
        (``run``), kept in this scene's memo under ``key`` (None: none), which the
        scenes ``replace`` makes with the same time span share, and None; or, with a
        time span, a plan of the same options on another span (kept under the key
        without the span, its last four entries) and the span ``(t0, t1)`` (checked) to
        run it on (``solve.run``), where the plan is direct, else that plan taken over
        on the span (``solve.on_span``): a loop over time spans plans once and makes
        no plan a run."""
        memo = self._memo
        free = spans = None
        if key is not None and t_span is not None:
            free = key[:-4]
            spans = memo.setdefault("quick_spans", {})
            other = spans.get(free)
            if other is not None:
                span = arguments.time_span(t_span)
                if other.direct:
                    return other, span
                return solve.on_span(other, *span), None
        plan = self._plan(rtol, atol, t_eval, method, save, None, t_span, None, False,
                          None, None, singular, split, None, False, True, keywords)
        if free is not None and plan.spans:
            solve.keep(spans, free, plan)
        if key is not None:
            solve.keep(memo.setdefault("quick", {}), key, plan)
        return plan, None

    def _plan(self, rtol, atol, t_eval, method, save, events, t_span, timeout, projection,
              backend, step, singular, split, newton, sensitivities, sensitivity_error,
              keywords) -> solve.Plan:
        """The plan of a run with these options (``run``), kept under a key of every
        option and the time span (``solve.planned``: a plan of the same options on
        another span lends what does not depend on it)."""
        span = self.t_span if t_span is None else arguments.time_span(t_span)
        key = (typed(rtol), typed(atol), method, save, timeout, projection, backend,
               typed(step), typed(singular), split, typed(newton), sensitivities,
               sensitivity_error, solve.hashable(events), solve.hashable(t_eval),
               *((k, typed(v)) for k, v in keywords.items()))
        key = (key, tuple(map(type, key)))
        return solve.planned(self, key, span=span, make=lambda: solve.plan(
            self, method, opts=options(step, singular, newton, rtol=rtol, atol=atol,
                                       split=split, **keywords),
            t_span=span, t_eval=t_eval, save=save, events=events, timeout=timeout,
            projection=projection, backend=backend, sensitivities=sensitivities,
            sensitivity_error=sensitivity_error))

    # ------------------------------------------------------------------ run helpers
    @memo
    def _p(self) -> np.ndarray:
        """``p``, made once: the run-time parameters the runs read (never written)."""
        return self.p

    @memo
    def _y0(self) -> np.ndarray:
        """``y0`` as the writable array compiled loops take, made once: the initial state
        of the direct runs (``solve.Plan.direct``), whose loops read it into a copy of
        their own and never write it."""
        return self.y0.copy()

    def _run_params(self, params) -> np.ndarray:
        """The run-time parameters of one run (``run(params=...)``), checked."""
        if params is None:
            return self._p
        index = self._runtime_index
        if (type(params) is dict and params.keys() <= index.keys()
                and _FLOAT.issuperset(map(type, params.values()))
                and math.isfinite(sum(params.values()))):
            # (run-time parameters by name as finite floats: what the general route makes
            # of them, at once; a NaN or an infinity makes the sum not finite, an overflow
            # of finite values takes the general route, which looks at each)
            p = self._p.copy()
            for name, value in params.items():
                p[index[name]] = value
            return p
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
            return self.y0.copy()        # the compiled loop gets its own array
        if (type(y0) is np.ndarray and y0.dtype is _FLOAT64 and y0.shape == self.y0.shape
                and math.isfinite(sum(y0.tolist()))):
            # (a NaN or an infinity makes the sum of the floats not finite; an overflow
            # of finite values takes the general route, which says so)
            y = y0.copy()               # (what the general route makes of it, sooner)
            if self.system.holonomic:
                self._check_holonomic(y, t0, p)
            if self.dependent_velocities and not self._regular_at(y, t0, p):
                self._check_split(y, {}, t0, p)
            return y
        if not isinstance(y0, dict):
            y, _ = arguments.keyed_or_sequence(y0, self.state_names, self.y0, "y0",
                                               "scene.state_names")
            if self.system.holonomic:
                self._check_holonomic(y, t0, p)
            if self.dependent_velocities:
                self._check_split(y, {}, t0, p)
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
        self._check_holonomic(y, t0, p)
        dep = {nm: v for nm, v in given.items() if nm in self.dependent_velocities}
        required = self._check_split(y, dep, t0, p)
        if dep:
            ok = self._agree({**dict(zip(self.state_names, y.tolist())), **dep}, required,
                             t0, dict(zip(self.runtime_params, p.tolist())))
            for nm, v in dep.items():
                if not ok[nm]:
                    raise ConstraintError(
                        f"y0 gives {nm} = {v!r} but the constraints give {required[nm]!r}; "
                        "omit it (dependent velocities follow from the constraints)")
        return y

    def _own_start_at(self, t0, p):
        """Refuse a run from the scene's own initial state at other run-time parameter
        values ``p`` (``run(params=...)``) where that state is off the holonomic
        constraints there, or the split cannot hold it (as ``run(y0=...)`` does)."""
        if self.system.holonomic:
            self._check_holonomic(self._y0, t0, p)
        if self.dependent_velocities and not self._regular_at(self._y0, t0, p):
            self._check_split(self._y0, {}, t0, p)

    def _check_split(self, y, dep, t0, p) -> dict | None:
        """Refuse a run's initial state that the split cannot hold
        (``_dependent_velocity_split``; ``dep``: the dependent velocities given with it);
        phi^alpha there (None where every singularity indicator is at least
        ``FLOAT_MARGIN`` from zero and none is given: the split determines them)."""
        if not self.dependent_velocities or (not dep and self._regular_at(y, t0, p)):
            return None
        vals = dict(zip(self.state_names, y.tolist()))
        prm = dict(zip(self.runtime_params, p.tolist()))
        required = self._dependent_velocity_values(vals, t0, prm)
        self._dependent_velocity_split({**vals, **dep}, required, t0, prm, "y0")
        return required

    def _regular_at(self, y, t0, p) -> bool:
        """Whether every singularity indicator of the kernels (among them det
        df/dqdot^alpha and the denominators of phi) is finite and at least
        ``FLOAT_MARGIN`` from zero at the state ``y``."""
        found = self._memo.get("sing")
        if found is None:       # (looked up once: a run's fixed cost)
            kern = self.kernels
            found = self._memo["sing"] = (getattr(kern, "sing", None),
                                          len(kern.layout.indicators))
        sing, n = found
        if sing is None:
            return False
        if not n:
            return True
        g = np.empty(n)
        sing(float(t0), y, p, g)
        for x in g.tolist():
            if not FLOAT_MARGIN <= abs(x) < math.inf:         # (False at a NaN)
                return False
        return True

    def _check_holonomic(self, y, t0, p):
        """Refuse a run's initial state off the holonomic constraints."""
        if not self.system.holonomic:
            return
        values = dict(zip(self.state_names, np.asarray(y, dtype=float).tolist()))
        try:
            holonomic.check(self.system, self._holonomic_point(
                values, t0, dict(zip(self.runtime_params, np.asarray(p).tolist()))))
        except ConstraintError as exc:
            raise ConstraintError(
                f"y0: {exc} (a run does not complete y0; use "
                "scene.replace(initial=..., complete=True))") from None

    def compile_events(self, events):
        """The compiled form of ``events`` (``events.CompiledEvents``), or None; kept per
        scene so repeated runs with the same events compile nothing."""
        from .events import as_events, compile_events

        evs = as_events(events)
        if not evs:
            return None
        memo = tuple((sp.srepr(e.fun) if e.is_expression else id(e.fun), e.direction,
                      e.max_events, e.name) for e in evs)
        store = self._memo.setdefault("events", {})
        if memo not in store:
            store[memo] = compile_events(self, evs)
        return store[memo]

    def _sensitivity_columns(self) -> tuple[str, ...]:
        """The names of the columns of S = dy/d(y0, p): the states, then the runtime
        parameters."""
        return self.state_names + self.runtime_params

    # ------------------------------------------------------------------ singularities
    def indicators(self, t, y, p=None) -> dict[str, float]:
        """The singularity indicators at (t, y): expression -> value."""
        kern = self.kernels
        g = np.empty(len(kern.layout.indicators))
        kern.sing(float(t), np.ascontiguousarray(y, dtype=float),
                  self.p if p is None else np.ascontiguousarray(p, dtype=float), g)
        return dict(zip(kern.layout.indicators, g.tolist()))

    @property
    def energy_changes(self) -> tuple[str, ...]:
        """Why the energy of this scene's motions is not conserved by design
        (``mechanics.energy.changes`` at these parameter values; () where it is):
        the diagnostics' note on its drift."""
        return _energy_changes(self.system, self.principle, tuple(self.params.items()))

    @property
    def dla_kernels(self):
        """Kernels of the discrete Lagrange-d'Alembert step (``codegen.generate_dla``)."""
        return discrete.kernels(self, "chetaev")

    @property
    def dvi_kernels(self):
        """Kernels of the discrete vakonomic step (``codegen.generate_dla(kind=
        "vakonomic")``)."""
        return discrete.kernels(self, "vakonomic")

    def __repr__(self):
        return (f"Scene({self.principle}, states={list(self.state_names)}, "
                f"t_span={self.t_span})")


@functools.lru_cache(maxsize=64)
def _energy_changes(system, principle, params) -> tuple[str, ...]:
    """``mechanics.energy.changes`` (derived once per system, principle and values)."""
    return energy.changes(system, principle, dict(params))


#: what a scene with the same kernels (``Scene.replace``) takes over from the memo: the
#: kernels' keys, the plans of runs (``solve.planned``) and those taken over on other
#: time spans, the quick plans of runs on a span of their own (``Scene._kept_plan``),
#: compiled events, whether an atlas applies and the first atlas (whose charts the
#: others share: ``atlas.atlas``)
_SHARED = ("spec", "key", "plans", "spans", "quick_spans", "events", "atlas_applies",
           "atlases", "dv_route")


_FLOAT = frozenset((float,))
_new = object.__new__
#: ``projected`` and ``completed`` of the copies ``replace`` makes (nothing moved)
_NOTHING = FrozenDict()
#: the plans of a scene that kept none (``run``: its key is hashed all the same)
_NONE_KEPT: dict = {}
#: the dtype of the arrays a run takes as they are (numpy's one instance of it)
_FLOAT64 = np.dtype(np.float64)

#: the least |indicator| at which the initial dependent velocities are taken from the
#: compiled kernels (``Scene._dependent_velocity_floats``)
FLOAT_MARGIN = initial_check.MARGIN


def _getter(names):
    """The values of ``names`` in a dict, as a tuple (``operator.itemgetter``, which
    returns one value, not a tuple, for one name, and takes no zero names)."""
    return operator.itemgetter(*names) if len(names) > 1 else _Few(tuple(names))


class _Few:
    """``_getter`` of fewer than two names."""

    def __init__(self, names):
        self.names = names

    def __call__(self, values) -> tuple:
        return tuple(values[n] for n in self.names)


def _loaded_kernels(key, persistent):
    """The kernels of ``key`` if this process has loaded them, else None (to use them
    where they are at hand, never to compile them)."""
    return loader._LOADED.get((key, persistent))


def _real(x) -> float:
    """An mpmath value as a float; NaN when it is missing or not real."""
    if x is None or (isinstance(x, mpmath.mpc) and x.imag != 0):
        return float("nan")
    return float(mpmath.re(x))
