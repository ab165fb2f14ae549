"""The two-point problem of the action principle: which motion joins two configurations?

``connect(system, principle, start, end, t_span, params, guess)`` finds a motion of
``principle`` from the configuration ``start`` at t0 to ``end`` at t1 (for Chetaev and
Suslov ``end`` may name only some coordinates) by shooting on the initial unknowns:

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
Newton's quadratic convergence near a solution.  On long or unstable spans (the guess's
run stops early or its sensitivities grow past ``GROWTH``), multiple shooting on
``segments`` equal segments comes first (the inner states are unknowns too, matched
with the segments' exact transition matrices), polished by single shooting -- or, where
single shooting cannot reach the tolerance, its segments stitched into one trajectory
(``connection.Stitched``: their sensitivities chained).  When the search fails from the
guess, the routes follow in turn (``Search.solve``): continuation in the endpoint
``end(s) = q(t1; guess) + s (end - q(t1; guess))`` from s = 0 to 1 with adaptive steps;
a collocation warm start (``collocation.warm_start``: scipy's solve_bvp on the compiled
equations and Jacobian, from the guess's run bent onto the end) polished by Newton;
continuation in T, from T / 8 (the straight-line guess rescaled) to T.  An end with
more conditions than the rank of the shooting Jacobian (overdetermined, or
rank-deficient) is continued on its best-determined conditions and checked on all at
the end, so the continuation's path never leaves the reachable set.  Iterations and
continuation steps have budgets; where they stop, ``ConnectError`` says so.

With holonomic constraints g = 0 the start (and an end naming every coordinate) must lie
on g = 0 (``complete=True`` completes the start, as ``Scene`` does); the multipliers of
g = 0 enter the equations only through their rates (inert), so they stay at 0 and are no
unknowns; the verdicts are measured on the tangent space of g = 0.  The runs carry
sensitivities and change split as ``Scene.run`` does (``numeric.atlas``), so an end
whose motion crosses the edge of the scene's chart is reached like any other;
``timeout`` bounds the search's wall-clock time.

Vakonomic and Hoelder ends may leave coordinates free: their transversality conditions
close the problem -- the coefficient of each free eta^i in the boundary term of the
composite action's variation (13), the momentum P_i = d(L + lambda f)/dqdot^i, vanishes
at t1 (``problem.transversality``, from the derivation); with holonomic constraints
g = 0, for the variations tangent to g = 0 (``problem.tangent_transversality``: the
reduced momenta P_R - G_R^T G_D^-T P_D vanish).

Verdicts on the answer:

- ``conjugate_times``: the times in (t0, t1] where the map from the initial unknowns to
  the configuration, ``dq(t)/du`` (a block of the sensitivity matrix: the Jacobi fields
  of the extremal), loses rank -- sign changes of its determinant located by Brent's
  method on the dense output, and t1 itself where it is rank-deficient there.  Rank is
  judged on the fields scaled as a subspace and by columns (``verdicts.jacobi_measure``),
  never relative to the sensitivities' size, which grows by orders of magnitude on long
  unstable spans.  Past the first, the extremal is no longer a local minimizer of the
  action: ``minimizer`` is False, and ``restarts`` look for a cheaper extremal without
  a conjugate time inside the span (``solve.least_action``; ``Connection.search`` says
  what they found).  Chetaev and Suslov (no extremals of an action): the times where
  the map from the unknowns to the named end coordinates (the two-point problem's
  endpoint map) loses rank.  None where nothing could be checked.
- ``legendre``, and in ``minimizer``: Legendre's condition, the Hessian of L + lambda f
  in the velocities on the admissible ones positive along the motion; where it has a
  negative direction the extremal is no minimizer.  Measured in the independent
  velocities and scaled to a unit diagonal, as the Gramian of ``normal``: neither
  depends on the units of the coordinates.  The verdicts are read off the
  returned trajectory's own dense output, never a new run.
- ``normal``: False when the endpoint map of the constraint system (the kinematic
  control system qdot^mu = u^mu, qdot^alpha = phi^alpha(t, q, u)) loses rank along the
  path, i.e. its controllability Gramian ``W' = A W + W A^T + B B^T`` (A, B the partial
  derivatives of the constraint system along the path, compiled from the derivation:
  ``codegen.verdicts``; the inputs weighted by L, the whole scaled to a unit diagonal)
  is singular: the path is then an abnormal extremal (the
  multiplier rule holds with lambda_0 = 0), which a small residual does not make
  normal.  Also False where the path is within its end miss of an abnormal one: the
  Gramian's gain changes by more than ``NEAR_ABNORMAL`` (10 %) along the
  minimum-energy correction of the miss (``gramian_change``: a Kantorovich number of
  order one, where the unit-free ratio of a path beside the abnormal one is of order
  one too); unchanged by the units of the coordinates.
- ``cost``: the action ``int L dt`` along the answer, by 5-point Gauss-Legendre on every
  step of the dense output.
- ``not_extremal``: under non-potential forces or dissipation (nonzero at the parameter
  values) a vakonomic or Hoelder motion is in general no extremal of ``int L dt`` (its
  first variation is ``int Q eta dt``): ``legendre`` and ``minimizer`` are None and
  this says why; ``cost`` is then only ``int L dt`` along the motion, and
  ``conjugate_times`` the folds of the map to the configuration.
"""

