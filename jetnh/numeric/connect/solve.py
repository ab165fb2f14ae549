"""The search: Levenberg-Marquardt on the shooting map, continuation in the endpoint
when it fails from the guess, and the answer (a ``Connection``) or the reason it was not
found (``ConnectError`` with the closest motion)."""

from __future__ import annotations

from types import MappingProxyType

import numpy as np

from ...errors import ConnectError, JetnhError
from . import direct
from .collocation import warm_start
from .connection import Connection, Stitched
from .levenberg import levenberg_marquardt
from .problem import VARIATIONAL
from .shooting import (Segments, Shooter, default_segments, first_values, rank, rank_of,
                       relative_miss, singular_values)

#: Levenberg-Marquardt iterations per continuation step (at most ``max_iter``)
STEP_ITER = 20
#: the first span of the continuation in T, as a fraction of T
FIRST_SPAN = 0.125
#: multiple shooting segments from the direct route's guess (``least_action``)
DIRECT_SEGMENTS = 4
#: growth max |dy(t1)/dy(t0)| of a single run above which multiple shooting's answer is
#: not polished into one run (its own integration error, amplified so, leaves the
#: motion: another run from the same start does not reach the end)
POLISH_GROWTH = 1e10
#: the ratio of the coordinates' largest end scale to a condition's (a coordinate's, a
#: transversality condition's) past which the search weighs that condition by it
#: (``Search``)
FAR = 1e3
#: the searches on to a tighter scale after one met ``end_scale`` (``Search.newton``)
OWN_ROUNDS = 3



