"""Scenes: a system, a principle, numbers, and a time span, ready to integrate.

    scene = Scene(system, "chetaev", params={R: 1.0}, initial={x: 0.0, phi_t: 1.0, ...},
                  t_span=(0.0, 10.0))
    traj = scene.run(rtol=1e-10, atol=1e-12)            # compiled DOP853
    traj = scene.run(method="dopri5")                   # compiled Dormand-Prince 5(4)
    traj = scene.run(method="rk4", n_steps=1000)        # compiled fixed-step RK4
    traj = scene.run(method="dla", h=0.01)              # discrete Lagrange-d'Alembert
    traj = scene.run(method="scipy-DOP853")             # scipy's solve_ivp, same kernels

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
from functools import cached_property

import numpy as np
import sympy as sp

from ..constraints import PRINCIPLES, System
from ..errors import ConstraintError, IntegrationError, JetnhError, PrincipleError
from . import cache as _cache
from . import codegen
from .integrators import ADAPTIVE, METHODS, STATUS_TEXT
from .integrators._common import AT_T_EVAL, ENDPOINTS, EVERY_STEP, NONFINITE, NOT_CONVERGED
from .trajectory import Trajectory

SCIPY_METHODS = ("RK45", "RK23", "DOP853", "Radau", "BDF", "LSODA")
DLA_NAMES = ("dla", "lda", "nh-midpoint")


def _name(key, what) -> str:
    if isinstance(key, sp.Symbol):
        return key.name
    if isinstance(key, str):
        return key
    raise JetnhError(f"{what} must be keyed by Symbol or by name, not {type(key).__name__} "
                     f"({key!r})")


def _float(value, what) -> float:
    try:
        v = float(value)
    except (TypeError, ValueError):
        raise JetnhError(f"{what} must be a number, got {value!r}") from None
    return v


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
        self.integrals = {str(k): sp.sympify(v) for k, v in (integrals or {}).items()}
        self.t_span = self._t_span(t_span)
        self.multipliers = codegen.multiplier_names(system, principle)
        self.params = self._params(params or {})
        self.runtime_params = tuple(_name(k, "a runtime parameter") for k in runtime_params)
        for name in self.runtime_params:
            if name not in self.params:
                raise JetnhError(f"runtime parameter {name!r} needs a value in params=")
        J = system.J
        self.coordinates = tuple(s.name for s in J.q)
        self.velocities = tuple(v.name for v in system.independent_velocities)
        self.dependent_velocities = tuple(v.name for v in system.dependent_velocities)
        self.state_names = self.coordinates + self.velocities + self.multipliers
        self.consistency_tol = consistency_tol
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
        t0, t1 = _float(t0, "t_span[0]"), _float(t1, "t_span[1]")
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
            name = _name(k, "a parameter")
            if name not in needed:
                raise JetnhError(
                    f"params has {name!r}, which is not a parameter of this system; its "
                    f"parameters are {sorted(needed) or 'none'}")
            out[name] = _float(v, f"parameter {name!r}")
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
            name = _name(k, "an initial value")
            if name not in allowed:
                raise JetnhError(
                    f"initial has {name!r}, which is not a state of this {self.principle} "
                    f"scene; the states are {', '.join(self.state_names)} (and the dependent "
                    f"velocities {', '.join(self.dependent_velocities) or 'none'})")
            given[name] = _float(v, f"initial value of {name!r}")
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

    def _dependent_velocity_values(self, given) -> dict[str, float]:
        """qdot^alpha = phi^alpha at the initial state, by sympy with numbers (small)."""
        sys_ = self.system
        if not sys_.k:
            return {}
        J = sys_.J
        sub = {J.t: sp.Float(self.t_span[0])}
        by_name = {s.name: s for s in J.q + J.qd}
        for name, v in given.items():
            if name in by_name:
                sub[by_name[name]] = sp.Float(v)
        for s in sys_.parameters:
            sub[s] = sp.Float(self.params[s.name])
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

    def compile(self) -> "Scene":
        """Build (or load) the kernels now rather than at the first run."""
        self.kernels
        return self

    @property
    def p(self) -> np.ndarray:
        return np.array([self.params[n] for n in self.runtime_params], dtype=float)

    # ------------------------------------------------------------------ run
    def run(self, rtol=1e-9, atol=1e-12, t_eval=None, method="dop853", *, backend=None,
            save="steps", first_step=None, max_step=np.inf, max_steps=10_000_000,
            n_steps=None, h=None, t_span=None, y0=None, params=None, newton_tol=1e-13,
            max_newton=50) -> Trajectory:
        """Integrate and return a ``Trajectory``.

        ``method``: "dop853" (default), "dopri5" (alias "RK45"), "rk4" (fixed step: give
        ``n_steps`` or ``h``), "dla" (the structure-preserving discrete
        Lagrange-d'Alembert midpoint integrator, Chetaev only, fixed step, Newton tolerance
        ``newton_tol``), or "scipy-<M>" for scipy's ``solve_ivp(method=M)`` on the
        same compiled right-hand side (also ``backend="scipy"``).  ``t_eval``: output
        times (dense output); else every accepted step, or the two ends with
        ``save="final"``.  ``atol`` may be a scalar or one value per state.
        NaN or infinity stops with an ``IntegrationError`` naming the time and state.
        """
        t0, t1 = self._t_span(t_span) if t_span is not None else self.t_span
        y_init = self.y0 if y0 is None else np.ascontiguousarray(y0, dtype=float)
        p = self.p if params is None else np.ascontiguousarray(params, dtype=float)
        name = str(method)
        if backend == "scipy" or name.lower().startswith("scipy"):
            m = name.split("-", 1)[1] if "-" in name else name
            m = {"dop853": "DOP853", "dopri5": "RK45", "rk45": "RK45"}.get(m.lower(), m)
            return self._run_scipy(m, rtol, atol, t_eval, t0, t1, y_init, p, first_step,
                                   max_step)
        if backend not in (None, "numba"):
            raise JetnhError(f"unknown backend {backend!r}; choose 'numba' or 'scipy'")
        key = name.lower()
        if key in DLA_NAMES:
            return self._run_dla(t0, t1, y_init, y0 is None, p, n_steps, h, save, newton_tol,
                                 max_newton)
        if key not in METHODS:
            raise JetnhError(
                f"unknown method {method!r}; choose one of {sorted(set(METHODS))} or "
                f"scipy-<{'|'.join(SCIPY_METHODS)}>")
        method = METHODS[key]
        kern = self.kernels
        solve = kern.integrator(method)
        n = y_init.shape[0]
        if save not in ("steps", "final"):
            raise JetnhError(f"save must be 'steps' or 'final', not {save!r}")
        te = np.zeros(0)
        if method in ADAPTIVE:
            mode = EVERY_STEP if save == "steps" else ENDPOINTS
            if t_eval is not None:
                te = np.ascontiguousarray(t_eval, dtype=float)
                self._check_t_eval(te, t0, t1)
                mode = AT_T_EVAL
            atol_v = np.ascontiguousarray(np.broadcast_to(np.asarray(atol, dtype=float), (n,)))
            tic = time.perf_counter()
            status, ts, ys, n_out, stats, t_last, y_last = solve(
                kern.rhs_c, t0, t1, y_init, p, float(rtol), atol_v,
                float(first_step or 0.0), float(max_step), int(max_steps), te, mode)
            wall = time.perf_counter() - tic
        else:
            if t_eval is not None:
                raise JetnhError("rk4 is a fixed-step method without dense output; pass "
                                 "n_steps or h and read every step, or use dop853 with t_eval")
            if n_steps is None:
                if h is None:
                    raise JetnhError("rk4 needs n_steps= or h=")
                n_steps = max(1, int(round(abs(t1 - t0) / float(h))))
            mode = EVERY_STEP if save == "steps" else ENDPOINTS
            tic = time.perf_counter()
            status, ts, ys, n_out, stats, t_last, y_last = solve(
                kern.rhs_c, t0, t1, y_init, p, int(n_steps), mode)
            wall = time.perf_counter() - tic
        if status == NONFINITE:
            self._raise_nonfinite(method, t_last, y_last)
        return Trajectory(self, ts[:n_out], ys[:n_out], p, method=method, status=int(status),
                          stop_reason=STATUS_TEXT[int(status)], steps=int(stats[0]),
                          rejected=int(stats[1]), nfev=int(stats[2]), wall_time=wall,
                          kernels=kern, projected=self.projected)

    @property
    def dla_kernels(self):
        """Kernels of the discrete Lagrange-d'Alembert step (``codegen.generate_dla``)."""
        compiled_params = {k: v for k, v in self.params.items()
                           if k not in self.runtime_params}
        key = codegen.symbolic_key(self.system, "chetaev", compiled_params,
                                   self.runtime_params, extra="dla")
        return _cache.load(key, lambda: codegen.generate_dla(
            self.system, compiled_params, self.runtime_params, key=key),
            persistent=self.cache)

    def _run_dla(self, t0, t1, y_init, default_y0, p, n_steps, h, save, tol, max_iter):
        from .integrators import dla

        if self.principle != "chetaev":
            raise PrincipleError(
                "the discrete Lagrange-d'Alembert integrator discretizes Chetaev "
                f"(Lagrange-d'Alembert) dynamics, not {self.principle}; use dop853")
        if n_steps is None:
            if h is None:
                raise JetnhError("dla is a fixed-step method: give n_steps= or h=")
            n_steps = max(1, int(round(abs(t1 - t0) / float(h))))
        J = self.system.J
        n, k = J.n, self.system.k
        q0 = np.ascontiguousarray(y_init[:n])
        if default_y0:
            v0 = np.array([self.initial[v.name] for v in J.qd])
        else:
            aux = np.empty(self.kernels.layout.n_aux)
            self.kernels.aux(t0, y_init, p, aux)
            vals = dict(zip(self.velocities, y_init[n:]))
            vals.update(zip(self.dependent_velocities, aux[:k]))
            v0 = np.array([vals[v.name] for v in J.qd])
        kern = self.dla_kernels
        solve = dla.solver()
        mode = EVERY_STEP if save == "steps" else ENDPOINTS
        tic = time.perf_counter()
        status, ts, rows, n_out, stats, t_last, y_last = solve(
            kern.step_residual, kern.momentum, kern.legendre, kern.nodal, t0, t1, q0,
            np.ascontiguousarray(v0, dtype=float), p, int(n_steps), k, float(tol),
            int(max_iter), mode)
        wall = time.perf_counter() - tic
        if status == NONFINITE:
            self._raise_nonfinite("dla", t_last, y_last[:n])
        if status == NOT_CONVERGED:
            raise IntegrationError(
                f"dla: Newton's method did not converge in the step from t = {t_last:.17g} "
                f"(h = {(t1 - t0) / n_steps:.3g}); take a smaller step, or the discrete "
                "constraint has no nearby solution there")
        rows = rows[:n_out]
        ind = [J.q.index(self.system.J.split(J.jet(s, 1))[0]) for s in self.system.independent]
        ys = np.ascontiguousarray(np.hstack([rows[:, :n], rows[:, [n + i for i in ind]]]))
        own = {"velocities": {v.name: rows[:, n + i] for i, v in enumerate(J.qd)},
               "residual": rows[:, 2 * n:2 * n + k], "energy": rows[:, 2 * n + k]}
        return Trajectory(self, ts[:n_out], ys, p, method="dla", status=int(status),
                          stop_reason=STATUS_TEXT[int(status)], steps=int(stats[0]),
                          rejected=0, nfev=int(stats[1]), wall_time=wall, kernels=kern,
                          projected=self.projected, own=own)

    @staticmethod
    def _check_t_eval(te, t0, t1):
        lo, hi = min(t0, t1), max(t0, t1)
        if te.ndim != 1:
            raise JetnhError("t_eval must be a 1-d array of times")
        if te.size and (te.min() < lo or te.max() > hi):
            raise JetnhError(f"t_eval must lie within t_span = ({t0}, {t1})")
        d = np.diff(te) * (1 if t1 >= t0 else -1)
        if np.any(d < 0):
            raise JetnhError("t_eval must be sorted in the direction of integration")

    def _raise_nonfinite(self, method, t, y):
        state = ", ".join(f"{n} = {v:.17g}" for n, v in zip(self.state_names, y))
        raise IntegrationError(
            f"{method}: the right-hand side or the state became NaN or infinite in the step "
            f"from t = {t:.17g}; state there: {state}. The equations are singular there "
            "(a vanishing denominator of the dependent velocities or of the reduced mass "
            "matrix), or the solution blows up")

    def _run_scipy(self, method, rtol, atol, t_eval, t0, t1, y_init, p, first_step,
                   max_step) -> Trajectory:
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

        kw = {}
        if first_step:
            kw["first_step"] = first_step
        tic = time.perf_counter()
        sol = solve_ivp(fun, (t0, t1), y_init, method=method, t_eval=t_eval, rtol=rtol,
                        atol=atol, max_step=max_step, **kw)
        wall = time.perf_counter() - tic
        ys = np.ascontiguousarray(sol.y.T)
        if ys.size and not np.all(np.isfinite(ys)):
            bad = int(np.argmax(~np.all(np.isfinite(ys), axis=1)))
            i = max(bad - 1, 0)
            self._raise_nonfinite(f"scipy-{method}", sol.t[i], ys[i])
        return Trajectory(self, sol.t, ys, p, method=f"scipy-{method}",
                          status=0 if sol.status == 0 else 2, stop_reason=sol.message,
                          steps=None, rejected=None, nfev=int(sol.nfev), wall_time=wall,
                          kernels=kern, projected=self.projected)

    def __repr__(self):
        return (f"Scene({self.principle}, states={list(self.state_names)}, "
                f"t_span={self.t_span})")