from __future__ import annotations

import time

from ...errors import ArgumentError, ConnectError, JetnhError
from ...mechanics import principles
from ...mechanics.system import System
from .. import arguments, interrupt, methods
from ..scene import Scene
from .connection import Connection
from .problem import (MAX_TOL, VARIATIONAL, Momenta, Unknowns, _configuration,
                      _guess, _holonomic_free, _scene, on_manifold)
from .solve import STEP_ITER, Search, least_action
from .shooting import GROWTH, MAX_SEGMENTS, MAX_STEPS, OutOfTime
from .verdicts import (GRAMIAN_RCOND, NEAR_ABNORMAL, action, conjugate_times,
                       gramian_change, gramian_ratio)

#: the most segments ``connect(segments=)`` takes: a Newton step of multiple shooting
#: solves for every segment's state at once (dense: 64 segments of a 6-state system
#: take seconds a connect)
MAX_SEGMENTS_GIVEN = 64

__all__ = ["connect", "Connection", "VARIATIONAL", "MAX_TOL", "STEP_ITER", "MAX_STEPS",
           "GROWTH", "MAX_SEGMENTS", "MAX_SEGMENTS_GIVEN", "GRAMIAN_RCOND",
           "NEAR_ABNORMAL", "action", "conjugate_times", "gramian_change", "gramian_ratio"]


#: principle names as given -> canonical names (``principles.canonical``, a few
#: microseconds a call), for the names seen
_CANONICAL: dict = {}


def _canonical(principle) -> str:
    name = _CANONICAL.get(principle) if type(principle) is str else None
    if name is None:
        name = principles.canonical(principle)
        if type(principle) is str and len(_CANONICAL) < 64:
            _CANONICAL[principle] = name
    return name


