"""The search: Levenberg-Marquardt on the shooting map, continuation in the endpoint
when it fails from the guess, and the answer (a ``Connection``) or the reason it was not
found (``ConnectError`` with the closest motion)."""

from __future__ import annotations

from types import MappingProxyType

import numpy as np

from ...errors import ConnectError, JetnhError
from .connection import Connection
from .problem import VARIATIONAL
from .shooting import Segments, Shooter, default_segments

#: Levenberg-Marquardt iterations per continuation step (at most ``max_iter``)
STEP_ITER = 20
#: the first span of the continuation in T, as a fraction of T
FIRST_SPAN = 0.125


class Search(Shooter):
    """A ``Shooter`` that solves q(t1; u) = end."""

    def newton(self, u, target, tol, max_iter):
        """Levenberg-Marquardt (``levenberg_marquardt``) on q(t1; u) = target; a
        least-squares point with the end missed raises ``unreachable``.  Returns
        ``(u, converged, iterations)``."""
        def evaluate(v):
            got = self.endpoint(v)
            return None if got is None else (got[0] - target, got[1])

        def stuck(v, F, Jm):
            if self.least_squares_point(F, Jm):
                raise self.unreachable(v)

        return levenberg_marquardt(evaluate, u, 1.0 + np.abs(target), tol, max_iter,
                                   self.svd, stuck)

    def solve(self, u0, tol, max_iter, max_continuation, segments=None):
        """Multiple shooting on ``segments`` segments (``default_segments`` when None)
        when there are more than one, polished by single shooting; else (or when it
        fails) Newton from ``u0``, else continuation in the endpoint from q(t1; u0)."""
        k = default_segments(self, u0) if segments is None else segments
        its = 0
        if k > 1:
            u, ok, its = self.multiple(u0, k, tol, max_iter)
            if ok:
                return u, its
        u, ok, more = self.newton(u0, self.target, tol, max_iter)
        its += more
        if ok:
            return u, its
        got = self.endpoint(u0)
        if got is None:
            v, ok, k, reached = self.grow(u0, tol, max_iter, max_continuation)
            if ok:
                return v, its + k
            raise ConnectError(
                f"the {self.scene.principle} run from the start with the guess "
                f"{dict(zip(self.unknowns, u0.tolist()))} fails before t1 (a singular "
                "configuration or a non-finite state), and continuation in T stopped at "
                f"T = {reached:.6g}; give another guess")
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
        v, ok, k, reached = self.grow(u0, tol, max_iter, max_continuation)
        total += k
        if ok:
            return v, total
        best = self._best(u)
        raise ConnectError(
            f"connect did not reach the end: continuation in the endpoint stopped at "
            f"s = {s:.6g} of 1 (step {ds:.3g}), continuation in T at T = {reached:.6g} "
            f"of {self.span[1] - self.span[0]:.6g} ({total} iterations in all); the closest "
            f"motion ends {best.residual:.3g} away from end"
            + self._reachability(u) + "; try another guess, a shorter span or an end "
            "nearer the start (ConnectError.best is that motion)", best)

    def grow(self, u0, tol, max_iter, max_continuation):
        """Continuation in T: solve on the span ``FIRST_SPAN`` T from the guess with its
        velocities and multipliers scaled by 1 / ``FIRST_SPAN`` (for L quadratic in the
        velocities and linear constraints, an extremal run faster is one of the
        shorter span: the straight line is a better guess there), then grow the span
        to T with adaptive steps, each predicted by that rescaling of the last answer.
        Returns ``(u, converged, iterations, the longest span solved)``."""
        full = self.span
        t0, t1 = full

        def solve_on(frac, u, budget, tol_):
            self.span = (t0, t0 + frac * (t1 - t0))
            try:
                return self.newton(u, self.target, tol_, budget)
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
                return u0, False, total, 0.0
            ds = (1.0 - s) / 4.0
            for _ in range(max_continuation):
                s_try = min(1.0, s + ds)
                v, ok, k = solve_on(s_try, u * (s / s_try), min(max_iter, STEP_ITER),
                                    tol if s_try == 1.0 else max(tol, 1e-6))
                total += k
                if ok:
                    s, u = s_try, v
                    if s == 1.0:
                        return u, True, total, s * (t1 - t0)
                    ds = min(2.0 * ds, 1.0 - s)
                else:
                    ds *= 0.5
                    if ds < 1e-4:
                        break
            return u, False, total, s * (t1 - t0)
        finally:
            self.span = full

    def multiple(self, u0, k, tol, max_iter):
        """Multiple shooting (``Segments``) from ``u0`` and the straight line, then
        single shooting from its ``u`` (at most ``STEP_ITER`` iterations: it starts at
        the answer up to the amplification of the matching error).  Returns ``(u,
        converged, iterations)``."""
        seg = Segments(self, k)
        U0 = seg.guess(u0)
        U, ok, its = levenberg_marquardt(lambda U: seg.evaluate(U, self.target), U0,
                                         seg.scale(U0, self.target), tol, max_iter,
                                         self.svd)
        if not ok:
            return u0, False, its
        u, ok, more = self.newton(U[:seg.m], self.target, tol, min(max_iter, STEP_ITER))
        return u, ok, its + more

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


def levenberg_marquardt(evaluate, u, scale, tol, max_iter, svd, stuck=None):
    """Levenberg-Marquardt on F(u) = 0 (``evaluate(u)`` is ``(F, dF/du)``, or None
    where the runs fail), in unknowns scaled by the largest
    column norms of the Jacobian seen so far (More's scaling: the multipliers'
    columns are often orders of magnitude smaller than the velocities'): the step
    ``-D^-1 V diag(s / (s^2 + mu)) U^T F`` of the truncated SVD of ``J D^-1`` (``svd``)
    (mu -> 0: the minimum-norm Gauss-Newton step, quadratic convergence near a
    solution; mu large: a short step down the gradient), mu adapted by the ratio of
    the actual to the predicted decrease (Nielsen's rule), a failed run counted as no
    decrease; ``stuck(u, F, J)`` is told of every rejected step.  Converged: max
    |F| / ``scale`` <= ``tol``.  Returns ``(u, converged, iterations)``."""
    got = evaluate(u)
    if got is None:
        return u, False, 0
    F, Jm = got
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
        U, s, Vt = svd(Jm / d)
        if not s.size:
            return u, False, it
        if mu is None:
            mu, nu = 1e-6 * s[0] ** 2, 2.0
        du = -(Vt.T @ (s * (U.T @ F) / (s**2 + mu))) / d
        # at most the size of the unknowns (and 1): stay on the branch of solutions
        # the search starts near instead of jumping to a far one
        du /= max(1.0, np.linalg.norm(du) / max(1.0, np.linalg.norm(u)))
        trial = evaluate(u + du)
        linear = F + Jm @ du
        predicted = F @ F - linear @ linear
        rho = -1.0
        if trial is not None and predicted > 0:
            F_new = trial[0]
            rho = (F @ F - F_new @ F_new) / predicted
        if rho > 0:
            u, (F, Jm) = u + du, trial
            mu *= max(1.0 / 3.0, 1.0 - (2.0 * rho - 1.0) ** 3)
            nu = 2.0
        else:
            if stuck is not None:
                stuck(u, F, Jm)
            mu *= nu
            nu *= 2.0
            if mu > 1e20 * s[0] ** 2:          # no step of any length decreases |F|
                return u, False, it
    return u, bool(np.max(np.abs(F) / scale) <= tol), max_iter
