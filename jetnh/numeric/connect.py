"""The two-point problem of the action principle: which motion joins two configurations?

``connect(system, principle, start, end, t_span, params, guess)`` finds a motion of
``principle`` from the configuration ``start`` at t0 to ``end`` at t1 (``end`` may name
only some coordinates) by shooting on the initial unknowns:

- vakonomic and Hoelder (the stationary composite action with fixed endpoints): the
  independent velocities and the multipliers at t0, n unknowns for the n coordinates
  (for L kinetic and f linear the motions are sub-Riemannian geodesics);
- Chetaev and Suslov: the independent velocities alone (m = n - k unknowns; Suslov's
  multipliers keep their guessed values), so an ``end`` naming all n coordinates is
  overdetermined: solved in the least-squares sense, and refused with the best answer
  and its residual (``ConnectError.best``) when the end is not reached.

The shooting map's Jacobian is the sensitivity matrix of the run
(``scene.run(sensitivities=True)``: the variational equations, compiled from the
derivation), never finite differences.  The search is Levenberg-Marquardt in unknowns
scaled by the Jacobian's column norms, each step from the singular value decomposition
with a rank cut-off (``rcond``): a rank-deficient Jacobian (a degenerate endpoint with a
whole family of solutions, such as the circles of the Heisenberg group through a point of
its z-axis) gives the minimum-norm step; the damping adapts to the ratio of the actual to
the predicted decrease, so the search neither diverges far from the guess nor loses
Newton's quadratic convergence near a solution.  When it fails from the guess,
continuation in the endpoint follows ``end(s) = q(t1; guess) + s (end - q(t1; guess))``
from s = 0 (solved by the guess) to 1 with adaptive steps.  Iterations and continuation
steps have budgets; where they stop, ``ConnectError`` says so.

Verdicts on the answer:

- ``conjugate_times``: the times in (t0, t1] where the map from the initial unknowns to
  the configuration, ``dq(t)/du`` (a block of the sensitivity matrix: the Jacobi fields
  of the extremal), loses rank -- sign changes of its determinant located by Brent's
  method on the dense output, and t1 itself where it is rank-deficient there.  Past the
  first, the extremal is no longer a local minimizer of the action.
- ``normal``: False when the endpoint map of the constraint system (the kinematic
  control system qdot^mu = u^mu, qdot^alpha = phi^alpha(t, q, u)) loses rank along the
  path, i.e. its controllability Gramian ``W' = A W + W A^T + B B^T`` (A, B the partial
  derivatives of the constraint system along the path, from the graph) is singular: the
  path is then an abnormal extremal (the multiplier rule holds with lambda_0 = 0), which
  a small residual does not make normal.
- ``cost``: the action ``int L dt`` along the answer, by 5-point Gauss-Legendre on every
  step of the dense output.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from functools import cached_property
from types import MappingProxyType

import numpy as np

from ..errors import ConnectError, JetnhError
from ..mechanics import principles
from ..mechanics.system import System
from . import arguments, codegen, methods
from .trajectory import Trajectory

#: the principles whose multipliers are unknowns of the two-point problem
VARIATIONAL = ("vakonomic", "holder")
#: Levenberg-Marquardt iterations per continuation step (at most ``max_iter``)
STEP_ITER = 20
#: steps a shooting run may take (a run that needs more counts as failed)
MAX_STEPS = 20_000


@dataclass(frozen=True)
class Connection:
    """A motion of ``principle`` joining two configurations (``connect``).

    The verdicts ``cost``, ``normal``, ``gramian_ratio`` and ``conjugate_times`` are
    computed on first access (one more run, sampled on the dense output) and then kept.
    """

    trajectory: Trajectory           # from start at t0 to (near) end at t1
    initial: MappingProxyType        # the full initial state found (name -> value)
    residual: float                  # max |q(t1) - end| over the named coordinates
    principle: str
    unknowns: tuple                  # names of the shooting unknowns
    rank: int                        # rank of the shooting Jacobian at the answer
    singular_values: tuple           # of the shooting Jacobian at the answer
    iterations: int                  # Levenberg-Marquardt iterations (all steps)
    _columns: tuple = field(repr=False, compare=False)     # the unknowns' states
    _rcond: float = field(repr=False, compare=False)
    _run: MappingProxyType = field(repr=False, compare=False)   # rtol, atol, method

    @cached_property
    def _samples(self):
        tr = self.trajectory
        return _Samples(tr, self._run["rtol"], self._run["atol"], self._run["method"],
                        tr.y[0])

    @cached_property
    def cost(self) -> float:
        """The action int L dt along the motion (``action``)."""
        return action(self.trajectory, self._samples)

    @cached_property
    def gramian_ratio(self) -> float:
        """Smallest / largest eigenvalue of the constraint system's controllability
        Gramian along the motion (``gramian_ratio``)."""
        return gramian_ratio(self.trajectory, self._samples)

    @property
    def normal(self) -> bool:
        """False: an abnormal extremal (the constraint system's endpoint map loses rank
        along the motion: ``gramian_ratio`` below ``GRAMIAN_RCOND``)."""
        return bool(self.gramian_ratio > GRAMIAN_RCOND)

    @cached_property
    def conjugate_times(self) -> tuple:
        """The times in (t0, t1] where dq/du loses rank (``conjugate_times``)."""
        return conjugate_times(self.trajectory, list(self._columns), self._samples,
                               self._rcond)

    def __repr__(self):
        return (f"Connection({self.principle}: cost {self.cost:.12g}, residual "
                f"{self.residual:.2e}, normal={self.normal}, conjugate_times="
                f"{tuple(round(t, 10) for t in self.conjugate_times)}, initial="
                f"{dict(self.initial)})")


def connect(system, principle, start, end, t_span, params=None, guess=None, *,
            tol=1e-9, rtol=1e-11, atol=1e-12, max_iter=100, max_continuation=64,
            rcond=1e-9, method="dop853") -> Connection:
    """The motion of ``principle`` from ``start`` (every coordinate) at t0 to ``end``
    (some or all coordinates) at t1, as a ``Connection`` (module docstring).

    Parameters
    ----------
    system : jetnh.System
        The constrained system.
    principle : str
        "vakonomic" or "holder" (the unknowns: independent velocities and multipliers
        at t0), "chetaev" or "suslov" (the independent velocities alone).
    start : dict
        Every coordinate at t0, keyed by Symbol or name.
    end : dict
        Some or all coordinates at t1; Chetaev and Suslov reach at most as many as
        there are independent velocities (otherwise ``ConnectError`` with the
        least-squares answer in ``.best``).
    t_span : tuple of float
        ``(t0, t1)``, of nonzero length (t1 < t0 runs backwards).
    params : dict, optional
        Parameter values; the system's defaults otherwise.
    guess : dict or sequence, optional
        The initial unknowns: a dict by name, or a sequence in the order of
        ``Connection.unknowns`` (the independent velocities, then for vakonomic and
        Hoelder the multipliers; Suslov's multipliers may be given too and are kept).
        Default: the straight-line velocities and zero multipliers, moved off runs
        that stop before t1 or start rank-deficient.
    tol : float, default 1e-9
        The largest accepted endpoint error (max norm, relative to 1 + |end|).
    rtol, atol : float, default 1e-11, 1e-12
        The integration's tolerances.
    max_iter : int, default 100
        Levenberg-Marquardt iterations (one run each) from the guess; each
        continuation step takes at most ``min(max_iter, STEP_ITER)`` (20).
    max_continuation : int, default 64
        Steps of the continuation in the endpoint (after a failed first search).
    rcond : float, default 1e-9
        The relative cut-off of singular values: the rank of the shooting Jacobian.
    method : {"dop853", "dopri5"}, default "dop853"
        The integrator (explicit, with dense output).

    Returns
    -------
    Connection
        The motion, its initial state, residual and rank; its verdicts (``cost``,
        ``normal``, ``conjugate_times``) on first access.

    Raises
    ------
    ConnectError
        The end is not reached within the budgets (the message says where the search
        stopped and what the motions reach; ``.best`` is the closest motion found).
    JetnhError
        Bad input: an unknown coordinate, a span of zero length, a guess of the wrong
        shape.
    """
    from .scene import Scene

    if not isinstance(system, System):
        raise JetnhError(f"connect needs a jetnh System, got {type(system).__name__}")
    principle = principles.canonical(principle)
    t0, t1 = Scene._t_span(t_span)
    if t1 == t0:
        raise JetnhError(f"t_span {t_span!r} has zero length: no motion joins two "
                         "configurations in no time; give t1 != t0")
    m = methods.method(method)
    if m.solver is not methods.Solver.EXPLICIT or not m.dense:     # dop853, dopri5
        raise JetnhError(f"connect integrates with 'dop853' or 'dopri5' (dense output), "
                         f"not {method!r}")
    tol = arguments.positive(tol, "tol")
    max_iter = arguments.count(max_iter, "max_iter", limit=10_000)
    max_continuation = arguments.count(max_continuation, "max_continuation", limit=100_000)
    coords = tuple(s.name for s in system.J.q)
    q0 = _configuration(start, coords, "start", complete=True)
    q1 = _configuration(end, coords, "end", complete=False)
    # a scene at the start with placeholder unknowns (the runs replace them)
    velocities = tuple(v.name for v in system.independent_velocities)
    mults = codegen.multiplier_names(system, principle)
    unknowns = velocities + (mults if principle in VARIATIONAL else ())
    fixed = {} if principle in VARIATIONAL else {m: 0.0 for m in mults}
    u0, fixed = _guess(guess, unknowns, fixed, system, q0, q1, t1 - t0)
    scene = _scene(system, principle, params, {**q0, **dict(zip(unknowns, u0)), **fixed},
                   (t0, t1))
    shooter = _Shooter(scene, q0, q1, unknowns, fixed, rtol, atol, method, rcond)
    if guess is None:
        u0 = shooter.regular_start(u0, q0, q1, t1 - t0, len(velocities))
    u, iterations = shooter.solve(u0, tol, max_iter, max_continuation)
    return shooter.connection(u, iterations, tol)


# ---------------------------------------------------------------------- input
#: (id(system), principle, params, t_span) -> (system, Scene): a scene's kernel keys
#: take milliseconds to compute, so repeated problems on one system reuse its scene (the
#: runs give every initial value; the scene's own are those of the first problem)
_SCENES: dict = {}


def _scene(system, principle, params, initial, t_span):
    from .scene import Scene

    try:
        key = (id(system), principle, None if params is None else tuple(sorted(
            (arguments.name_of(k, "a parameter"), float(v)) for k, v in params.items())),
            t_span)
    except (AttributeError, TypeError, ValueError, JetnhError):
        key = None                       # Scene says what is wrong with params
    hit = _SCENES.get(key)
    if hit is not None and hit[0] is system:
        return hit[1]
    scene = Scene(system, principle, params=params, initial=initial, t_span=t_span)
    if key is not None:
        if len(_SCENES) >= 16:
            _SCENES.clear()
        _SCENES[key] = (system, scene)
    return scene


def _configuration(values, coords, what, complete) -> dict[str, float]:
    if not hasattr(values, "items"):
        raise JetnhError(f"{what} must be a dict of coordinate values keyed by Symbol or "
                         f"name, got a {type(values).__name__}")
    out = {}
    for k, v in values.items():
        name = arguments.name_of(k, f"a coordinate of {what}")
        if name not in coords:
            raise JetnhError(f"{what} has {name!r}, which is not a coordinate of this "
                             f"system; its coordinates are {', '.join(coords)}")
        out[name] = arguments.real(v, f"{what}[{name!r}]")
        if not np.isfinite(out[name]):
            raise JetnhError(f"{what}[{name!r}] is {out[name]}; give a finite value")
    missing = [c for c in coords if c not in out]
    if complete and missing:
        raise JetnhError(f"start must give every coordinate; missing {', '.join(missing)}")
    if not out:
        raise JetnhError(f"{what} names no coordinate; give the end configuration "
                         f"(some of {', '.join(coords)})")
    return out


def _guess(guess, unknowns, fixed, system, q0, q1, T):
    """The starting unknowns (and Suslov's fixed multipliers) from ``guess`` or the
    straight line."""
    if guess is None:
        u = []
        for v in unknowns:
            base = next((system.J.split(s)[0].name for s in system.independent_velocities
                         if s.name == v), None)
            u.append((q1[base] - q0[base]) / T if base in q1 else 0.0)
        return np.array(u, dtype=float), fixed
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


# ---------------------------------------------------------------------- shooting
class _Shooter:
    """Runs of one scene from the start with the unknowns ``u``: the endpoint residual
    and its Jacobian from the sensitivities."""

    def __init__(self, scene, q0, q1, unknowns, fixed, rtol, atol, method, rcond):
        self.scene, self.unknowns, self.fixed = scene, unknowns, fixed
        names = scene.state_names
        self.rows = [names.index(c) for c in q1]
        self.target = np.array(list(q1.values()))
        self.cols = [names.index(u) for u in unknowns]
        given = {**q0, **fixed}
        self.y0 = np.array([given.get(n, 0.0) for n in names])
        self.rtol, self.atol, self.method, self.rcond = rtol, atol, method, rcond
        self.end_names = tuple(q1)
        self.seen: dict = {}

    def state(self, u) -> np.ndarray:
        y = self.y0.copy()
        y[self.cols] = u
        return y

    def endpoint(self, u):
        """``(q_named(t1), dq_named(t1)/du, the run)``, or None where the run fails
        (the last few kept: the guess and the answer are evaluated more than once)."""
        key = np.asarray(u, dtype=float).tobytes()
        if key not in self.seen:
            if len(self.seen) > 8:
                self.seen.clear()
            self.seen[key] = self._endpoint(u)
        return self.seen[key]

    def _endpoint(self, u):
        tr = self.run(u)
        if tr is None:
            return None
        S = tr.sensitivities[-1]
        return tr.y[-1, self.rows], S[np.ix_(self.rows, self.cols)], tr

    def run(self, u):
        """The run from the start with the unknowns ``u`` (every step, with
        sensitivities), or None where it fails before t1 (or takes more than
        ``MAX_STEPS`` steps: a wild trial of the search must not take minutes)."""
        try:
            tr = self.scene.run(rtol=self.rtol, atol=self.atol, method=self.method,
                                y0=self.state(u), sensitivities=True, max_steps=MAX_STEPS)
        except JetnhError:
            return None
        return tr if tr.status == 0 and np.all(np.isfinite(tr.y[-1])) else None

    def regular_start(self, u0, q0, q1, T, n_velocities):
        """The default guess, moved off a point where the run stops before t1 (a speed
        that falls to a singular zero) or where the shooting Jacobian is rank-deficient
        (zero velocities, a straight line along an abnormal direction): by a fixed
        pattern of the size of the straight-line velocities, then with the velocities
        doubled and quadrupled; 12 tries, the first regular one kept (else the first
        that reaches t1)."""
        scale = max([abs(q1[c] - q0[c]) for c in q1] + [1.0]) / abs(T)
        pattern = 0.5 * (-0.6) ** np.arange(len(u0))
        speed = np.ones(len(u0))
        reaching = None
        for k in range(12):
            speed[:n_velocities] = 2.0 ** (k // 4)
            u = speed * u0 + (scale * np.roll(pattern, k) * (k % 4) if k % 4 else 0.0)
            got = self.endpoint(u)
            if got is not None:
                s = np.linalg.svd(got[1], compute_uv=False)
                if s.size and s[0] > 0 and s[-1] > 1e-6 * s[0]:
                    return u
                reaching = u if reaching is None else reaching
        return u0 if reaching is None else reaching

    def svd(self, Jm):
        """The singular value decomposition of the shooting Jacobian with its numerical
        rank (relative cut-off ``rcond``)."""
        U, s, Vt = np.linalg.svd(Jm, full_matrices=False)
        r = int(np.sum(s > self.rcond * s[0])) if s.size and s[0] > 0 else 0
        return U[:, :r], s[:r], Vt[:r]

    def newton(self, u, target, tol, max_iter):
        """Levenberg-Marquardt on q(t1; u) = target, in unknowns scaled by the largest
        column norms of the Jacobian seen so far (More's scaling: the multipliers'
        columns are often orders of magnitude smaller than the velocities'): the step
        ``-D^-1 V diag(s / (s^2 + mu)) U^T F`` of the truncated SVD of ``J D^-1``
        (mu -> 0: the minimum-norm Gauss-Newton step, quadratic convergence near a
        solution; mu large: a short step down the gradient), mu adapted by the ratio of
        the actual to the predicted decrease (Nielsen's rule), a run that fails before
        t1 counted as no decrease.  Returns ``(u, converged, iterations)``."""
        got = self.endpoint(u)
        if got is None:
            return u, False, 0
        scale = 1.0 + np.abs(target)
        q, Jm, _ = got
        F = q - target
        d = np.ones(len(u))
        mu = nu = None
        for it in range(1, max_iter + 1):
            if np.max(np.abs(F) / scale) <= tol:
                return u, True, it - 1
            # a column far below the largest (an unknown the end does not feel) keeps
            # a floor: its scaled column is then cut by rcond instead of blown up
            norms = np.linalg.norm(Jm, axis=0)
            norms = np.maximum(norms, 1e-6 * norms.max()) if norms.max() > 0 else 1.0
            d = np.maximum(d, norms) if it > 1 else norms
            U, s, Vt = self.svd(Jm / d)
            if not s.size:
                return u, False, it
            if mu is None:
                mu, nu = 1e-6 * s[0] ** 2, 2.0
            du = -(Vt.T @ (s * (U.T @ F) / (s**2 + mu))) / d
            # at most the size of the unknowns (and 1): stay on the branch of solutions
            # the search starts near instead of jumping to a far one
            du /= max(1.0, np.linalg.norm(du) / max(1.0, np.linalg.norm(u)))
            trial = self.endpoint(u + du)
            linear = F + Jm @ du
            predicted = F @ F - linear @ linear
            rho = -1.0
            if trial is not None and predicted > 0:
                F_new = trial[0] - target
                rho = (F @ F - F_new @ F_new) / predicted
            if rho > 0:
                u, (q, Jm, _), F = u + du, trial, F_new
                mu *= max(1.0 / 3.0, 1.0 - (2.0 * rho - 1.0) ** 3)
                nu = 2.0
            else:
                if self.least_squares_point(F, Jm):
                    raise self.unreachable(u)
                mu *= nu
                nu *= 2.0
                if mu > 1e20 * s[0] ** 2:          # no step of any length decreases |F|
                    return u, False, it
        return u, bool(np.max(np.abs(F) / scale) <= tol), max_iter

    def solve(self, u0, tol, max_iter, max_continuation):
        """Newton from ``u0``, else continuation in the endpoint from q(t1; u0)."""
        u, ok, its = self.newton(u0, self.target, tol, max_iter)
        if ok:
            return u, its
        got = self.endpoint(u0)
        if got is None:
            raise ConnectError(
                f"the {self.scene.principle} run from the start with the guess "
                f"{dict(zip(self.unknowns, u0.tolist()))} fails before t1 (a singular "
                "configuration or a non-finite state); give another guess")
        first = got[0]
        total, s, ds, u = its, 0.0, 0.25, u0
        for _ in range(max_continuation):
            s_try = min(1.0, s + ds)
            target = first + s_try * (self.target - first)
            # a continuation step starts near its solution: a short budget, so that an
            # unreachable end fails in seconds
            v, ok, k = self.newton(u, target, tol if s_try == 1.0 else max(tol, 1e-6),
                                   min(max_iter, STEP_ITER))
            total += k
            if ok:
                s, u = s_try, v
                if s == 1.0:
                    return u, total
                ds = min(2.0 * ds, 1.0 - s)
            else:
                ds *= 0.5
                if ds < 1e-4:
                    break
        best = self._best(u)
        raise ConnectError(
            f"connect did not reach the end: continuation in the endpoint stopped at "
            f"s = {s:.6g} of 1 (step {ds:.3g}, {total} iterations in all); the closest "
            f"motion ends {best.residual:.3g} away from end"
            + self._reachability(u) + "; try another guess, a shorter span or an end "
            "nearer the start (ConnectError.best is that motion)", best)

    def least_squares_point(self, F, Jm) -> bool:
        """Whether ``u`` is a stationary point of |F|^2 with F != 0 (J^T F = 0): more
        conditions than the motions can meet there."""
        g = np.linalg.norm(Jm.T @ F)
        return bool(Jm.shape[0] > Jm.shape[1]
                    and g <= 1e-7 * max(np.linalg.norm(Jm), 1e-300) * np.linalg.norm(F))

    def unreachable(self, u) -> ConnectError:
        best = self._best(u)
        return ConnectError(
            f"the {self.scene.principle} motions from the start do not reach end in this "
            f"time: the least-squares answer ends "
            f"{'?' if best is None else format(best.residual, '.3g')} away"
            + self._reachability(u) + " (ConnectError.best is that answer)", best)

    def _reachability(self, u) -> str:
        got = self.endpoint(u)
        if got is None:
            return ""
        s = np.linalg.svd(got[1], compute_uv=False)
        r = int(np.sum(s > self.rcond * s[0])) if s.size and s[0] > 0 else 0
        if len(self.rows) > r:
            return (f" (the {self.scene.principle} motions from the start reach a "
                    f"{r}-dimensional set of the {len(self.rows)} named coordinates near "
                    f"there: {len(self.unknowns)} unknowns "
                    f"{', '.join(self.unknowns)}; name at most {r} coordinates in end)")
        return ""

    def _best(self, u):
        try:
            return self.connection(u, 0, None)
        except JetnhError:
            return None

    # ------------------------------------------------------------------ the answer
    def connection(self, u, iterations, tol) -> Connection:
        scene = self.scene
        got = self.endpoint(u)
        if got is None:
            raise ConnectError(f"the motion found stops before t1: "
                               f"{scene.run(y0=self.state(u)).stop_reason}")
        tr = got[2]
        q = tr.y[-1, self.rows]
        residual = float(np.max(np.abs(q - self.target)))
        _, s, _ = self.svd(tr.sensitivities[-1][np.ix_(self.rows, self.cols)])
        full = np.linalg.svd(tr.sensitivities[-1][np.ix_(self.rows, self.cols)],
                             compute_uv=False)
        start = list(tr.y[0]) + [float(tr[d][0]) for d in scene.dependent_velocities]
        best = Connection(
            trajectory=tr,
            initial=MappingProxyType({n: float(v) for n, v in zip(
                scene.state_names + scene.dependent_velocities, start)}),
            residual=residual, principle=scene.principle, unknowns=self.unknowns,
            rank=len(s), singular_values=tuple(full.tolist()), iterations=iterations,
            _columns=tuple(self.cols), _rcond=self.rcond, _run=MappingProxyType(
                {"rtol": self.rtol, "atol": self.atol, "method": self.method}))
        if tol is not None and np.max(np.abs(q - self.target)
                                      / (1 + np.abs(self.target))) > tol:
            raise ConnectError(
                f"the {scene.principle} motion found ends {residual:.3g} away from end"
                + self._reachability(u), best)
        return best


# ---------------------------------------------------------------------- verdicts
#: smallest / largest eigenvalue of the controllability Gramian below which the path is
#: abnormal
GRAMIAN_RCOND = 1e-9
#: |det| of dq/du with normalized columns below which it has no sign (rounding level)
DET_ZERO = 1e-10
_GAUSS_X, _GAUSS_W = np.polynomial.legendre.leggauss(5)


def _dense_states(tr, times, full=False):
    from .dense import evaluate

    return evaluate(tr, times, full=full)


class _Samples:
    """The states and sensitivities of a trajectory at the times its verdicts need --
    the 5 Gauss-Legendre nodes of every step (``gauss``) and ``GRID`` + 1 equal-spaced
    times (``grid``) -- from one run with these times as ``t_eval`` (dense output: the
    values ``Trajectory.at`` gives, without re-taking each step from Python)."""

    GRID = 400

    def __init__(self, tr, rtol, atol, method, y0):
        t = tr.t
        a, b = t[:-1], t[1:]
        self.half = 0.5 * (b - a)
        self.gauss = ((0.5 * (a + b))[:, None] + self.half[:, None] * _GAUSS_X[None, :])
        self.grid = np.linspace(t[0], t[-1], self.GRID + 1)
        times = np.concatenate([self.gauss.ravel(), self.grid])
        order = np.argsort(times, kind="stable")
        run = tr.scene.run(rtol=rtol, atol=atol, method=method, y0=y0, t_eval=times[order],
                           sensitivities=True)
        if run.status != 0 or len(run.t) != times.size:
            raise ConnectError(f"the motion found could not be sampled: {run.stop_reason}")
        ys = np.empty_like(run.y)
        S = np.empty_like(run.sensitivities)
        ys[order], S[order] = run.y, run.sensitivities
        k = self.gauss.size
        self.gauss_y, self.grid_y, self.grid_S = ys[:k], ys[k:], S[k:]


def action(tr, samples) -> float:
    """``int L dt`` along the trajectory: 5-point Gauss-Legendre on every step of its
    dense output (``_Samples``), L evaluated on the graph (dependent velocities by the
    aux kernel)."""
    times = samples.gauss
    L = _lagrangian(tr.scene, times.ravel(), samples.gauss_y).reshape(times.shape)
    return float(np.sum(L * _GAUSS_W[None, :] * samples.half[:, None]))


def _point(scene, times, ys) -> dict:
    """Symbol -> values of t, q, every velocity and the parameters at the rows ``ys``."""
    system = scene.system
    J = system.J
    kern = scene.kernels
    aux = np.empty((ys.shape[0], kern.layout.n_aux))
    kern.aux_rows(np.ascontiguousarray(times), np.ascontiguousarray(ys), scene.p, aux)
    col = {n: i for i, n in enumerate(scene.state_names)}
    point = {J.t: times}
    for s in J.q:
        point[s] = ys[:, col[s.name]]
    for v in system.independent_velocities:
        point[v] = ys[:, col[v.name]]
    for a, v in enumerate(system.dependent_velocities):
        point[v] = aux[:, a]
    for s in system.parameters:
        point[s] = scene.params[s.name]
    return point


def _lagrangian(scene, times, ys) -> np.ndarray:
    from ..algebra import dag

    (L,) = dag.evaluate_numpy([scene.system.L], _point(scene, times, ys))
    return np.broadcast_to(L, times.shape)


#: system id -> (system, [d phi/dq..., d phi/du...]) for ``gramian_ratio``
_DERIVATIVES: dict = {}


def gramian_ratio(tr, samples) -> float:
    """Smallest over largest eigenvalue of the controllability Gramian of the constraint
    system (qdot^mu = u^mu, qdot^alpha = phi^alpha(t, q, u)) linearized along ``tr``,
    ``W = int Phi(t1, s) B B^T Phi(t1, s)^T ds`` (A = d qdot/dq, B = d qdot/du from the
    graph on the dense output; the transition matrix Phi by RK4 propagators of ``steps``
    equal steps, ``_Samples.GRID / 2`` of them, the integral by Simpson's rule on their
    nodes).  Zero: the endpoint
    map loses rank along the path (an abnormal extremal)."""
    from ..algebra import dag

    scene = tr.scene
    system = scene.system
    J = system.J
    n, us = len(J.q), system.independent_velocities
    if not system.k:
        return 1.0
    steps = samples.GRID // 2
    phis = [system.phi[v] for v in system.dependent_velocities]
    derivatives = _DERIVATIVES.get(id(system))
    if derivatives is None or derivatives[0] is not system:
        derivatives = _DERIVATIVES[id(system)] = (
            system, list(dag.jacobian(phis, list(J.q))) + list(dag.jacobian(phis, list(us))))
    t0, t1 = float(tr.t[0]), float(tr.t[-1])
    times = samples.grid
    vals = dag.evaluate_numpy(derivatives[1], _point(scene, times, samples.grid_y))
    k = len(phis)
    A = np.zeros((times.size, n, n))
    B = np.zeros((times.size, n, len(us)))
    index = {s: i for i, s in enumerate(J.q)}
    dep_rows = [index[J.split(v)[0]] for v in system.dependent_velocities]
    for j, v in enumerate(us):
        B[:, index[J.split(v)[0]], j] = 1.0
    for a in range(k):
        for c in range(n):
            A[:, dep_rows[a], c] = np.broadcast_to(vals[a * n + c], times.shape)
        for c in range(len(us)):
            B[:, dep_rows[a], c] = np.broadcast_to(vals[k * n + a * len(us) + c],
                                                   times.shape)
    h = (t1 - t0) / steps
    I = np.eye(n)
    A0, Am, A1 = A[0:-1:2], A[1::2], A[2::2]
    K1 = A0
    K2 = Am @ (I + 0.5 * h * K1)
    K3 = Am @ (I + 0.5 * h * K2)
    K4 = A1 @ (I + h * K3)
    P = I + h / 6.0 * (K1 + 2 * K2 + 2 * K3 + K4)        # Phi(t_{j+1}, t_j)
    Phi = np.empty((steps + 1, n, n))                     # Phi(t_j, t0)
    Phi[0] = I
    for j in range(steps):
        Phi[j + 1] = P[j] @ Phi[j]
    G = np.linalg.solve(np.transpose(Phi, (0, 2, 1)), Phi[-1].T).transpose(0, 2, 1)
    GB = G @ B[::2]                                       # Phi(t1, s_j) B(s_j)
    w = np.full(steps + 1, 2.0)
    w[1::2] = 4.0
    w[0] = w[-1] = 1.0
    W = np.einsum("j,jam,jbm->ab", w * h / 3.0, GB, GB)
    ev = np.linalg.eigvalsh(0.5 * (W + W.T))
    return float(max(ev[0], 0.0) / ev[-1]) if ev[-1] > 0 else 0.0


def conjugate_times(tr, cols, samples, rcond=1e-9) -> tuple:
    """The times in (t0, t1] where dq(t)/du (rows: every coordinate; columns ``cols``,
    the unknowns' states) loses rank: the sign changes of its determinant (square case)
    on the equal-spaced times of ``samples``, located by Brent's method on the dense
    output; and t1 when the matrix is rank-deficient there (relative cut-off
    ``rcond``)."""
    from scipy.optimize import brentq

    n = tr.layout.n_state
    nq = len(tr.layout.coordinates)
    m = tr.sensitivities.shape[2]
    t0, t1 = float(tr.t[0]), float(tr.t[-1])
    found = []

    def block(times):
        Y = _dense_states(tr, np.atleast_1d(times), full=True)
        S = Y[:, n:].reshape(-1, n, m)
        return S[:, :nq][:, :, cols]

    if len(cols) == nq:
        def det(t):
            M = block(t)[0]
            norms = np.linalg.norm(M, axis=0)
            return np.linalg.det(M / np.where(norms > 0, norms, 1.0))

        grid = samples.grid[1:]
        M = samples.grid_S[1:, :nq][:, :, cols]
        norms = np.linalg.norm(M, axis=1, keepdims=True)
        d = np.linalg.det(M / np.where(norms > 0, norms, 1.0))
        for i in range(len(grid) - 1):
            # |det| of the normalized columns at rounding level: singular there (along a
            # whole stretch when an unknown has no effect), no sign to follow
            if max(abs(d[i]), abs(d[i + 1])) < DET_ZERO or np.sign(d[i]) == np.sign(
                    d[i + 1]):
                continue
            found.append(float(brentq(det, grid[i], grid[i + 1], xtol=1e-14, rtol=1e-14)))
    s = np.linalg.svd(tr.sensitivities[-1][:nq][:, cols], compute_uv=False)
    if s.size and (s[0] == 0 or s[-1] <= rcond * s[0] * 1e2) and len(cols) >= nq:
        found.append(t1)
    return tuple(found)