def connect(system, principle, start, end, t_span, params=None, guess=None, *,
            tol=1e-9, rtol=1e-11, atol=1e-12, max_iter=100, max_continuation=64,
            rcond=1e-9, method="dop853", segments=None, restarts=0,
            complete=False, timeout=None) -> Connection:
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
        Every coordinate at t0, keyed by Symbol or name; on the holonomic constraints
        g = 0 where the system has any (else ``ConstraintError``, or ``complete``).
    end : dict
        Vakonomic and Hoelder: some or all coordinates at t1 (the momenta of the
        free ones vanish there: their transversality conditions).  Chetaev and
        Suslov: some or all coordinates at t1; more than there are independent
        velocities only where the end is reachable (otherwise ``ConnectError`` with
        the least-squares answer in ``.best``).  With holonomic constraints g = 0: an
        end naming every coordinate must lie on g = 0; vakonomic and Hoelder ends
        that name fewer coordinates than g = 0 has dimensions close with the free
        ones' momenta projected onto its tangent space.
    t_span : tuple of float
        ``(t0, t1)`` with t1 > t0 (connect solves forwards in time).
    params : dict, optional
        Parameter values; the system's defaults otherwise.
    guess : dict or sequence, optional
        The initial unknowns: a dict by name, or a sequence in the order of
        ``Connection.unknowns`` (the independent velocities, then for vakonomic and
        Hoelder the multipliers; Suslov's multipliers may be given too and are kept).
        Default: the straight-line velocities and zero multipliers, moved off runs
        that stop before t1 or start rank-deficient.
    tol : float, default 1e-9
        The largest accepted endpoint error (max norm), relative to each named
        coordinate's scale (``shooting.own_scale``; ``Connection.relative_residual``
        is the answer's): its displacement |end - start|, at least ``SMALLEST_MOVE``
        (1e-3) times the largest displacement of the named coordinates; for one that
        returns to its start, its own excursion max |q(t) - q(t0)| along the motion
        found (in its own units); and the problem's momentum for the momenta of free
        coordinates.  Below ``MAX_TOL`` (1e-3): a looser miss is no connection.
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
    restarts : int, default 0
        Vakonomic and Hoelder: where the answer is no minimizer of the action
        (Legendre's condition fails, or a conjugate time lies inside the span), this
        many restarts from around it (``solve.least_action``); the cheapest minimizer
        is returned, else the cheapest, with ``Connection.search`` saying what was
        tried and which verdict failed.  0: the first answer as found.
    segments : int, optional
        Multiple shooting on this many equal segments of the span (the inner states
        are unknowns too, matched by their exact sensitivities; then single shooting
        polishes the answer): for long or unstable spans, where single shooting's
        sensitivities blow up.  Default: 1 where the guess's run reaches t1 with
        sensitivities below ``GROWTH`` (1e6), else one segment per factor 100 of the
        growth (2 to ``MAX_SEGMENTS``, 16); 1 is single shooting only; at most
        ``MAX_SEGMENTS_GIVEN`` (64: each Newton step is dense in the segments' unknowns).
    complete : bool, default False
        With holonomic constraints: solve ``start``'s dependent coordinates from g = 0
        (as ``Scene(complete=True)``) instead of refusing a start off it.
    timeout : float, optional
        Seconds of wall-clock time for the search: no run starts after them, and
        ``ConnectError`` says where the search was (``.best``: the closest motion
        seen).  Default: no limit but the iteration budgets.

    Returns
    -------
    Connection
        The motion, its initial state, residual and rank, its end ``conditions`` and the
        ``route`` that found it; its verdicts (``cost``, ``normal``,
        ``conjugate_times``) on first access.

    Raises
    ------
    ConnectError
        The end is not reached within the budgets or ``timeout`` (the message says
        where the search stopped and what the motions reach; ``.best`` is the closest
        motion found, None where no run reached t1).
    JetnhError
        Bad input: an unknown coordinate, a span of zero length, a guess of the wrong
        shape.
    """
    if not isinstance(system, System):
        raise JetnhError(f"connect needs a jetnh System, got {type(system).__name__}")
    principle = _canonical(principle)
    t0, t1 = Scene._t_span(t_span)
    if t1 == t0:
        raise JetnhError(f"t_span {t_span!r} has zero length: no motion joins two "
                         "configurations in no time; give t1 > t0")
    if t1 < t0:
        raise ArgumentError(f"{t_span!r} runs backwards: connect solves forwards "
                            "in time; give (t0, t1) with t1 > t0", argument="t_span")
    m = methods.method(method)
    if m.solver is not methods.Solver.EXPLICIT or not m.dense:     # dop853, dopri5
        raise JetnhError(f"connect integrates with 'dop853' or 'dopri5' (dense output), "
                         f"not {method!r}")
    tol = arguments.positive(tol, "tol")
    if tol >= MAX_TOL:
        raise ArgumentError(f"tol={tol!r} accepts an end missed by {tol:g} of its displacement: "
                            f"no connection; give tol < {MAX_TOL:g} (default 1e-9)",
                            argument="tol")
    max_iter = arguments.count(max_iter, "max_iter", limit=10_000)
    max_continuation = arguments.count(max_continuation, "max_continuation", limit=100_000)
    if segments is not None:
        segments = arguments.count(segments, "segments", limit=MAX_SEGMENTS_GIVEN)
    rcond = arguments.positive(rcond, "rcond")
    if rcond >= 1.0:
        raise ArgumentError(f"must be below 1, got {rcond!r}: a cut-off on the singular "
                            "values relative to the largest that calls every Jacobian "
                            "rank-deficient; give 0 < rcond < 1 (default 1e-9)",
                            argument="rcond")
    if timeout is not None:
        timeout = arguments.positive(timeout, "timeout")
    if not (type(restarts) is int and restarts == 0):
        restarts = arguments.count(restarts, "restarts", limit=10_000)
        if principle not in VARIATIONAL:
            raise ArgumentError(f"restarts look for the least-action extremal; {principle}"
                                " motions do not make an action stationary: leave "
                                "restarts at 0", argument="restarts")
    shape = Unknowns.of(system, principle)
    coords = shape.coords
    q0 = _configuration(start, coords, "start", complete=True)
    q1 = _configuration(end, coords, "end", complete=False)
    if system.holonomic:
        q0 = on_manifold(system, params, q0, q1, t0, t1, complete)
    unknowns = shape.unknowns
    u0, fixed = _guess(guess, unknowns, shape.fixed, shape.bases, q0, q1, t1 - t0)
    # a scene at the start with placeholder unknowns (the runs replace them)
    scene = _scene(system, principle, params,
                   lambda: {**q0, **dict(zip(unknowns, u0)), **fixed}, (t0, t1))
    free = [c for c in coords if c not in q1] if principle in VARIATIONAL else []
    if free and system.holonomic:
        free = _holonomic_free(system, q1, free)
    shooter = Search(scene, q0, q1, unknowns, fixed, rtol, atol, method, rcond,
                     momenta=Momenta(scene, free) if free else None)
    failed = None
    if timeout is not None:
        shooter.deadline = time.monotonic() + timeout
    halt = interrupt.flag()
    # the runs share one watch for Ctrl-C (``interrupt.shared``: registered once)
    with interrupt.shared(halt) as run:
        shooter.watch = (run, halt)
        try:
            for start in shooter.starts(u0, guess is None, q0, q1, t1 - t0):
                try:
                    u, iterations, stitched, route = shooter.solve(
                        start, tol, max_iter, max_continuation, segments)
                except ConnectError as e:
                    failed = failed or e      # the first start's reasons are reported
                    continue
                found = shooter.connection(u, iterations, tol, stitched, route)
                return least_action(shooter, found, tol, max_iter, restarts)
        except OutOfTime:
            shooter.deadline = None
            raise shooter.out_of_time(timeout) from None
        finally:
            shooter.watch = None
    raise failed