class Search(Shooter):
    """A ``Shooter`` that solves the end conditions: q(t1; u) = end for the named
    coordinates and, with ``momenta`` (``problem.Momenta``), the transversality
    conditions P_i(t1; u) = 0 of the free ones."""

    def __init__(self, scene, q0, q1, *args, momenta=None):
        super().__init__(scene, q0, q1, *args)
        self.momenta = momenta
        scale = self.scale
        if momenta is not None:
            self.target = np.concatenate([self.target, np.zeros(len(momenta.free))])
            # the momenta's transversality conditions: relative to the problem's own
            # momentum in each free coordinate (``problem.Momenta.scale``)
            t0, t1 = scene.t_span
            scale = np.concatenate([scale, momenta.scale(q0, q1, t0, t1 - t0)])
        # the search weighs the misses as they are, but a condition whose scale is
        # more than ``FAR`` from the coordinates' largest by that ratio (a coordinate
        # in other units, or a momentum), so that it neither drowns in nor swamps
        # |F|^2, nor falls below ``rcond`` in the Jacobian (a weight near 1 changes
        # the search's path for nothing: a disk's free heading was missed at 1.7)
        ratio = self.scale.max() / scale
        far = (ratio > FAR) | (ratio < 1.0 / FAR)
        if far.any():
            self.weight = np.where(far, ratio, 1.0)
        self.scale = scale

    #: (scaled miss, u) of the run over the whole span that came nearest the end
    closest = None
    #: each end condition's weight in the search's |F|^2 (``levenberg_marquardt``;
    #: None: 1 each)
    weight = None

    def _endpoint(self, u):
        shot = self.run(u)
        if shot is None:
            return None
        if self.momenta is None:
            got = (shot.y[self._rows], self.named(shot.S), shot)
        else:
            got = (*self.end_conditions(shot.t, shot.y, shot.S), shot)
        # the closest miss is read only by ``out_of_time``: kept under a timeout alone
        if self.deadline is not None and self.span == self.scene.t_span \
                and len(got[0]) == len(self.target):
            miss = float(np.max(np.abs(got[0] - self.target) / self.scale))
            if self.closest is None or miss < self.closest[0]:
                self.closest = (miss, np.array(u, dtype=float))
        return got

    def out_of_time(self, timeout) -> ConnectError:
        """The ``ConnectError`` of a search stopped by ``connect(timeout=)``, with the
        closest motion its runs over the whole span reached."""
        best = None if self.closest is None else self._best(self.closest[1])
        edge = self.stops_note()
        return ConnectError(
            f"connect stopped at its timeout of {timeout:g} s after {self.runs} runs: "
            + ("no run reached t1, so there is no closest motion (ConnectError.best is "
               "None)" if best is None else f"the closest motion ends {best.residual:.3g} "
               "away from end (ConnectError.best is that motion)")
            + (f"; {edge}" if edge else "") + "; give more time, a guess nearer the "
            "answer, or an end nearer the start", best)

    def end_conditions(self, t, y, S):
        """The end conditions' values at the end ``(t, y)`` of a run from the start with
        the sensitivities ``S`` there, and their derivatives by the unknowns."""
        if self.momenta is None:
            return y[self._rows], self.named(S)
        values, D = self.conditions_at(t, y)
        return values, D @ S[:, self._cols]

    def conditions_at(self, t, y):
        """The end conditions' values at the state ``y`` at t1 and their derivatives by
        the state."""
        D = np.eye(len(y))[self.rows]
        if self.momenta is None:
            return y[self.rows], D
        g, G = self.momenta(t, y)
        return np.concatenate([y[self.rows], g]), np.vstack([D, G])

    #: where the default guess came from ("": the straight line)
    origin = ""

    def first_guess(self, u0, q0, q1, T):
        """The default guess made usable: where its run fails before t1, the
        collocation warm start (``collocation.warm_start`` from the straight line,
        milliseconds) when its run reaches t1; else ``regular_start``."""
        if self.endpoint(u0) is None:
            u = warm_start(self, self.leading(u0))
            if u is not None and self.endpoint(u) is not None:
                self.origin = " (the collocation warm start)"
                return u
        return self.regular_start(u0, q0, q1, T, self.n_velocities)

    def starts(self, u0, default, q0, q1, T):
        """The starts of the search, each made when the one before has failed: the
        guess ``u0`` as given; or (``default``: the straight line) ``first_guess`` and,
        unless that is the collocation warm start, ``second_guess``."""
        if not default:
            yield u0
            return
        yield self.first_guess(u0, q0, q1, T)
        if not self.origin:
            yield self.second_guess(u0, q0, q1, T)

    def second_guess(self, u0, q0, q1, T):
        """Where the search from ``first_guess`` fails: the straight line ``u0`` moved
        by the first step of ``regular_start``'s pattern (the velocities' scale times
        0.5 (-0.6)^i, rolled once), a start on another side of a fold of the endpoint
        map than its Gauss-Newton point."""
        scale = max([abs(q1[c] - q0[c]) for c in q1] + [1.0]) / abs(T)
        return u0 + scale * np.roll(0.5 * (-0.6) ** np.arange(len(u0)), 1)

    @property
    def conditions(self) -> tuple:
        """The names of the end conditions: the named coordinates, then p_<free>."""
        if self.momenta is None:
            return self.end_names
        return self.end_names + tuple(f"p_{c}" for c in self.momenta.free)

    def newton(self, u, target, tol, max_iter, rows=None):
        """Levenberg-Marquardt (``levenberg_marquardt``) on the end conditions = target
        (only those of ``rows`` when given); a least-squares point with the end missed
        raises ``unreachable``.  Returns ``(u, converged, iterations)``."""
        endpoint = self.endpoint
        if rows is None:
            def evaluate(v):
                got = endpoint(v)
                return None if got is None else (got[0] - target, got[1])
            scale = self.scale
        else:
            pick = list(rows)

            def evaluate(v):
                got = endpoint(v)
                return None if got is None else ((got[0] - target)[pick], got[1][pick])
            scale = self.scale[pick]

        def stuck(v, F, Jm):
            if self.least_squares_point(F, Jm):
                raise self.unreachable(v)

        weight = self.weight if rows is None or self.weight is None else self.weight[pick]
        u, ok, its = levenberg_marquardt(evaluate, u, scale, tol, max_iter, self.rcond,
                                         stuck, weight)
        # met on the search's scale (``end_scale``, which may measure a coordinate
        # that returns to its start by another's displacement): on to what ``tol``
        # is checked against (``own_scale``) where that is tighter (only where one
        # returns: else the two are the same)
        for _ in range(OWN_ROUNDS if self.returns else 0):
            if not ok or rows is not None or target is not self.target \
                    or self.span != self.scene.t_span:
                break
            got = endpoint(u)
            own = np.array(self.own_scale(got[2]))
            if relative_miss(np.abs(got[0] - target).tolist(), own.tolist()) <= tol:
                break
            scale = np.where(own > 0, np.minimum(own, self.scale), self.scale)
            v, ok, more = levenberg_marquardt(evaluate, u, scale, tol, max_iter - its,
                                              self.rcond, stuck, weight)
            its += more
            if not ok:
                # no nearer: the answer met on the search's scale, for ``connection``
                # to judge (it refuses a miss beyond ``tol`` of the own scale)
                return u, True, its
            u = v
        return u, ok, its

    def solve(self, u0, tol, max_iter, max_continuation, segments=None):
        """The routes in turn, each from what the last left: multiple shooting on
        ``segments`` segments (``default_segments`` when None) when there are more than
        one, polished by single shooting (or stitched, ``Stitched``, where single shooting
        cannot reach the tolerance); Newton from ``u0``; continuation in the endpoint
        from q(t1; u0); a direct collocation warm start (``collocation.warm_start``)
        polished by Newton; continuation in T.  An overdetermined or rank-deficient end
        (more conditions than the rank of the shooting Jacobian) is continued on its
        best-determined conditions (``leading``) and checked on all at the end.
        Returns ``(u, iterations, stitched or None, the route that found it)``."""
        k = default_segments(self, u0) if segments is None else segments
        its, notes, closest = 0, [], None
        if k > 1:
            u, ok, its, stitched = self.multiple(u0, k, tol, max_iter)
            if ok:
                return u, its, stitched, (f"multiple shooting ({k} segments"
                                          + (", stitched)" if stitched else ")"))
            notes.append(f"multiple shooting on {k} segments did not converge")
        try:
            u, ok, more = self.newton(u0, self.target, tol, max_iter)
        except ConnectError as e:           # a least-squares point near the guess
            closest, ok, more = e, False, max_iter
        its += more
        if ok:
            return u, its, None, "Newton from the guess" + self.origin
        rows = self.leading(u0)
        routes = [("continuation in the endpoint", self.continuation),
                  ("collocation", self.collocation), ("continuation in T", self.grow)]
        for name, route in routes:
            try:
                v, ok, k, where = route(u0, tol, max_iter, max_continuation, rows)
            except ConnectError as e:
                closest = _closer(closest, e)
                notes.append(f"{name}: {e.args[0].split(':')[0]}")
                continue
            its += k
            if ok and rows is not None:
                # the leading conditions met: all of them from there
                try:
                    v, ok, k = self.newton(v, self.target, tol, max_iter)
                except ConnectError as e:
                    # the leading conditions met exactly and the others then missed at
                    # a least-squares point: the end is off the reachable set here
                    closest = _closer(closest, e)
                    notes.append(f"{name} met {', '.join(self.conditions[r] for r in rows)}"
                                 " exactly; the others then missed at a least-squares "
                                 "point")
                    break
                its += k
                if not ok:
                    notes.append(f"{name} met {', '.join(self.conditions[r] for r in rows)}"
                                 " exactly; Newton on every condition from there did not "
                                 "converge")
                    u = v
                    continue
            if ok:
                return v, its, None, name + ("" if rows is None else " (on " + ", ".join(
                    self.conditions[r] for r in rows) + " first)")
            notes.append(f"{name} stopped at {where}")
        edge = self.stops_note()
        if edge:
            notes.append(edge)
        if closest is not None:
            raise ConnectError(closest.args[0] + "; also tried: " + "; ".join(notes),
                               closest.best)
        best = self._best(u)
        if best is None:
            raise ConnectError(
                f"connect did not reach the end ({its} iterations in all): "
                + "; ".join(notes) + "; no motion from where the search stopped reaches "
                "t1 (its run stops before), so there is no closest motion "
                "(ConnectError.best is None); try a guess whose run reaches t1, a "
                "shorter span or an end nearer the start", None)
        raise ConnectError(
            f"connect did not reach the end ({its} iterations in all): "
            + "; ".join(notes) + f"; the closest motion ends {best.residual:.3g} away "
            "from end" + self._reachability(u) + "; try another guess, a shorter span "
            "or an end nearer the start (ConnectError.best is that motion)", best)

    def leading(self, u):
        """The end conditions to continue on when the shooting Jacobian at ``u`` has
        lower rank r than there are conditions (an overdetermined Chetaev or Suslov end,
        or a rank-deficient one): the r best determined (column-pivoted QR of the
        scaled Jacobian's transpose); where the run fails, the named coordinates of the
        independent velocities first.  None when the rank is full."""
        got = self.endpoint(u)
        n_cond = len(self.target)
        if got is None:
            ind = [self.conditions.index(v[:-2]) for v in self.unknowns[:self.n_velocities]
                   if v.endswith("_t") and v[:-2] in self.conditions]
            if n_cond <= len(self.unknowns) or not ind:
                return None
            rest = [r for r in range(n_cond) if r not in ind]
            return (ind + rest)[:len(self.unknowns)]
        from scipy.linalg import qr

        Jm = self.unit_free(got[1])
        r = rank(singular_values(Jm), self.rcond)
        if r >= n_cond:
            return None
        _, _, piv = qr(Jm.T, pivoting=True)
        return sorted(int(i) for i in piv[:max(r, 1)])

    def continuation(self, u0, tol, max_iter, max_continuation, rows=None):
        """Continuation in the endpoint: the conditions ``rows`` (all when None) follow
        ``first + s (target - first)`` from s = 0 (q(t1; u0)) to 1 with adaptive steps.
        Returns ``(u, reached s = 1, iterations, where it stopped)``."""
        got = self.endpoint(u0)
        if got is None:
            return u0, False, 0, "s = 0 (the guess's run fails before t1)"
        first = got[0]

        def step(s_try, s, u):
            target = first + s_try * (self.target - first)
            # a continuation step starts near its solution: a short budget, so that an
            # unreachable end fails in seconds
            try:
                return self.newton(u, target, tol if s_try == 1.0 else max(tol, 1e-6),
                                   min(max_iter, STEP_ITER), rows)
            except ConnectError:
                return u, False, min(max_iter, STEP_ITER)

        u, s, ds, total = march(u0, 0.0, 0.25, step, max_continuation)
        if s == 1.0:
            return u, True, total, "s = 1"
        return u, False, total, f"s = {s:.6g} of 1 (step {ds:.3g})"

    def collocation(self, u0, tol, max_iter, max_continuation, rows=None):
        """A direct collocation warm start (``collocation.warm_start``: scipy's solve_bvp
        on the scene's equations from the straight line, the conditions ``rows``),
        polished by Newton on them.  Returns ``(u, converged, iterations, where)``."""
        u = warm_start(self, rows, u0)
        if u is None:
            return u0, False, 0, "its mesh limit without a solution"
        v, ok, k = self.newton(u, self.target, tol, max_iter, rows)
        return v, ok, k, "Newton from its answer" if not ok else "its answer"

    def grow(self, u0, tol, max_iter, max_continuation, rows=None):
        """Continuation in T: solve on the span ``FIRST_SPAN`` T from the guess with its
        velocities and multipliers scaled by 1 / ``FIRST_SPAN`` (for L quadratic in the
        velocities and linear constraints, an extremal run faster is one of the
        shorter span: the straight line is a better guess there), then grow the span
        to T with adaptive steps, each predicted by that rescaling of the last answer.
        Returns ``(u, converged, iterations, where it stopped)``."""
        full = self.span
        t0, t1 = full

        def solve_on(frac, u, budget, tol_):
            self.span = (t0, t0 + frac * (t1 - t0))
            try:
                return self.newton(u, self.target, tol_, budget, rows)
            except ConnectError:          # an overdetermined end missed: not this way
                return u, False, budget

        try:
            s = FIRST_SPAN
            self.span = (t0, t0 + s * (t1 - t0))
            u = np.asarray(u0) / s
            if self.endpoint(u) is None:        # moved off a run that stops early
                q0 = {c: self.y0[r] for c, r in zip(self.end_names, self.rows)}
                u = self.regular_start(u, q0, dict(zip(self.end_names, self.target)),
                                       self.span[1] - t0, self.n_velocities)
            u, ok, total = solve_on(s, u, max_iter, max(tol, 1e-6))
            if not ok:
                return u0, False, total, f"T = {s * (t1 - t0):.6g} (its first span)"

            def step(s_try, s, u):
                return solve_on(s_try, u * (s / s_try), min(max_iter, STEP_ITER),
                                tol if s_try == 1.0 else max(tol, 1e-6))

            u, s, _, k = march(u, s, (1.0 - s) / 4.0, step, max_continuation)
            total += k
            if s == 1.0:
                return u, True, total, "T"
            return u, False, total, f"T = {s * (t1 - t0):.6g} of {t1 - t0:.6g}"
        finally:
            self.span = full

    def multiple(self, u0, k, tol, max_iter):
        """Multiple shooting (``Segments``) from ``u0`` and the straight line, then
        single shooting from its ``u`` (at most ``STEP_ITER`` iterations: it starts at
        the answer up to the amplification of the matching error).  Where single
        shooting cannot get there, or gets there with a run whose growth exceeds
        ``POLISH_GROWTH`` (its own error, so amplified, exceeds the tolerance), the
        segments' answer is the motion: ``Stitched``.
        Returns ``(u, converged, iterations, stitched or None)``."""
        seg = _Segments(self, k, tol)
        U0 = seg.guess(u0)
        U, ok, its = levenberg_marquardt(lambda U: seg.evaluate(U, self.target), U0,
                                         seg.scale, tol, max_iter, self.rcond)
        if not ok:
            return u0, False, its, None
        try:
            u, ok, more = self.newton(U[:seg.m], self.target, tol,
                                      min(max_iter, STEP_ITER))
        except ConnectError:
            ok, more = False, min(max_iter, STEP_ITER)
        if ok and abs(self.endpoint(u)[2].S[:, :len(self.y0)]).max() <= POLISH_GROWTH:
            return u, True, its + more, None
        stitched = Stitched.join(seg, U)
        return U[:seg.m], stitched is not None, its + more, stitched

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
            f"time: " + ("the least-squares answer's run stops before t1 (ConnectError."
                         "best is None)" if best is None else
                         f"the least-squares answer ends {best.residual:.3g} away"
                         + self._reachability(u) + " (ConnectError.best is that answer)"),
            best)

    def _reachability(self, u) -> str:
        got = self.endpoint(u)
        if got is None:
            return ""
        r = rank(singular_values(got[1]), self.rcond)
        if len(self.target) > r:
            return (f" (the {self.scene.principle} motions from the start reach a "
                    f"{r}-dimensional set of the {len(self.target)} end conditions near "
                    f"there: {len(self.unknowns)} unknowns "
                    f"{', '.join(self.unknowns)}; "
                    + ("choose an end on that set or another span)"
                       if self.scene.principle in VARIATIONAL
                       else f"name at most {r} coordinates in end)"))
        return ""

    def _best(self, u):
        try:
            return self.connection(u, 0, None)
        except JetnhError:
            return None

    # ------------------------------------------------------------------ the answer
    def connection(self, u, iterations, tol, stitched=None, route="") -> Connection:
        scene = self.scene
        if stitched is not None:
            motion = stitched
            q, Jm = self.end_conditions(motion.t[-1], motion.y[-1],
                                        motion.sensitivities[-1])
        else:
            got = self.endpoint(u)
            if got is None:
                raise ConnectError(f"the motion found stops before t1: "
                                   f"{scene.run(y0=self.state(u)).stop_reason}")
            # the run itself: its Trajectory is made when the Connection's is read
            q, Jm, motion = got
        # a few entries: as Python floats (the same IEEE operations as numpy's, without
        # an array call each)
        target = self.target.tolist()
        miss = [abs(a - b) for a, b in zip(q.tolist(), target)]
        residual = max(miss)
        # the miss relative to each condition's own scale, in its own units
        # (``shooting.own_scale``: never another coordinate's displacement)
        relative = relative_miss(miss, self.own_scale(motion))
        full = singular_values(Jm).tolist()
        # the dependent velocities at t0: the aux kernel on the first row alone
        state, aux = first_values(motion)
        dependent = scene.dependent_velocities
        best = Connection(
            _motion=motion,
            initial=MappingProxyType(dict(zip(
                scene.state_names + dependent, state + aux[:len(dependent)]))),
            residual=residual, principle=scene.principle, unknowns=self.unknowns,
            rank=rank_of(full, self.rcond), singular_values=tuple(full),
            iterations=iterations,
            _columns=tuple(self.cols), _rcond=self.rcond, _run=MappingProxyType(
                {"rtol": self.rtol, "atol": self.atol, "method": self.method}),
            conditions=self.conditions, route=route, relative_residual=relative,
            _end=tuple(target[:len(self.rows)]))
        if tol is not None and relative > tol:
            raise ConnectError(
                f"the {scene.principle} motion found ends {residual:.3g} away from end "
                f"({relative:.3g} of its own scale, the displacement start -> end "
                f"or the excursion along the motion)"
                + self._reachability(u), best)
        return best


