"""Single shooting: runs of one scene from the start with the initial unknowns ``u``,
the endpoint residual and its Jacobian from the exact sensitivities
(``scene.run(sensitivities=True)``), never finite differences."""

from __future__ import annotations

import numpy as np

from ...errors import JetnhError
from .. import solve
from ..options import options

#: steps a shooting run may take (a run that needs more counts as failed)
MAX_STEPS = 20_000


class Shooter:
    """Runs of one scene from the start with the unknowns ``u``: the endpoint residual
    and its Jacobian from the sensitivities."""

    def __init__(self, scene, q0, q1, unknowns, fixed, rtol, atol, method, rcond):
        self.scene, self.unknowns, self.fixed = scene, unknowns, fixed
        names = scene.state_names
        self.rows = [names.index(c) for c in q1]
        self.target = np.array(list(q1.values()))
        self.cols = [names.index(u) for u in unknowns]
        self.block = np.ix_(self.rows, self.cols)      # dq_named(t1)/du in S
        given = {**q0, **fixed}
        self.y0 = np.array([given.get(n, 0.0) for n in names])
        self.rtol, self.atol, self.method, self.rcond = rtol, atol, method, rcond
        self.end_names = tuple(q1)
        self.seen: dict = {}
        self.span = scene.t_span         # the runs' span (continuation in T moves t1)
        self.n_velocities = len(scene.system.independent_velocities)   # lead unknowns
        self.plans: dict = {}            # the driver's plans of the runs

    def plan(self, span, save="steps"):
        """The driver's plan of a shooting run on ``span`` (with sensitivities; every
        step or the ends), made once: each run then only calls the compiled loop."""
        key = ("shooting", self.method, self.rtol, solve.hashable(self.atol), span, save,
               MAX_STEPS)
        found = self.plans.get(key)
        if found is None:
            # kept on the scene too: repeated problems on one scene plan nothing
            found = self.plans[key] = solve.planned(self.scene, key, lambda: solve.plan(
                self.scene, self.method, t_span=span, save=save, sensitivities=True,
                opts=options(rtol=self.rtol, atol=self.atol, max_steps=MAX_STEPS)))
        return found

    def start(self, y, span, save="steps"):
        """The run of the plan of ``span`` from the state ``y`` (its own array), or
        None where it fails before the end of the span or ends in a non-finite
        state."""
        scene = self.scene
        if not np.isfinite(y).all():
            return None
        try:
            scene._check_holonomic(y, span[0], scene._p)
            tr = solve.run(scene, self.plan(span, save), y, scene._p)
        except JetnhError:
            return None
        return tr if tr.status == 0 and np.isfinite(tr.y[-1]).all() else None

    def state(self, u) -> np.ndarray:
        y = self.y0.copy()
        y[self.cols] = u
        return y

    def endpoint(self, u):
        """``(q_named(t1), dq_named(t1)/du, the run)``, or None where the run fails
        (the last few kept: the guess and the answer are evaluated more than once)."""
        key = (np.asarray(u, dtype=float).tobytes(), self.span)
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
        return tr.y[-1, self.rows], S[self.block], tr

    def run(self, u):
        """The run from the start with the unknowns ``u`` (every step, with
        sensitivities), or None where it fails before t1 (or takes more than
        ``MAX_STEPS`` steps: a wild trial of the search must not take minutes)."""
        return self.start(self.state(u), self.span)

    def regular_start(self, u0, q0, q1, T, n_velocities):
        """The default guess, moved off a point where the run stops before t1 (a speed
        that falls to a singular zero) or where the shooting Jacobian is rank-deficient
        (zero velocities, a straight line along an abnormal direction): first to the
        minimum-norm Gauss-Newton point of its run's sensitivities (``newton_point``:
        the motion the guess's linearisation says reaches the end), then by a fixed
        pattern of the size of the straight-line velocities, with the velocities
        doubled and quadrupled; 12 tries, the first regular one kept (else the first
        that reaches t1)."""
        scale = max([abs(q1[c] - q0[c]) for c in q1] + [1.0]) / abs(T)
        pattern = 0.5 * (-0.6) ** np.arange(len(u0))
        speed = np.ones(len(u0))
        reaching = None
        for k in range(12):                 # k = 0: u0 itself
            speed[:n_velocities] = 2.0 ** (k // 4)
            u = speed * u0 + (scale * np.roll(pattern, k) * (k % 4) if k % 4 else 0.0)
            got = self.endpoint(u)
            if got is not None:
                if self.regular(got):
                    return u
                if k == 0:
                    newton = self.newton_point(u, got)
                    if newton is not None and self.regular(self.endpoint(newton)):
                        return newton
                reaching = u if reaching is None else reaching
        return u0 if reaching is None else reaching

    @staticmethod
    def regular(got) -> bool:
        """Whether the ``endpoint`` ``got`` exists (the run reached t1) and its shooting
        Jacobian has full rank by a margin (smallest singular value above 1e-6 of the
        largest)."""
        if got is None:
            return False
        s = np.linalg.svd(got[1], compute_uv=False)
        return bool(s.size and s[0] > 0 and s[-1] > 1e-6 * s[0])

    def newton_point(self, u, got):
        """``u`` plus the minimum-norm Gauss-Newton step of its endpoint ``got`` (the
        truncated SVD, at most the size of ``u`` and 1), or None where it does not
        move."""
        U, s, Vt = self.svd(got[1])
        if not s.size:
            return None
        du = -(Vt.T @ ((U.T @ (got[0] - self.target)) / s))
        du /= max(1.0, np.linalg.norm(du) / max(1.0, np.linalg.norm(u)))
        return u + du if np.any(du) else None

    def svd(self, Jm):
        """The singular value decomposition of the shooting Jacobian with its numerical
        rank (relative cut-off ``rcond``)."""
        U, s, Vt = np.linalg.svd(Jm, full_matrices=False)
        r = int(np.sum(s > self.rcond * s[0])) if s.size and s[0] > 0 else 0
        return U[:, :r], s[:r], Vt[:r]


#: growth max |dy(t1)/dy(t0)| of the guess's run above which the default splits the span
GROWTH = 1e6
#: the most segments the default chooses (``segments`` may ask for more)
MAX_SEGMENTS = 16


def default_segments(shooter, u) -> int:
    """The number of shooting segments for the guess ``u``: 1 where its run reaches t1
    with sensitivities below ``GROWTH``; else one segment per factor 100 of the growth
    (``MAX_SEGMENTS`` where the run fails before t1), at least 2."""
    got = shooter.endpoint(u)
    if got is None:
        return MAX_SEGMENTS
    tr = got[2]
    n = len(shooter.y0)
    growth = float(np.max(np.abs(tr.sensitivities[-1][:, :n])))
    if not np.isfinite(growth):
        return MAX_SEGMENTS
    if growth <= GROWTH:
        return 1
    return int(min(MAX_SEGMENTS, max(2, np.ceil(np.log10(growth) / 2.0))))


class Segments:
    """Multiple shooting of a ``Shooter``'s problem on ``k`` equal segments of the span:
    the unknowns are the shooter's ``u`` and the full states ``Y_1 .. Y_{k-1}`` at the
    inner nodes; the conditions are the matching ``y(t_i; Y_{i-1}) - Y_i = 0`` and the
    end ``q_named(t1; Y_{k-1}) = end``.  The Jacobian is block bidiagonal: the segments'
    state transition matrices (their exact sensitivities) and -I."""

    def __init__(self, shooter, k):
        self.shooter, self.k = shooter, int(k)
        t0, t1 = shooter.scene.t_span
        self.nodes = np.linspace(t0, t1, self.k + 1)
        self.n = len(shooter.y0)
        self.m = len(shooter.cols)

    def guess(self, u):
        """``u`` and the inner states on the line from the start to the named end (the
        other coordinates kept, the unknowns' states from ``u``)."""
        sh = self.shooter
        y, t0, t1 = sh.state(u), self.nodes[0], self.nodes[-1]
        inner = []
        for t in self.nodes[1:-1]:
            Y = y.copy()
            Y[sh.rows] = y[sh.rows] + (t - t0) / (t1 - t0) * (sh.target - y[sh.rows])
            inner.append(Y)
        return np.concatenate([np.asarray(u, dtype=float)] + inner)

    def split(self, U):
        """The initial states of the segments from the unknowns ``U``."""
        sh, n, m = self.shooter, self.n, self.m
        return [sh.state(U[:m])] + [U[m + i * n:m + (i + 1) * n] for i in range(self.k - 1)]

    def run(self, i, y):
        return self.shooter.start(np.array(y, dtype=float),
                                  (float(self.nodes[i]), float(self.nodes[i + 1])), "final")

    def evaluate(self, U, target):
        """``(F, dF/dU)`` of the matching and end conditions, or None where a segment's
        run fails."""
        sh, n, m, k = self.shooter, self.n, self.m, self.k
        starts = self.split(U)
        F = np.empty((k - 1) * n + len(sh.rows))
        Jm = np.zeros((F.size, U.size))
        for i, y in enumerate(starts):
            tr = self.run(i, y)
            if tr is None:
                return None
            end, S = tr.y[-1], tr.sensitivities[-1][:, :n]
            # columns: segment 0 depends on u (its unknowns' states), the others on Y_i
            cols = (slice(0, m), sh.cols) if i == 0 else (slice(m + (i - 1) * n,
                                                                  m + i * n), slice(None))
            if i < k - 1:
                r = slice(i * n, (i + 1) * n)
                F[r] = end - starts[i + 1]
                Jm[r, cols[0]] = S[:, cols[1]]
                Jm[r, m + i * n:m + (i + 1) * n] = -np.eye(n)
            else:
                r = slice((k - 1) * n, F.size)
                F[r] = end[sh.rows] - target
                Jm[r, cols[0]] = S[sh.rows][:, cols[1]]
        return F, Jm

    def scale(self, U, target):
        """1 + |value| of each condition's quantity (the inner states, the end)."""
        return np.concatenate([1.0 + np.abs(U[self.m:]), 1.0 + np.abs(target)])