def march(u, s, ds, step, max_steps):
    """Adaptive continuation in s from ``s`` to 1: ``step(s_try, s, u)`` -> ``(v, ok,
    iterations)`` solves at ``s_try`` from the answer ``u`` at ``s``; the step doubles
    after a success and halves after a failure, giving up below 1e-4 or after
    ``max_steps`` tries.  Returns ``(u, s, ds, iterations)``: s == 1.0 where it arrived."""
    total = 0
    for _ in range(max_steps):
        s_try = min(1.0, s + ds)
        v, ok, k = step(s_try, s, u)
        total += k
        if ok:
            s, u = s_try, v
            if s == 1.0:
                break
            ds = min(2.0 * ds, 1.0 - s)
        else:
            ds *= 0.5
            if ds < 1e-4:
                break
    return u, s, ds, total


def _closer(a, b):
    """Of two ``ConnectError`` (or None), the one whose ``best`` ends nearer the end."""
    if a is None or (b.best is not None and (a.best is None
                                             or b.best.residual < a.best.residual)):
        return b
    return a


class _Segments(Segments):
    """``Segments`` whose last block is every end condition of the search (the named
    coordinates and the free ones' transversality conditions)."""

    def guess(self, u):
        sh = self.shooter
        full, sh.target = sh.target, sh.target[:len(sh.rows)]     # the named coordinates
        try:
            return super().guess(u)
        finally:
            sh.target = full

    def run(self, i, y):
        shot = super().run(i, y)
        if i == self.k - 1:
            self.last = shot
        return shot

    def evaluate(self, U, target):
        sh = self.shooter
        got = super().evaluate(U, target[:len(sh.rows)])
        if got is None or sh.momenta is None:
            return got
        F, Jm = got
        shot, n = self.last, self.n
        g, G = sh.momenta(shot.t, shot.y)
        block = np.zeros((len(g), U.size))
        block[:, self.m + (self.k - 2) * n:] = G @ shot.S[:, :n]
        return np.concatenate([F, g - target[len(sh.rows):]]), np.vstack([Jm, block])


def least_action(search, found, tol, max_iter, restarts):
    """The least-action answer among ``found`` (a ``Connection`` of a vakonomic or
    Hoelder problem) and the extremals reached from ``restarts`` restarts, where
    ``found`` is no minimizer (Legendre's condition fails or a conjugate time lies inside
    the span: ``Connection.minimizer`` False).  The first restart starts from the direct route's guess
    (``direct.guess``: the action minimised over a family of admissible paths, where the
    problem allows it), solved by multiple shooting on ``DIRECT_SEGMENTS`` segments;
    restart k moves ``found``'s unknowns by a fixed pseudo-random direction (seeded by
    k) of growing size (a quarter, a half, one, two times each unknown's scale,
    max(|u_i|, 1)), then Newton with at most ``min(max_iter, STEP_ITER)`` iterations
    (no other route).  Each answer's ``iterations`` are those of its restart.  Kept:
    the cheapest minimizer (``Connection.minimizer`` True), else the cheapest.
    Returns that ``Connection`` with ``search`` saying what was tried and where it
    stopped."""
    import dataclasses

    if not restarts or found.minimizer is not False:
        if restarts and found.minimizer is None and found.not_extremal:
            return dataclasses.replace(found, search=(
                f"no restarts: the minimizer verdict is undecided ({found.not_extremal})"))
        return found
    u = np.array([found.initial[k] for k in found.unknowns])
    scale = np.maximum(np.abs(u), 1.0)
    seen = [u]
    answers = [found]
    budget = min(max_iter, STEP_ITER)
    direct_note = ""
    for k in range(restarts):
        stitched, route = None, found.route + f", restart {k + 1}"
        try:
            if k == 0:
                start = direct.guess(search)
                if start is None:
                    direct_note = "; the direct route does not apply"
                    continue
                v, ok, iters, stitched = search.multiple(start, DIRECT_SEGMENTS, tol,
                                                         max_iter)
                if ok and stitched is None:     # polished just inside tol: once more
                    w, better, more = search.newton(v, search.target, 1e-3 * tol, budget)
                    v, iters = (w, iters + more) if better else (v, iters)
                route += (f": multiple shooting ({DIRECT_SEGMENTS} segments) from the "
                          "direct route")
                direct_note = "" if ok else "; shooting from the direct route failed"
            else:
                step = np.random.default_rng(k).standard_normal(len(u))
                start = u + 0.25 * 2.0 ** (k % 4) * scale * step / np.linalg.norm(step)
                v, ok, iters = search.newton(start, search.target, tol, budget)
        except ConnectError:
            continue
        if not ok or any(np.max(np.abs(v - w) / scale) < 1e-6 for w in seen):
            continue
        seen.append(v)
        try:
            answers.append(search.connection(v, iters, tol, stitched, route))
        except JetnhError:
            continue
    minimizers = [c for c in answers if c.minimizer]
    best = min(minimizers or answers, key=lambda c: c.cost)

    def verdict_of(c):
        if c.minimizer:
            return ""
        why = c._not_minimizer
        return (" (Legendre fails)" if why.startswith("Legendre") else " (conjugate)"
                if why else " (not checked)")

    costs = ", ".join(f"{c.cost:.8g}{verdict_of(c)}"
                      for c in sorted(answers, key=lambda c: c.cost))
    failed = {verdict_of(c) for c in answers} - {""}
    if minimizers:
        verdict = ("the cheapest minimizer kept (Legendre's condition holds and no "
                   "conjugate time lies inside the span)")
    elif failed == {" (Legendre fails)"}:
        verdict = ("Legendre's condition fails on every one (L + lambda f is not "
                   "positive definite on the admissible velocities somewhere along "
                   "them: no minimizer of the action there): the cheapest kept, not a "
                   "minimizer")
    else:
        verdict = ("none is a minimizer: the cheapest kept, not a minimizer; try a guess "
                   "near the least-action motion, or more restarts")
    return dataclasses.replace(best, search=(
        f"{restarts} restarts from the first answer, which is no minimizer: "
        f"{found._not_minimizer}{direct_note}; {len(answers)} extremals (costs {costs}); "
        f"{verdict}"))
