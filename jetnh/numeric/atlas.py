"""Atlases of splits: a run that reaches the edge of its split's chart goes on in another.

A split (the dependent coordinates q^alpha) is a chart of the constraint manifold
f(t, q, qdot) = 0: the constraints solve for qdot^alpha where the minor A_alpha =
df/dqdot^alpha of A = df/dqdot (k x n) is invertible.  How well, at a point::

    m_alpha = det(A_alpha)^2 / det(A A^T)   in [0, 1],

unchanged when the constraints are recombined (f -> M f) and, by the Cauchy-Binet
formula, summing to 1 over all splits; so among the N splits whose minor is not
identically zero one has m >= 1/N wherever A has rank k.  A run watches the edge of its
chart, m_alpha = eps with eps = 1/(4N), as a terminal event (``edge``: det(A_alpha)^2 -
eps det(A A^T) crossing zero downwards).  The step in which it is reached is not kept
(its stages may have run on toward the chart's singular set, or past it: a step that
jumps the whole band stops at the singular set, and is taken the same way): the run goes
back to the step's start, where the chart is regular, and continues there in the split
of largest measure if that is at least 2 eps (hysteresis, no chattering), else reaches
the edge in steps of an eighth (``_approach``) and continues there.  Fixed steps so
switch on their grid, each step no longer than h.  Near its singular set a chart's
right-hand side has a pole (phi^alpha = A_alpha^-1 (...)), and a step whose length is
comparable to its distance from the pole has a local error that the embedded estimate
misses (dop853 accepted the last step before each edge at 100 times its usual error):
so an adaptive step of a switching run after its first switch is no longer than
``NEAR`` times the time in which the chart's singularity indicators would reach zero
(``loop.near_zero``; the first piece takes the steps of a run that keeps its split, bit
for bit, the same run up to the edge), and a fixed step one of whose stages is past the
edge (its end may look regular all the same) stops the run at its start, where it
switches as above (``loop.past_edge``; both set by ``Control.edge``).  From the switch point the run goes on
with the state mapped exactly:

- coordinates unchanged; the velocities re-split (the dependent ones, computed from the
  constraints, become states and the states that are now dependent drop out);
- multipliers: those of the forms built on the constraints as written (vakonomic and
  Hoelder (15), (22): F = L + lambda_a f^a) belong to the constraints, not to the split,
  and keep their values (their names follow the dependent coordinates: lambda_y in one
  split is lambda_x in the other).  The explicit forms ((17)-(20)) weigh
  qdot^alpha - phi^alpha instead; on the constraints f = A_alpha (qdot^alpha -
  phi^alpha) to first order, so their multipliers are A_alpha^T lambda and map as
  lambda_beta = A_beta^T A_alpha^-T lambda_alpha.  Chetaev's equations have no multiplier
  states.

The switch costs microseconds, not a walk of the expressions: df/dqdot comes from a
compiled kernel of each chart (its entries as an events kernel, cached on disk with the
scene's kernels; ``Chart.point``), the measures from the k x k determinants on floats,
the new state and the rows mapped home by index maps (the multipliers by A where they
map).  Where the multipliers keep their values and the charts have their kernels, the
whole change is one compiled call (``chart_change``, ``Atlas.change``), and a run whose
charts, events and loops are made runs all its pieces inside one ``interrupt.call``
(``Cold`` where one is not: the run goes on outside it, so that making a chart never
holds back Ctrl-C).

Suslov's equations in the paper's convention (29)-(31) are no chart change away from
each other: the commutator term P_alpha c^alpha weighs the momenta of the dependent
coordinates, and the motions of two splits differ (``split_invariant``).  Such runs, runs
with callable events (functions of one split's state vector), systems with more than 3
constraints, scipy's methods (``scipy-<M>``) and ``split="fixed"`` keep their split and
stop at its edge as before (dla and dvi never solve for the dependent velocities, so no
split's edge stops them).  The compiled methods dop853, dopri5, rk4 and radau switch;
``Scene.run`` calls ``run``, ensembles and sweeps ``begin`` and ``follow`` (the same
continuation, so their runs equal single runs bit for bit).

A switched run is one ``Trajectory`` of the scene: its rows are in the scene's state
layout (the other charts' rows mapped), its dependent velocities, residuals, energy and
first integrals come from each chart's own kernels, dense output re-takes each chart's
own steps, and ``traj.switches`` (also in the diagnostics) lists (time, from, to).

A run with sensitivities (S = dy(t)/d(y0, p)) switches too, each chart with its own
sensitivity kernels.  The flow on the constraint manifold is one flow: written in two
charts, y_beta = Phi(t, y_alpha, p) (``change_map``) carries the motions of one onto
those of the other, so the switch time's dependence on y0 drops out and S goes across
as S_beta = D_y S_alpha + (0 | D_p), D the derivative of the chart change at the switch
point (``Chart.carry``; from the graph, compiled once per pair of charts).  The rows
of other charts, S too, are mapped home the same way.  Ensembles with sensitivities
switch as their single runs do (``follow`` with ``sens``).
"""

from __future__ import annotations

import copy
import math
import time
from itertools import combinations

import numpy as np
import sympy as sp

from ..algebra import dag, linalg
from ..errors import JetnhError
from ..mechanics import principles
from ..mechanics.system import paired_columns
from .methods import projection
from .methods._common import (AT_T_EVAL, ENDPOINTS, EVENT, EVERY_STEP, FINISHED, SINGULAR,
                              STATUS_TEXT, STOPPED, entry_point)
from . import arguments, chart_change, chart_driver, interrupt, loops, methods
from .events import Event, OwnEvent, as_events
from .kernels.calls import Kernel, Rows
from .methods.loop import PAST_EDGE, Control, Result, Watch
from .methods.loop import features as loop_features
from .trajectory import Trajectory

#: the event name of a chart's edge (internal: the stitched run does not report it)
EDGE = "chart edge"
#: the largest number of constraints whose splits are watched (symbolic determinants)
MAX_K = 3
#: an adaptive step of a run that changes chart is no longer than NEAR times the time in
#: which its chart's singularity indicators would reach zero (``loop.near_zero``): the
#: end of every step at least 3 step lengths from the singular set, where the local
#: error of dop853 and dopri5 is in proportion to their estimate again
NEAR = chart_driver.NEAR
#: what a loop's halt flag is made from (a copy: sooner than ``np.zeros``; never written)
_HALT = np.zeros(1, dtype=np.int64)
#: the plans an atlas keeps their marked loop arguments for (``_marked``)
MAX_MARKED = 64
#: ``Atlas.change``: a chart it needs has no kernels yet
MISSING = object()
_F8 = np.dtype(np.float64)
#: the compiled change of chart once loaded (``Atlas.register``)
_CHANGE: list = []


class Cold(Exception):
    """A piece of a run inside one ``interrupt.call`` around the whole run (``follow``'s
    ``halt``) needs what is not made yet (a chart's scene, kernels, events or loop:
    work that could hold back Ctrl-C): the run goes on outside it."""


def split_invariant(principle, convention) -> bool:
    """Whether the motions of ``principle`` in ``convention`` are the same in every split
    (so that a run may change split): all but Suslov's in the paper's convention."""
    p = principles.get(principle)
    return not (p.kappa == "momenta" and not p.restricts(convention))


def splits(system) -> list[tuple[str, ...]]:
    """The splits of ``system`` whose minor df/dqdot^alpha is not identically zero, the
    system's own first."""
    J, k = system.J, system.k
    A = system.jacobian
    own = tuple(s.name for s in system.dependent)
    out = [own]
    for cols in combinations(range(J.n), k):
        names = tuple(J.q[c].name for c in paired_columns(A, cols))    # as with_split's
        if set(names) != set(own) and linalg.numeric_rank(A[:, list(cols)]) == k:
            out.append(names)
    return out


def applies(scene, events) -> bool:
    """Whether a run of ``scene`` with ``events`` watches its chart's edge: at most
    ``MAX_K`` constraints, a split whose minor varies, a principle whose motions do not
    depend on the split, another split to go to, and no callable events."""
    static = scene._memo.get("atlas_applies")
    if static is None:
        sys_ = scene.system
        static = (0 < sys_.k <= MAX_K
                  and not all(e.is_number for e in sys_.jacobian_dependent)
                  and split_invariant(scene.principle, scene.convention)
                  and len(atlas(scene).splits) > 1)
        scene._memo["atlas_applies"] = static
    if not static or events is None:
        return static
    return all(e.is_expression for e in as_events(events))


def atlas(scene) -> "Atlas":
    """The atlas of ``scene`` (built once, kept in its memo; a copy of the scene with the
    same kernels, ``Scene.replace``, takes the first one's charts: ``Atlas.moved``)."""
    found = scene._memo.get("atlas")
    if found is None:
        first = scene._memo.setdefault("atlases", [])      # (shared by the copies)
        found = Atlas(scene) if not first else first[0].moved(scene)
        if not first:
            first.append(found)
        scene._memo["atlas"] = found
    return found


class Chart:
    """One split of an atlas: the positions of its dependent and independent coordinates,
    whether its multipliers weigh the explicit constraints, and its scene (``None`` for a
    chart used only to map a state).  Its kernels, and the compiled df/dqdot, are looked
    up once (a chart switch calls them and nothing else)."""

    def __init__(self, system, split, explicit, scene=None):
        names = [s.name for s in system.J.q]
        self.split = tuple(split)
        self.dep = np.array([names.index(c) for c in split], dtype=np.int64)
        self.ind = np.array([i for i in range(len(names)) if names[i] not in split],
                            dtype=np.int64)
        self._independent = self.ind.tolist()
        self.explicit = explicit
        self.n, self.k = len(names), len(split)
        self.scene = scene
        self._kernels = self._jacobian = self._sens = None
        self._columns: dict = {}
        self._changes: dict = {}
        #: where each velocity is in a state of this chart followed by its aux row
        #: (the dependent velocities first there; counted from the end: set with the
        #: kernels, which give the aux row's length)
        self._velocity_at = None
        self._watches: dict = {}
        self._entries: dict = {}

    @property
    def kernels(self):
        if self._kernels is None:
            kernels = self.scene.kernels
            n_aux = kernels.layout.n_aux
            where = {int(j): self.n + i for i, j in enumerate(self.ind)}
            where.update({int(j): i - n_aux for i, j in enumerate(self.dep)})
            self._velocity_at = [where[j] for j in range(self.n)]
            self._n_aux = kernels.layout.n_aux      # before _kernels: another thread
            self._kernels = kernels                 # reading it finds them set
        return self._kernels

    def watch(self, ce, checked, singular_tol, user_max, counts, edge) -> Watch:
        """What the loop of a piece in this chart watches: the singularity indicators
        (``checked``) and the events ``ce``, each user event with the terminal count left
        to it (``user_max`` less ``counts``), then the edge's one (kept per events when
        there are no user events: the same for every piece)."""
        key = None if user_max else (id(ce), checked, float(singular_tol), edge)
        found = self._watches.get(key) if key is not None else None
        if found is not None and found[0] is ce:
            return found[1]
        left_max = np.array([m - c if m > 0 else 0 for m, c in zip(user_max, counts)]
                            + [1] * edge, dtype=np.int64)
        watch = Watch(len(self.kernels.layout.indicators) if checked else 0,
                      float(singular_tol),
                      ce.direction if ce is not None else loops.NO_EVENTS,
                      left_max if ce is not None else loops.NO_EVENTS)
        if key is not None:
            self._watches[key] = (ce, watch)
        return watch

    def call(self, method, ce, watch, t0, t1, y, p, ctl, te, mode, newton, limit, sens,
             halt=None):
        """``loops.call`` of this chart's scene and kernels (``sens``: the kernels of its
        state augmented by its sensitivities), the loop's entry and callbacks looked up
        once per method, events and loop parts (``loops.entry``).  ``halt``: the flag of
        an ``interrupt.call`` around this one (``follow``): the loop called with it
        directly, or ``Cold`` raised if it is not looked up yet."""
        # (``features`` of the loop, given ``ce``: what ``mode``, the projection and the
        # indicators add to it)
        key = (method, id(ce), sens is not None, mode, ctl.n_hol > 0, watch.n_sing > 0)
        found = self._entries.get(key)
        if found is None or found[0] is not ce:
            if halt is not None:
                raise Cold
            loop, prefix, suffix, callbacks = loops.entry(
                self.scene, methods.method(method), self.kernels, ce, sens, ctl, te, mode,
                watch, newton)
            found = self._entries[key] = (ce, loop, prefix, len(suffix), callbacks)
        _, loop, prefix, n_suffix, _ = found
        # (the arguments after (t0, t1, y0, p) as ``loops.entry`` gives them)
        suffix = (ctl, te, mode, watch) if n_suffix == 4 else (ctl, newton, te, mode, watch)
        tic = time.perf_counter()
        if halt is not None:
            out = loop(*prefix, t0, t1, y, p, *suffix, halt)
        else:
            halt = _HALT.copy()
            out = interrupt.call(loop, halt, limit, (*prefix, t0, t1, y, p, *suffix, halt))
        wall = time.perf_counter() - tic
        loops.on_constraints(self.kernels, ctl, mode, sens, out, p, t0)
        return loops.result(out), wall

    @property
    def jacobian_kernel(self):
        """``kernel(t, y, p, out)``: df/dqdot (k x n, row-major) at a state of this chart,
        compiled once (an events kernel of the entries: expressions in t, q and every
        velocity, cached on disk with the scene's kernels)."""
        if self._jacobian is None:
            ce = self.scene.compile_events(_jacobian_events(self.scene.system))
            self._jacobian = Kernel(ce.uev, (len(self.scene.state_names),
                                             len(self.scene.runtime_params),
                                             self.k * self.n))
        return self._jacobian

    @property
    def sensitivity_kernels(self):
        """The kernels of this chart's state augmented by its sensitivities
        (``kernels.sensitivity_kernels`` of its scene), looked up once."""
        if self._sens is None:
            from .kernels import sensitivity_kernels

            self._sens = sensitivity_kernels(self.scene)
        return self._sens

    def change(self, other) -> "Rows":
        """``rows(ts, Y, p, out)``: D = d(state of ``other``)/d(state here, p) at rows
        of this chart's states, each row n_state x (n_state + runtime parameters)
        row-major: the derivative of the chart change (``change_map``) by the state
        and the runtime parameters, from the graph, compiled once per target (an events
        kernel of its entries, cached on disk with the scene's kernels)."""
        found = self._changes.get(other.split)
        if found is None:
            scene = self.scene
            D = change_map_jacobian(scene, other.split, self.explicit)
            ce = scene.compile_events([Event(e, name=f"D{i}") for i, e in enumerate(D)])
            found = self._changes[other.split] = Rows(
                ce.uev, (len(scene.state_names), len(scene.runtime_params), len(D)))
        return found

    def carry(self, other, t, Y, S, p) -> np.ndarray:
        """The sensitivities ``S`` (``[rows, n_state, n_state + runtime parameters]``)
        of the rows ``(t, Y)`` of this chart in the chart ``other``: D S, plus D's
        parameter columns in S's (the chart change depends on the parameters too)."""
        Y = np.ascontiguousarray(np.atleast_2d(Y), dtype=float)
        t = np.ascontiguousarray(np.broadcast_to(np.asarray(t, dtype=float),
                                                 (Y.shape[0],)))
        n, m = S.shape[-2:]
        D = np.empty((Y.shape[0], n * m))
        if Y.shape[0]:
            self.change(other)(t, Y, np.ascontiguousarray(p, dtype=float), D)
        D = D.reshape(-1, n, m)
        out = D[:, :, :n] @ S
        out[:, :, n:] += D[:, :, n:]
        return out

    def jacobian(self, t, Y, p) -> np.ndarray:
        """df/dqdot at the rows (t, Y) of this chart: [rows, k, n]."""
        kern = self.jacobian_kernel
        out = np.empty((Y.shape[0], self.k * self.n))
        for r in range(Y.shape[0]):
            kern(float(t[r]), Y[r], p, out[r])
        return out.reshape(-1, self.k, self.n)

    def universal(self, t, Y, p, jacobian=False):
        """``(q, qdot, lam, A, aux)`` of rows of this chart: every velocity, the
        multipliers of the constraints as written, df/dqdot (with ``jacobian``, or for
        explicit forms with multipliers; else None) and the aux rows."""
        Y = np.ascontiguousarray(np.atleast_2d(Y), dtype=float)
        t = np.ascontiguousarray(np.atleast_1d(np.asarray(t, dtype=float)))
        n, k = self.n, self.k
        aux = np.empty((Y.shape[0], self.kernels.layout.n_aux))
        if Y.shape[0]:
            self.kernels.aux_rows(t, Y, p, aux)
        qd = np.empty((Y.shape[0], n))
        qd[:, self.ind] = Y[:, n:2 * n - k]
        qd[:, self.dep] = aux[:, :k]
        lam = Y[:, 2 * n - k:]
        explicit = self.explicit and lam.shape[1]
        A = None
        if (jacobian or explicit) and Y.shape[0]:
            A = self.jacobian(t, Y, p)
        if explicit and Y.shape[0]:
            lam = np.linalg.solve(np.transpose(A[:, :, self.dep], (0, 2, 1)),
                                  lam[:, :, None])[:, :, 0]
        return Y[:, :n], qd, lam, A, aux

    def velocities(self, t, y, p) -> np.ndarray:
        """Every velocity at one state ``y`` of this chart (the dependent ones from its
        aux kernel)."""
        return np.array(self.velocity_list(t, y, p))

    def velocity_list(self, t, y, p) -> list:
        """``velocities`` as a list (a few numbers: copied through lists, cheaper than
        numpy's calls on small arrays)."""
        kern = self.kernels
        aux = np.empty(self._n_aux)
        kern.aux(t, y, p, aux)
        row = y.tolist() + aux.tolist()
        return [row[i] for i in self._velocity_at]

    def point(self, t, y, p):
        """``universal`` of one state ``y`` (C-contiguous floats) with df/dqdot:
        ``(q, qdot, lam, A)``, A k x n; the same numbers, without the rows."""
        n, k = self.n, self.k
        qd = self.velocities(t, y, p)
        A = np.empty(k * n)
        self.jacobian_kernel(t, y, p, A)
        A = A.reshape(k, n)
        lam = y[2 * n - k:]
        if self.explicit and lam.shape[0]:
            lam = np.linalg.solve(A[:, self.dep].T[None], lam[None, :, None])[0, :, 0]
        return y[:n], qd, lam, A

    def jacobian_rows(self, t, y, p) -> list:
        """df/dqdot at one state ``y`` (C-contiguous floats) as k lists of n floats (the
        numbers of ``point``'s A)."""
        n = self.n
        A = np.empty(self.k * n)
        self.jacobian_kernel(t, y, p, A)
        flat = A.tolist()
        return [flat[i:i + n] for i in range(0, len(flat), n)]

    def columns_of(self, other, as_list=False) -> np.ndarray | list:
        """Where the columns of ``other``'s state are in a row of this chart's state
        followed by its aux row, when the multipliers keep their values (not
        ``explicit``): coordinates, ``other``'s independent velocities (independent
        velocities here or dependent ones, the first of aux), multipliers (``as_list``:
        as a list)."""
        found = self._columns.get(other.split)
        if found is None:
            n, k = self.n, self.k
            n_y = len(self.scene.state_names)
            where = {int(j): n + i for i, j in enumerate(self.ind)}
            where.update({int(j): n_y + i for i, j in enumerate(self.dep)})
            cols = [*range(n), *(where[int(j)] for j in other.ind), *range(2 * n - k, n_y)]
            found = self._columns[other.split] = (np.array(cols, dtype=np.int64), cols)
        return found[as_list]

    def state(self, q, qd, lam, A) -> np.ndarray:
        """Rows of this chart's state from ``(q, qdot, lam, A)`` (``universal``)."""
        if self.explicit and lam.shape[1]:
            lam = np.einsum("rai,ra->ri", A[:, :, self.dep], lam)
        return np.concatenate((q, qd[:, self.ind], lam), axis=1)

    def state_at(self, q, qd, lam, A) -> np.ndarray:
        """``state`` of one point (``point``)."""
        if self.explicit and lam.shape[0]:
            return self.state(q[None], qd[None], lam[None], A[None])[0]
        v = qd.tolist()
        return np.array(q.tolist() + [v[i] for i in self._independent] + lam.tolist())


def _det(M) -> float:
    """The determinant of a k x k matrix (rows of floats): by cofactors for k <= 3
    (``MAX_K``, the splits a run watches), else by LAPACK."""
    if len(M) <= 1:
        return M[0][0] if M else 1.0
    if len(M) == 2:
        return M[0][0] * M[1][1] - M[0][1] * M[1][0]
    if len(M) > 3:
        return float(np.linalg.det(np.array(M, dtype=float)))
    (a, b, c), (d, e, f), (g, h, i) = M
    return a * (e * i - f * h) - b * (d * i - f * g) + c * (d * h - e * g)


def measures_at(A, columns) -> list[float]:
    """m_beta = det(A_beta)^2 / det(A A^T) of the split of each entry of ``columns`` (the
    columns of its minor) at one point (A: k x n floats, or k lists of them); all 0
    where A has rank < k (no split is regular).  ``Atlas.measures`` (the charts of a run) and
    ``regular.best`` (every choice of k coordinates) both take them from here."""
    rows = A if type(A) is list else np.asarray(A, dtype=float).tolist()
    if len(rows) == 1:          # one constraint: the same sums, without the matrices
        r = rows[0]
        gram = sum([a * a for a in r])
        if not gram > 0.0:
            return [0.0] * len(columns)
        return [r[c] ** 2 / gram for c, in columns]
    gram = _det([[sum(a * b for a, b in zip(r, s)) for s in rows] for r in rows])
    if not gram > 0.0:
        return [0.0] * len(columns)
    return [_det([[r[c] for c in cols] for r in rows]) ** 2 / gram for cols in columns]


def split_measure_of(A, columns) -> np.ndarray:
    """det(A_columns)^2 / det(A A^T), the measure of one split, for each k x n matrix of
    the stack ``A`` (``[..., k, n]``, in numpy); 0 where A has rank < k.  One point and
    several splits: ``measures_at``."""
    gram = np.linalg.det(A @ np.swapaxes(A, -1, -2))
    minor = np.linalg.det(A[..., columns])
    with np.errstate(divide="ignore", invalid="ignore"):
        out = np.where(gram > 0, minor ** 2 / gram, 0.0)
    return np.where(np.isfinite(out), out, 0.0)


def _jacobian_events(system):
    return [Event(e, name=f"A{i}") for i, e in enumerate(system.jacobian)]


def change_map(scene, split, explicit) -> list:
    """The state of the chart of ``split`` as expressions in the state of ``scene``'s
    split (and t and the parameters): the coordinates kept, the velocities independent
    there, each its symbol or phi^alpha of ``scene``'s split where it is dependent here,
    the multipliers kept, or with ``explicit`` mapped as lambda_beta = A_beta^T
    A_alpha^-T lambda_alpha (the module docstring)."""
    sys_ = scene.system
    J = sys_.J
    phi = dict(sys_.phi)
    names = [s.name for s in J.q]
    dep = [names.index(c) for c in split]
    vel = [phi.get(J.qd[i], J.qd[i]) for i in range(J.n) if i not in dep]
    lam = list(principles.get(scene.principle).multiplier_symbols(sys_))
    if explicit and lam:
        A = sp.Matrix(sys_.k, J.n, [dag.xreplace(e, phi) for e in sys_.jacobian])
        univ = linalg.solve(A[:, list(sys_.dep_index)].T, sp.Matrix(lam))
        lam = list(A[:, dep].T * univ)
    return [*J.q, *vel, *lam]


def change_map_jacobian(scene, split, explicit) -> list:
    """The entries of d(``change_map``)/d(state of ``scene``, runtime parameters),
    row-major (``dag.jacobian``: the graph's derivatives, shared subexpressions)."""
    sys_ = scene.system
    by_name = {s.name: s for s in (*sys_.J.q, *sys_.independent_velocities,
                                   *principles.get(scene.principle).multiplier_symbols(sys_),
                                   *sys_.parameters)}
    by = [by_name[n] for n in (*scene.state_names, *scene.runtime_params)]
    return list(dag.jacobian(change_map(scene, split, explicit), by))


class Atlas:
    """The charts of a scene's system (``splits``), each a ``Scene`` of
    ``system.with_split`` built when a run first enters it; ``eps`` the edge of every
    chart."""

    def __init__(self, home):
        self.home = home
        self.splits = splits(home.system)
        self.eps = 1.0 / (4 * len(self.splits))
        p = principles.get(home.principle)
        self.explicit = bool(p.multipliers) and p.form(home.form).explicit
        self._own = Chart(home.system, self.splits[0], self.explicit, home)
        #: the charts of the other splits, built when a run first enters them
        self.charts: dict = {}
        #: each split as a chart that only maps states (``Chart.state``)
        self.maps = {s: Chart(home.system, s, self.explicit) for s in self.splits}
        #: the columns of each split's minor of df/dqdot (in increasing order, as
        #: ``regular.best`` takes them: the same split measured the same to the bit)
        self.columns = [sorted(m.dep.tolist()) for m in self.maps.values()]
        self._events: dict = {}
        self._edges: dict = {}
        #: what the compiled change of chart reads (``chart_change``): the splits' index
        #: maps, their kernels' addresses (filled as charts get their kernels:
        #: ``_register``) and the kernels kept alive for them
        self._index = {s: i for i, s in enumerate(self.splits)}
        n, k = home.system.J.n, home.system.k
        table = np.zeros((1 + len(self.splits), max(5, k + n)), dtype=np.int64)
        table[0, :5] = (n, k, len(home.state_names), len(home.runtime_params),
                        len(self.splits))
        for i, (m, cols) in enumerate(zip(self.maps.values(), self.columns)):
            table[1 + i, :k + n] = [*m.dep.tolist(), *cols, *m.ind.tolist()]
        self._table = table
        self._addr = np.zeros((3, len(self.splits)), dtype=np.int64)
        self._alive: dict = {}
        #: what ``chart_driver`` takes, per method, output mode and watch (``_drive_inputs``)
        self._drives: dict = {}
        #: whether the last run of each of those reached an edge (``run``)
        self._reaches: dict = {}
        #: the loop's arguments after ``p`` that test the edge at a run's start, per
        #: plan (``_marked``)
        self._marked: dict = {}

    @property
    def own(self) -> Chart:
        return self._own

    def moved(self, home) -> "Atlas":
        """This atlas for ``home``, a copy of its home with the same kernels (other
        initial values, time span or run-time parameter values: ``Scene.replace``): its
        own chart ``home``'s, the other charts (each a scene of its split, compiled
        once), maps and compiled events shared."""
        new = object.__new__(Atlas)
        new.__dict__.update(self.__dict__)
        new.home = home
        new._own = copy.copy(self._own)         # (its kernels and df/dqdot: the same)
        new._own.scene = home
        return new

    def chart(self, split, t0, y) -> Chart:
        """The chart of ``split`` (its scene built at the state ``y`` of it at ``t0``
        the first time)."""
        if split == self.splits[0]:
            return self._own
        found = self.charts.get(split)
        if found is None:
            home = self.home
            sys_ = home.system.with_split(list(split))
            mult = [s.name for s in principles.get(home.principle).multiplier_symbols(sys_)]
            names = ([s.name for s in sys_.J.q]
                     + [v.name for v in sys_.independent_velocities] + mult)
            scene = home.replace(system=sys_,
                                 initial=dict(zip(names, np.asarray(y, dtype=float).tolist())),
                                 t_span=(t0, home.t_span[1]),
                                 integrals=self.rewrite(home.integrals, sys_))
            found = self.charts[split] = Chart(sys_, split, self.explicit, scene)
        return found

    def rewrite(self, exprs: dict, sys_) -> dict:
        """Expressions in the home split's multipliers, rewritten in those of ``sys_``
        (the map of the module docstring)."""
        p = principles.get(self.home.principle)
        old = p.multiplier_symbols(self.home.system)
        new = p.multiplier_symbols(sys_)
        if not old or tuple(old) == tuple(new):
            return dict(exprs)
        if not self.explicit:
            sub = dict(zip(old, new))
        else:
            A = self.home.system.jacobian
            lam = linalg.solve(A[:, list(sys_.dep_index)].T, sp.Matrix(new))
            sub = dict(zip(old, list(A[:, list(self.home.system.dep_index)].T * lam)))
        return {k: sp.sympify(v, strict=True).xreplace(sub) for k, v in exprs.items()}

    def edge(self, chart) -> sp.Expr:
        """det(A_alpha)^2 - eps det(A A^T) of the chart's split (A = df/dqdot)."""
        sys_ = chart.scene.system
        A = sys_.jacobian
        Ad = A[:, list(sys_.dep_index)]
        gram = A * A.T
        if sys_.k == 1:
            return Ad[0, 0]**2 - sp.Float(self.eps) * gram[0, 0]
        return (Ad.det(method="berkowitz")**2
                - sp.Float(self.eps) * gram.det(method="berkowitz"))

    def change(self, chart, t, y, p):
        """``switch`` at (t, y) of ``chart`` (a state moved onto the holonomic
        constraints, C-contiguous floats) in one compiled call (``chart_change``): ``(new
        chart, its state)``, None, or ``MISSING`` where a chart it needs has no kernels
        here yet, or before the compiled change is loaded (``switch`` in Python then,
        which makes them: ``register``; nothing is compiled here)."""
        cur = self._index[chart.split]
        if not _CHANGE or not self._addr[0, cur]:
            return MISSING
        if not (type(y) is np.ndarray and y.dtype == _F8 and y.ndim == 1
                and y.flags.c_contiguous and type(p) is np.ndarray and p.dtype == _F8
                and p.ndim == 1 and p.flags.c_contiguous):
            raise JetnhError("a chart change takes a state and parameters as C-contiguous "
                             "float64 vectors (np.ascontiguousarray(x, dtype=float))")
        out = np.empty(self._table[0, 2])
        i = _CHANGE[0](t, y, p, self._table, self._addr, self.eps, cur, out)
        if i >= 0:
            return self.chart(self.splits[i], t, out), out
        return None if i == -1 else MISSING

    def made(self, chart) -> bool:
        """Whether ``chart``'s df/dqdot and every chart's kernels are made (``register``):
        a change of chart from ``chart`` makes nothing."""
        return bool(self._addr[0, self._index[chart.split]]) and bool(self._addr[1].all())

    def register(self, *charts):
        """Give the compiled change of chart the kernels of ``charts`` that are made
        (their aux row's length before its address: a thread reading them meanwhile sees
        the length first), kept alive with the atlas; the compiled change loaded (or
        compiled, on a machine's first use) here, where a switch makes what it needs."""
        if not _CHANGE and not self.explicit:
            _CHANGE.append(chart_change.change())
        for chart in charts:
            i = self._index[chart.split]
            kern, jac = chart._kernels, chart._jacobian
            if kern is not None and not self._addr[1, i]:
                self._alive[1, i] = kern
                self._addr[2, i] = kern.layout.n_aux
                self._addr[1, i] = kern.aux_fp.address
            if jac is not None and not self._addr[0, i]:
                self._alive[0, i] = jac
                self._addr[0, i] = jac.address.address

    def measures(self, A) -> list[float]:
        """m_beta = det(A_beta)^2 / det(A A^T) of every split (in the order of
        ``splits``) at one point (A: k x n); all 0 where A has rank < k (no split is
        regular; ``measures_at``)."""
        return measures_at(A, self.columns)

    def events(self, chart, user, edge: bool, made=False):
        """The compiled events of a run in ``chart``: the user's (rewritten in its
        multipliers) and, with ``edge``, its edge last; or None.  Kept per chart, user
        events and edge, so that repeated runs build nothing (the key holds the
        expressions themselves: hashed once by sympy, compared by identity first).
        ``made``: ``Cold`` raised where they are not made yet."""
        key = (chart.split, edge, tuple((e.fun, e.direction, e.max_events, e.name)
                                        for e in user) if user else ())
        found = self._events.get(key)
        if found is None:
            if made:
                raise Cold
            found = self._events[key] = (self._compile_events(chart, user, edge),)
        return found[0]

    def edge_kernel(self, ce) -> tuple[Kernel, int]:
        """``(kernel(t, y, p, out), len(ce))``: the compiled events ``ce`` of a run in
        the scene's own chart (``events``, its edge last) called from Python, made
        once."""
        return self.edge_call(ce)[:2]

    def edge_call(self, ce) -> tuple:
        """``(kernel, len(ce), entry, address, sizes)``: ``edge_kernel`` and the
        machine-code entry of its trampoline with the trampoline's first arguments
        (``_common.entry_point``: ``entry(address, sizes, t, y, p, out)`` skips numba's
        type dispatch; its caller passes exactly the declared types), made once."""
        found = self._edges.get(id(ce))
        if found is None or found[0] is not ce:
            home = self.home
            kernel = Kernel(ce.uev, (len(home.state_names), len(home.runtime_params),
                                     len(ce)))
            found = self._edges[id(ce)] = (ce, (kernel, len(ce),
                                                entry_point(kernel.func), *kernel.args))
        return found[1]

    def _compile_events(self, chart, user, edge):
        sys_ = chart.scene.system
        evs = [Event(e2, terminal=e.max_events, direction=e.direction, name=e.name)
               for e, e2 in zip(user, self.rewrite({i: e.fun for i, e in enumerate(user)},
                                                   sys_).values())]
        if edge:
            evs.append(OwnEvent(self.edge(chart), terminal=True, direction=-1, name=EDGE))
        return chart.scene.compile_events(evs) if evs else None


# ---------------------------------------------------------------------- the driver
def run(home, plan, y0, p, build):
    """``Scene.run`` of a scene whose split has an edge (``applies``) by its ``plan``
    (``solve.plan``): the plan's loop in the scene's own chart, watching the chart's
    edge as its last event; a run that ends before the edge is that loop's Trajectory
    as any run's, one that reaches it goes on in the split of largest measure with the
    state mapped (``follow``): one Trajectory of ``home``.  ``build``: the Trajectory of
    a piece from its loop's result (``solve.trajectory``).  A run with sensitivities
    (``plan.sens``; ``y0`` holds the state and S(t0) after it) runs each chart with its
    own kernels, S carried across every switch (``Chart.carry``)."""
    at = atlas(home)
    tic = time.perf_counter()
    quick = (plan.events is None and plan.sens is None and plan.limit is None
             and not plan.ctl.n_hol)
    if quick:
        # (most runs: no user events, sensitivities, time budget or holonomic constraints)
        key = (plan.method.name, plan.mode, plan.checked, plan.singular_tol)
        if at._reaches.get(key):
            # (runs of a plan whose last run reached the edge: the whole run in one
            # compiled call; a run that does not is cheaper as one loop call, below)
            driven = _driven(home, at, plan, y0, p, build, tic, key)
            if driven is not None:
                return driven
        marked = _marked(at, plan)
        if marked is not None or not _edge_at(at, plan.ce, plan.t0, y0, p) < 0.0:
            # the plan's loop called as a run that cannot switch calls it: a run that
            # finishes is its Trajectory at once; one that reaches the edge goes on in
            # a second call (``_made_onward``); one that starts past it (``marked``:
            # the loop tests that, ``PAST_EDGE``; else ``_edge_at``) goes on below
            halt = _HALT.copy()
            tic_loop = time.perf_counter()
            out = interrupt.call(plan.entry, halt, None,
                                 (*plan.head, y0, p, *(marked or plan.suffix), halt))
            wall = time.perf_counter() - tic_loop
            status, dense = out[0], plan.dense_ends
            if status == FINISHED:
                return Trajectory._of_loop(home, out, p, plan.method.name, _FINISHED_TEXT,
                                           wall, plan.kern,
                                           None if dense is None else dense[0])
            if not (status == SINGULAR and out[11] == PAST_EDGE):
                if dense is not None:       # stopped inside a step or not
                    dense = dense[status == EVENT or status == SINGULAR]
                ahead = None
                if status == EVENT or status == SINGULAR:       # (the edge: its one event)
                    ahead = interrupt.call(_made_onward, halt, None,
                                           (at, plan, out, wall, dense, y0, p, build, tic,
                                            halt))
                return _on_from(home, at, plan, y0, p, (), build, tic, key, out, wall,
                                dense, ahead)
    user = as_events(plan.events)
    sens, t0, t1, ctl = plan.sens, plan.t0, plan.t1, plan.ctl
    method = plan.method.name
    n = len(home.state_names)
    key = (method, plan.mode, plan.checked, plan.singular_tol)
    if (not quick and sens is None and plan.limit is None and not user
            and at._reaches.get(key)):
        driven = _driven(home, at, plan, y0, p, build, tic, key)
        if driven is not None:
            return driven
    start = (own_edge(at, plan.ce, t0, y0, p) < 0.0
             and begin(at, user, t0, y0[:n], p, past=True))
    if start and start[2]:          # past the edge at t0: the split of largest measure
        chart, y, first = start
        if sens is not None:        # S(t0) in the chart the run starts in
            S = at.own.carry(chart, t0, y0[:n], y0[n:].reshape(1, n, -1), p)
            y = np.concatenate((y, S.ravel()))
        parts, switches = follow(at, method, chart, t0, y, t1, p, user,
                                 np.zeros(len(user), np.int64), ctl, ctl.max_steps,
                                 plan.te, plan.mode, plan.dense, plan.checked,
                                 plan.singular_tol, plan.newton, plan.limit,
                                 _Piece.maker(build), sens=sens is not None, tic=tic)
        return stitch(home, at, method, p, parts, first + switches, user, plan.mode,
                      time.perf_counter() - tic)
    # the scene's own chart: the plan's loop, as a run that cannot switch calls it (and
    # the pieces after it in the same ``interrupt.call``: ``_ahead``)
    halt = _HALT.copy()
    out, wall, dense, ahead = interrupt.call(_ahead, halt, plan.limit,
                                             (at, plan, y0, p, user, build, halt, tic))
    return _on_from(home, at, plan, y0, p, user, build, tic, key, out, wall, dense, ahead)


def _on_from(home, at, plan, y0, p, user, build, tic, key, out, wall, dense, ahead):
    """``run`` after the first piece's loop (``out``, the loop's tuple; ``ahead``: the
    pieces after it made in the same ``interrupt.call``, or None): a run that did not
    stop at the edge (nor singular) is that loop's Trajectory; one that did goes on
    (``follow``) and is stitched."""
    status, n_ev, method = out[0], out[10], plan.method.name
    if ahead is None and not (status == EVENT and out[8][n_ev - 1] == len(user)
                              or status == SINGULAR):
        # (not at the edge, nor stopped singular: perhaps past it, ``follow``)
        if status == FINISHED and not user and plan.sens is None:   # most runs: at once
            return Trajectory._finished(home, (out[1], out[2], out[3]), p, method,
                                        _FINISHED_TEXT, (out[4], wall, home.projected),
                                        plan.kern, dense)
        # (a Result: its rows checked again where the projection moved them)
        return build(home, method, loops.result(out) if plan.ctl.n_hol else out, wall,
                     plan.kern, plan.ce, p, plan.t0, y0, plan.singular_tol, plan.checked,
                     plan.limit, dense, n_events=len(user), sens=plan.sens)
    parts, switches = ahead or _onward_from(at, plan, out, wall, dense, y0, p, user,
                                            build, tic)
    at._reaches[key] = True
    return stitch(home, at, method, p, parts, switches, user, plan.mode,
                  time.perf_counter() - tic)


_FINISHED_TEXT = STATUS_TEXT[FINISHED]


def _ahead(at, plan, y0, p, user, build, halt, tic):
    """``run``'s first piece inside its ``interrupt.call`` (``halt``): the plan's loop,
    its rows onto the holonomic constraints and its dense record; a run without a time
    budget or sensitivities that stopped at the edge goes on in the same call
    (``follow`` with ``halt``: one watch for the whole run), unless a piece needs what is
    not made yet (``Cold``: the run goes on outside).  Returns ``(the loop's tuple, its
    wall time, its dense record, follow's (parts, switches) or None)``."""
    tic_loop = time.perf_counter()
    out = plan.entry(*plan.head, y0, p, *plan.suffix, halt)
    wall = time.perf_counter() - tic_loop
    sens = plan.sens
    loops.on_constraints(plan.kern, plan.ctl, plan.mode, sens, out, p, plan.t0)
    status, dense = out[0], plan.dense_ends
    if dense is not None:           # stopped inside a step or not
        dense = dense[status == EVENT or status == SINGULAR]
        if sens is not None:        # the run's own (``build`` adds its rows)
            dense = dict(dense)
    if ((status == EVENT and out[8][out[10] - 1] == len(user) or status == SINGULAR)
            and plan.limit is None and sens is None):
        try:
            return out, wall, dense, _onward_from(at, plan, out, wall, dense, y0, p, user,
                                                  build, tic, halt)
        except Cold:
            pass
    return out, wall, dense, None


def _onward_from(at, plan, out, wall, dense, y0, p, user, build, tic, halt=None):
    """``follow`` of ``run`` from its first piece (``out``, the loop's tuple, stopped
    at the edge of the scene's own chart)."""
    ctl = plan.ctl
    return follow(at, plan.method.name, at.own, plan.t0, y0, plan.t1, p, user,
                  np.zeros(len(user), np.int64), ctl, ctl.max_steps, plan.te, plan.mode,
                  plan.dense, plan.checked, plan.singular_tol, plan.newton, plan.limit,
                  _Piece.maker(build), sens=plan.sens is not None, tic=tic,
                  ran=(loops.result(out), wall, plan.ce, plan.watch, dense), halt=halt)


def _made_onward(at, plan, out, wall, dense, y0, p, build, tic, halt):
    """``_onward_from`` of a run without user events inside an ``interrupt.call``
    (``halt``), or None where a piece needs what is not made yet (``Cold``: the run goes
    on outside)."""
    try:
        return _onward_from(at, plan, out, wall, dense, y0, p, (), build, tic, halt)
    except Cold:
        return None


def _driven(home, at, plan, y0, p, build, tic, key):
    """``run`` of a run without user events, sensitivities or time budget in one
    compiled call (``chart_driver``: every piece, step start, cut and change of chart),
    where its method, charts and multipliers allow: the Trajectory that ``run``'s pieces
    would make (its pieces made when first read, ``_Recorded``), or None (the run is
    ``run``'s: not for the driver, or a chart not made yet)."""
    got = _drive_inputs(at, plan, key)
    if got is None:
        return None
    entry, addr, n_sing, edge_dir, edge_max = got
    halt = _HALT.copy()
    (code, n_p, n_sw, n_rows, status, steps, rejected, nfev, partial, once, I,
     B) = interrupt.call(entry, halt, None, (
        addr, n_sing, plan.t0, plan.t1, y0, p, plan.ctl, plan.te, plan.mode,
        float(plan.singular_tol), edge_dir, edge_max, loops.NO_EVENTS, halt, at._table,
        at._addr, at.eps, 0))
    wall = time.perf_counter() - tic
    if code:
        return None
    method, record = plan.method.name, (n_p, n_sw, n_rows, I, B)
    if once:                                # (never at the edge)
        at._reaches[key] = False
    if status != FINISHED:                  # (the reasons of its stop: ``stitch``)
        parts = _recorded_parts(at, plan, p, build, wall, record)
        return stitch(home, at, method, p, parts, _switches(at, record), (), plan.mode,
                      wall)
    counts = ((steps, rejected, nfev), wall, home.projected)
    dense = plan.dense_ends
    if dense is not None:
        dense = dense[partial]
    if once:
        _, TS, YS = chart_driver.unpacked(record, len(home.state_names))
        return Trajectory._finished(home, (TS, YS, n_rows), p, method, _FINISHED_TEXT,
                                    counts, plan.kern, dense)
    return Trajectory._switched(home, p, method, _FINISHED_TEXT, counts, at.own.kernels,
                                dense, _Recorded(at, plan, p, build, wall, record),
                                _switches(at, record))


def _switches(at, record) -> tuple:
    """The switches ``{"t", "from", "to"}`` of a run that ``chart_driver`` recorded
    (``record``: ``(pieces, switches, rows, I, B)``; switch ``j``'s time is ``F[j, SW_T]``,
    at ``B[j * width + SW_T]``; a loop of ``item`` reads: the fastest for a few)."""
    splits, n_sw, I, B = at.splits, record[1], record[3], record[4]
    width = _N_F + 3 * len(at.home.state_names)
    out = []
    for j in range(n_sw):
        out.append({"t": B.item(j * width + _SW_T), "from": [*splits[I.item(j, _SW_FROM)]],
                    "to": [*splits[I.item(j, _SW_TO)]]})
    return tuple(out)


_N_F, _SW_T, _SW_FROM, _SW_TO = (chart_driver.N_F, chart_driver.SW_T, chart_driver.SW_FROM,
                                 chart_driver.SW_TO)


def _drive_inputs(at, plan, key):
    """What ``chart_driver.drive`` takes for ``plan`` beyond the run's own arguments:
    ``(entry, addresses, indicators per chart, the edge's direction and count)``, or
    None where the run is not for it (an implicit method, multipliers mapped by A,
    holonomic constraints, events other than the edge) or its driver is not compiled
    (``chart_driver.drive``).  The addresses of each chart
    whose kernels and edge are made (rows of zeros elsewhere: the driver hands the run
    back there), kept until another chart is made."""
    found = at._drives.get(key)
    made = (len(at.charts), len(at._events))
    if found is not None and found[0] == made:
        return found[1]
    inputs = None
    ce, watch = plan.ce, plan.watch
    if (plan.method.solver is methods.Solver.EXPLICIT and not at.explicit
            and not plan.ctl.n_hol and ce is not None and len(ce) == 1
            and watch.ev_max.tolist() == [1] and watch.ev_dir.tolist() == [-1]):
        parts = loop_features(plan.ctl, plan.mode, watch)
        N = len(at.splits)
        addr = np.zeros((N, 4), dtype=np.int64)
        n_sing = np.zeros(N, dtype=np.int64)
        for i, split in enumerate(at.splits):
            chart = at.own if i == 0 else at.charts.get(split)
            edge = at._events.get((split, True, ()))
            if chart is None or edge is None or edge[0] is None:
                continue
            kern = chart.kernels        # (of a chart's scene: made with it)
            addr[i] = (kern.rhs_fp.address, kern.sing_fp.address, edge[0].uev.address,
                       kern.hol_or_none.address)
            n_sing[i] = len(kern.layout.indicators) if plan.checked else 0
        entry = chart_driver.drive(plan.method.name, parts)
        if entry is not None:       # (else not compiled yet: ``precompile``)
            inputs = (entry, addr, n_sing, np.array([-1], dtype=np.int64),
                      np.array([1], dtype=np.int64))
    at._drives[key] = (made, inputs)
    return inputs


def _recorded_parts(at, plan, p, build, wall, record):
    """``follow``'s parts ``[(chart, piece, what re-running it needs)]`` of the run
    ``chart_driver`` recorded (``record``: ``(pieces, switches, rows, I, B)``,
    ``chart_driver.unpacked``)."""
    from . import chart_driver as cd

    n = len(at.home.state_names)
    n_p, I = record[0], record[3]
    F, TS, YS = cd.unpacked(record, n)
    ctl, make = plan.ctl, _Piece.maker(build)
    parts = []
    for k in range(n_p):
        i, f = I[k], F[k]
        split = at.splits[i[cd.C_SPLIT]]
        chart = at.chart(split, f[cd.C_T], None)
        edge = bool(i[cd.C_EDGE])
        ce = at.events(chart, (), edge)
        if i[cd.C_FIRST]:
            seg_ctl, watch = ctl, plan.watch
            dense = plan.dense_ends
            dense = None if dense is None else dense[int(i[cd.C_PARTIAL])]
        else:
            c = list(_onward(ctl, int(i[cd.C_MAXSTEPS]), int(i[cd.C_NSTEPS]), edge))
            c[_MAX_STEP] = float(f[cd.C_MAXSTEP])
            seg_ctl = ctl._make(c)
            watch = chart.watch(ce, plan.checked, plan.singular_tol, [], (), edge)
            dense = (None if plan.dense is None else
                     {**plan.dense, "partial_last": bool(i[cd.C_PARTIAL])})
        a, rows, n_ev = int(i[cd.C_ROW0]), int(i[cd.C_ROWS]), int(i[cd.C_NEV])
        y_start = f[cd.N_F:cd.N_F + n]
        out = Result(int(i[cd.C_STATUS]), TS[a:a + rows], YS[a:a + rows], rows,
                     tuple(int(c) for c in i[cd.C_STEPS:cd.C_NFEV + 1]),
                     float(f[cd.C_TEND]), f[cd.N_F + n:cd.N_F + 2 * n],
                     f[cd.C_EVT:cd.C_EVT + n_ev], i[cd.C_EVI:cd.C_EVI + n_ev],
                     f[None, cd.N_F + 2 * n:cd.N_F + 3 * n][:n_ev], n_ev,
                     int(i[cd.C_SING]))
        t = float(f[cd.C_T])
        seg = make(chart.scene, plan.method.name, out, wall if k == 0 else 0.0,
                   chart.kernels, ce, p, t, y_start, plan.singular_tol, plan.checked,
                   None, dense, n_events=0, sens=None)
        parts.append((chart, seg, (t, y_start, float(f[cd.C_TTO]), seg_ctl, watch, ce,
                                   None)))
    return parts


def own_edge(at, ce, t, y, p) -> float:
    """The edge indicator of the scene's own chart (the last of its compiled events
    ``ce``, ``Atlas.events``) at the state ``y`` (its first entries) at ``t``: negative
    past the edge."""
    kernel, n = at.edge_kernel(ce)
    out = np.empty(n)
    kernel(float(t), y, p, out)
    return float(out[-1])


def _marked(at, plan):
    """``plan.suffix`` with ``Control.edge = -1`` (made once per plan): its loop returns
    at once (``PAST_EDGE``) where a run of ``run``'s quick route starts past the edge;
    None where the loop has no such test (radau; the fixed steps, whose ``edge`` is
    ``NEAR``: ``_edge_at`` tests it)."""
    suffix = plan.suffix
    found = at._marked.get(id(suffix))
    if found is None or found[0] is not suffix:
        marked = None
        if plan.method.solver is methods.Solver.EXPLICIT and plan.ctl.edge == 0.0:
            marked = (suffix[0]._replace(edge=-1.0), *suffix[1:])
        if len(at._marked) >= MAX_MARKED:     # (plans are dropped: ``solve.keep``)
            at._marked.clear()
        found = at._marked[id(suffix)] = (suffix, marked)
    return found[1]


def _edge_at(at, ce, t, y, p) -> float:
    """``own_edge`` of a run's own arrays (``y``, ``p``: C-contiguous float64 vectors,
    ``t`` a float, as ``chart_driver.drive`` takes them): its kernel's trampoline called
    at its machine-code entry (``Atlas.edge_call``), without numba's type dispatch."""
    _, n, entry, address, sizes = at.edge_call(ce)
    out = np.empty(n)
    entry(address, sizes, t, y, p, out)
    return out[n - 1]


def begin(at, user, t0, y0, p, past=False):
    """The chart a run from (t0, y0) (the scene's state) starts in: the scene's own,
    unless that is already past its edge there (then the split of largest measure);
    ``(chart, state in it, [the switch at t0] or [])``.  ``past``: the edge indicator is
    known to be negative there (``own_edge``)."""
    own = at.own
    if not past and not own_edge(at, at.events(own, user, True), t0, y0, p) < 0.0:
        return own, y0, []
    point = own.point(float(t0), np.ascontiguousarray(y0, dtype=float), p)
    if not at.measures(point[3])[0] < at.eps:
        return own, y0, []
    target = _target(at, own, float(t0), p, *point)
    if target is None:
        return own, y0, []
    chart, y = target
    return chart, y, [{"t": t0, "from": list(own.split), "to": list(chart.split)}]


def follow(at, method, chart, t, y, t1, p, user, counts, ctl, steps_left, te, mode, dense, checked,
           singular_tol, newton, limit, build, first=True, h_fixed=None, edge=True,
           sens=False, tic=None, ran=None, halt=None):
    """Run from (t, y) in ``chart`` to ``t1``, changing chart at every edge; returns the
    pieces ``[(chart, trajectory of the chart's scene made by ``build``, what re-running
    it needs)]`` and the switches.  ``counts``: occurrences of the user events so far
    (terminal counts go on); ``first``: whether (t, y) starts the run (else the run goes
    on after a switch); ``edge``: whether to watch the chart's edge; ``sens``: ``y``
    holds the state and its sensitivities after it (each chart runs with its
    ``sensitivity_kernels``, S carried across a switch by ``Chart.carry``); ``tic``: when
    the run began (``limit`` counts from there); ``ran``: the first piece's loop already
    called (``run``: the plan's call), ``(Result, wall time, events, watch, dense)``;
    ``halt``: the flag of an ``interrupt.call`` around this one (no ``limit``: ``run``'s
    one watch of the whole run), each loop called with it, ``Cold`` raised where a piece
    needs what is not made yet."""
    user_max = [e.max_events for e in user]
    parts, switches = [], []
    direction = 1.0 if t1 >= t else -1.0
    if h_fixed is None:
        h_fixed = (t1 - t) / ctl.n_steps if ctl.n_steps > 0 else 0.0
    if tic is None:
        tic = time.perf_counter()
    near = None             # (span, depth): the shorter steps of an approach to the edge
    while True:
        scene, kern = chart.scene, chart.kernels
        ksens = chart.sensitivity_kernels if sens else None
        t_to = t1
        if ran is not None:
            (out, wall, ce, watch, seg_dense), ran = ran, None
            seg_ctl, seg_te = ctl, te
        else:
            ce = at.events(chart, user, edge, halt is not None)
            watch = chart.watch(ce, checked, singular_tol, user_max, counts, edge)
            seg_ctl, seg_te = ctl, te
            if parts or not first or near is not None:
                seg_ctl = _onward(ctl, max(steps_left, 0), _n_steps(ctl, t, t1, h_fixed),
                                  edge)
                if near is not None:        # the part of the step that crossed the edge
                    t_to, seg_ctl = _approach(seg_ctl, t, t1, h_fixed, near[0])
                if mode == AT_T_EVAL:
                    seg_te = np.ascontiguousarray(te[direction * (te - t) > 0.0])
            left = None if limit is None else limit - (time.perf_counter() - tic)
            seg_dense = None if dense is None else dict(dense)
            if seg_dense is not None and sens:
                seg_dense["rhs"] = ksens
            out, wall = chart.call(method, ce, watch, t, t_to, y, p, seg_ctl, seg_te, mode,
                                   newton, left, ksens, halt)
            if seg_dense is not None:
                seg_dense["partial_last"] = int(out.status) in (EVENT, SINGULAR)
        out = _trimmed(out)
        n_ev = int(out.n_ev)
        status = int(out.status)
        hit = (edge and status == EVENT and n_ev > 0
               and int(out.ev_i[n_ev - 1]) == len(user))
        back = None
        depth = 0 if near is None else near[1] + 1
        if (((hit and near is None) or (edge and status == SINGULAR)) and depth <= _DEPTH
                and not (limit is not None and time.perf_counter() - tic >= limit)):
            # the step that reached the edge (or the singular set past it) is not kept:
            # the piece ends at its start, where the chart is still regular, and goes on
            # to the edge in shorter steps (``_approach``: located there, as it is)
            back = _step_start(chart, method, out, t, y, t_to, p, seg_ctl, mode, newton,
                               ce, watch, ksens, direction, halt)
        if back is not None:
            t_k, y_k, span = back
            out = _cut(out, mode, t_k, y_k, len(user), direction)
            if seg_dense is not None:       # (a copy: the plan's are shared)
                seg_dense = {**seg_dense, "partial_last": False}
        near = None
        if build is None:
            seg = out
        else:
            seg = build(scene, method, out, wall, kern, ce, p, t, y, singular_tol, checked,
                        limit, seg_dense, n_events=len(user), sens=ksens)
        n_ev = int(out.n_ev)
        if user and n_ev:           # the occurrences of each user event
            counts += np.bincount(out.ev_i[:n_ev], minlength=len(counts))[:len(counts)]
        if back is None or t_k != t or not parts:     # (not a piece of no steps)
            parts.append((chart, seg, (t, y, t_to, seg_ctl, watch, ce, ksens)))
        steps_left -= int(out.stats[0])
        if not hit and back is None:
            if t_to != t1 and int(out.status) == FINISHED:     # an approach's end
                t, y = float(out.t), np.ascontiguousarray(out.y)
                continue
            break
        if back is not None:
            t, ys = t_k, y_k
            # the switch at the step's start where another split is regular enough
            # (the measure at least twice the edge's), else at the edge
            target = (None if _at_end(t, t1)
                      else _switched(at, chart, t, ys, p, sens, halt is not None))
            if target is None:
                y, near = ys, (span, depth)
                continue
        else:
            t = float(out.ev_t[n_ev - 1])
            ys = np.ascontiguousarray(out.ev_y[n_ev - 1])
            if limit is not None and time.perf_counter() - tic >= limit:
                break
            target = (None if _at_end(t, t1)
                      else _switched(at, chart, t, ys, p, sens, halt is not None))
        if target is None:          # no better split here: go on without the edge
            edge, y = False, ys
            continue
        new, y = target
        switches.append({"t": t, "from": list(chart.split), "to": list(new.split)})
        chart = new
    return parts, switches


#: how many times a step that crossed a chart's edge is cut short (each time to an
#: eighth, ``_approach``) before its located edge is taken as it is
_DEPTH = 4
#: the parts an approach cuts the step that crossed the edge into
_PARTS = 8
#: the t_eval of a loop run again to find the start of a step (none)
_NO_TIMES = np.zeros(0)


def _n_steps(ctl, t, t1, h_fixed) -> int:
    """The fixed steps from ``t`` to ``t1``, none longer than ``h_fixed`` (0: adaptive)."""
    if ctl.n_steps <= 0:
        return 0
    return max(1, math.ceil(abs(t1 - t) / abs(h_fixed) * (1.0 - 1e-12)))


def _approach(ctl, t, t1, h_fixed, span):
    """``(end, step control)`` of the run from ``t``, the start of a step that crossed
    the chart's edge, to that edge in steps of a ``_PARTS``-th of ``span`` (from ``t`` to
    where that step stopped), over the whole step of a fixed-step run (equal steps) or
    twice ``span`` (adaptive steps no longer than that)."""
    if ctl.n_steps > 0:
        span = math.copysign(abs(h_fixed), t1 - t)
    end = t + (span if ctl.n_steps > 0 else 2.0 * span)     # (the edge located roughly)
    if abs(end - t) >= abs(t1 - t):
        end = t1
    if ctl.n_steps > 0:
        return end, _onward(ctl, ctl.max_steps, _PARTS)
    c = list(ctl)
    c[_MAX_STEP] = min(ctl.max_step, abs(span) / _PARTS)
    return end, ctl._make(c)


def _step_start(chart, method, out, t, y, t_to, p, ctl, mode, newton, ce, watch, sens,
                direction, halt):
    """``(t_k, y_k, span)``: the start of the step in which the piece ``out`` (from
    (t, y) to ``t_to``) stopped, the state there and the span from there to the stop:
    the last output row of every step before the stop.  The loop gives that step's start
    in row ``n_out`` (``loop._solve``); where the stop is at that start (a fixed step's
    kink, an event there), the rows of every step are in ``out`` (mode EVERY_STEP) or in
    the same loop run again keeping them (the same steps, bit for bit: a run's rows do
    not depend on what it keeps)."""
    t_stop = float(out.t)
    if int(out.stats[0]) == 0:          # (no step: stopped where it began)
        return t, np.ascontiguousarray(y), t_stop - t
    n = int(out.n_out)
    t_s = float(out.ts[n])
    if direction * (t_stop - t_s) > 0.0:
        if t_s == t:
            return t, np.ascontiguousarray(y), t_stop - t
        return t_s, np.ascontiguousarray(out.ys[n, :y.shape[0]]), t_stop - t_s
    if mode != EVERY_STEP:
        out, _ = chart.call(method, ce, watch, t, t_to, y, p, ctl, _NO_TIMES, EVERY_STEP,
                            newton, None, sens, halt)
    ts, n = out.ts, int(out.n_out)
    k = n - 1
    while k >= 0 and not direction * (t_stop - ts[k]) > 0.0:
        k -= 1
    if k <= 0:
        return t, np.ascontiguousarray(y), t_stop - t
    return float(ts[k]), np.ascontiguousarray(out.ys[k, :y.shape[0]]), t_stop - float(ts[k])


def _trimmed(out):
    """``out`` with its output rows (to row ``n_out``, the step start ``_step_start``
    reads) copied out of the loop's allocation where they fill less than half of it: a
    fixed-step piece gets room for every step to the run's end, and a run through many
    changes of chart kept that much per piece (memory quadratic in the switches: 3.2 GB
    for rk4 on a knife edge over 545 switches, out of memory at 10^6 steps)."""
    n = int(out.n_out) + 1
    if out.ts.shape[0] <= 2 * n + 64:
        return out
    return out._replace(ts=out.ts[:n].copy(), ys=out.ys[:n].copy())


def _cut(out, mode, t_k, y_k, n_user, direction):
    """The loop's result ``out`` cut at ``t_k`` (the start of the step it stopped in,
    state ``y_k``): a finished run to there, its output rows and user events after it
    dropped (the next piece has them)."""
    ts, ys, n = out.ts, out.ys, int(out.n_out)
    keep = n
    while keep > 0 and direction * (ts[keep - 1] - t_k) > 0.0:
        keep -= 1
    ts, ys = ts.copy(), ys.copy()
    if mode == ENDPOINTS:       # (the first row and the last)
        keep = min(keep, 1)
    if mode != AT_T_EVAL and not (keep and ts[keep - 1] == t_k):
        ts[keep], ys[keep, :y_k.shape[0]] = t_k, y_k
        keep += 1
    n_ev = int(out.n_ev)
    m = 0
    while m < n_ev and direction * (t_k - out.ev_t[m]) >= 0.0 and out.ev_i[m] < n_user:
        m += 1
    return out._replace(status=FINISHED, ts=ts, ys=ys, n_out=keep, t=t_k, y=y_k.copy(),
                        n_ev=m, sing_index=-1)


def _onward(ctl, max_steps, n_steps, edge=True):
    """``ctl._replace(first_step=0.0, max_steps=max_steps, n_steps=n_steps,
    edge=NEAR)``: the step control of a piece after the first (its first step chosen
    afresh, its steps near the chart's singular set shorter: ``NEAR``), without the
    keyword machinery.  A fixed-step piece that does not watch the chart's edge
    (``edge`` false) gets ``edge=0``: its stage check would read its last user event
    as the edge."""
    c = list(ctl)
    c[_FIRST], c[_MAX_STEPS], c[_N_STEPS] = 0.0, max_steps, n_steps
    c[_EDGE] = NEAR if edge or n_steps == 0 else 0.0
    return ctl._make(c)


_FIRST, _MAX_STEPS, _N_STEPS, _MAX_STEP, _EDGE = (Control._fields.index(f) for f in (
    "first_step", "max_steps", "n_steps", "max_step", "edge"))


def _at_end(t, t1) -> bool:
    """Whether an edge at ``t`` lies within the time resolution of a span of the run's
    end ``t1`` (``arguments.MIN_TIME_RESOLUTION`` units in the last place, or at
    ``t1``): no chart is entered there (its scene could not span the rest); the run
    ends in the chart it is in, whose split is still regular at its edge."""
    return abs(t1 - t) < arguments.MIN_TIME_RESOLUTION * math.ulp(max(abs(t), abs(t1)))


def _switched(at, chart, t, y, p, sens, made=False):
    """``switch`` of a state ``y`` of ``chart``, with ``sens`` followed by its
    sensitivities, which go across in the new chart's coordinates (``Chart.carry``):
    ``(new chart, its state)`` or None.  ``made``: as ``switch``'s."""
    n = len(chart.scene.state_names)
    target = switch(at, chart, t, y[:n], p, made)
    if target is None or not sens:
        return target
    new, y_new = target
    S = chart.carry(new, t, y[:n], y[n:].reshape(1, n, -1), p)
    return new, np.concatenate((y_new, S.ravel()))


def _on_constraints(chart, t, y, p) -> np.ndarray:
    """``y`` (a state of ``chart``) with its coordinates moved onto the holonomic
    constraints g = 0, as the loops move every accepted step (``methods.projection``)."""
    system = chart.scene.system
    if not system.holonomic:
        return np.ascontiguousarray(y, dtype=float)
    ys = np.array(y, dtype=float).reshape(1, -1)
    projection.rows(chart.kernels.hol, len(system.holonomic), system.J.n, np.array([float(t)]),
                    ys, p)
    return ys[0]


def switch(at, chart, t, y, p, made=False):
    """The chart to go on in at the edge of ``chart`` (reached at (t, y), moved onto the
    holonomic constraints) and the state there, or None (``_target``): in one compiled
    call (``Atlas.change``) where the multipliers keep their values and every chart it
    needs has its kernels, else in Python, which makes them (``made``: ``Cold`` raised
    instead)."""
    t = float(t)
    y = _on_constraints(chart, t, y, p)
    if not chart.explicit:
        found = at.change(chart, t, y, p)
        if found is not MISSING:
            return found
    if made and not at.made(chart):
        raise Cold
    if chart.explicit:              # (multipliers mapped by A: ``Chart.point``)
        found = _target(at, chart, t, p, *chart.point(t, y, p))
    else:   # the same numbers copied through lists (``point``, ``state_at``: a few numbers)
        qd, n = chart.velocity_list(t, y, p), chart.n
        head, lam = y[:n].tolist(), y[2 * n - chart.k:].tolist()
        found = _choose(at, chart, t, p, chart.jacobian_rows(t, y, p), qd,
                        lambda to: np.array(head + [qd[i] for i in to._independent] + lam))
    at.register(at.own, chart, *at.charts.values())     # (what was made on the way)
    return found


def _target(at, chart, t, p, q, qd, lam, A):
    """The chart to go on in at the edge of ``chart`` and the state there (``_choose``).
    ``(q, qd, lam, A)``: ``Chart.point`` there."""
    return _choose(at, chart, t, p, A, qd.tolist(),
                   lambda to: to.state_at(q, qd, lam, A))


def _choose(at, chart, t, p, A, want, state_in):
    """The split of largest measure (at least twice the edge) whose constraints give
    back the velocities ``want`` (every velocity at the edge of ``chart``, a list: the
    same branch) and the state there (``state_in(its map)``), or None.  ``A``: df/dqdot
    there (k x n)."""
    m = at.measures(A)
    # (two splits: the other is the one candidate, in any order)
    for i in range(2) if len(m) == 2 else sorted(range(len(m)), key=lambda i: -m[i]):
        split = at.splits[i]
        if split == chart.split or m[i] < 2 * at.eps:
            continue
        y = state_in(at.maps[split])
        new = at.chart(split, t, y)
        for a, b in zip(new.velocity_list(t, y, p), want):
            if not abs(a - b) <= 1e-8 * max(1.0, abs(b)):
                break
        else:
            return new, y
    return None


def stitch(home, at, method, p, parts, switches, user, mode, wall):
    """One Trajectory of ``home`` from the runs in the charts ``parts`` (``_Piece``: the
    rows kept taken from each loop's result and mapped home when first read,
    ``Stitched.rows``; the pieces' own Trajectories made only when read: for user
    events, a stop other than the end, sensitivities, the aux rows and the dense
    output)."""
    own = at.own
    if len(parts) == 1 and not switches:
        return parts[0][1].traj
    pieces, (steps, rejected, nfev), sens = _layout(own, parts, mode, p)
    events = None
    if user:
        t_ev, y_ev = [], []
        for i in range(len(user)):
            t_ev.append(np.concatenate([seg.t_events[i] for _, seg, _ in parts]))
            y_ev.append(np.concatenate([
                to_home(own, chart, seg.t_events[i], seg.y_events[i].reshape(
                    -1, len(chart.scene.state_names)), p)
                for chart, seg, _ in parts]))
        events = (tuple([e.name for e in user]), t_ev, y_ev)
    last = parts[-1][1]
    if last.out.status == FINISHED and not parts[-1][2][3].n_hol:   # (rows not moved)
        status, reason, singularity = FINISHED, _FINISHED_TEXT, None
    else:
        status, reason, singularity = last.status, last.stop_reason, last.singularity
    # (the rows: made on first read, ``Stitched.rows``)
    return Trajectory._of_run(home, None, p, method,
                              status, reason, ((steps, rejected, nfev), wall, home.projected),
                              own.kernels, events, singularity, parts[0][1].dense,
                              None if sens is None else (home._sensitivity_columns(),
                                                         np.concatenate(sens)),
                              segments=Stitched(own, tuple(pieces)),
                              switches=tuple(switches))


def _layout(own, parts, mode, p):
    """``(pieces, (steps, rejected, evaluations), S or None)`` of ``stitch``: the rows
    ``lo:hi`` of the trajectory that each part gives from its rows ``a:`` (``Stitched``),
    the counts over the parts, and the sensitivities of a run with them, carried to the
    scene's chart."""
    pieces = []
    sens = [] if parts[-1][2][6] is not None else None
    row, last_part, steps, rejected, nfev = 0, len(parts) - 1, 0, 0, 0
    ends = mode == ENDPOINTS and last_part
    for i, (chart, seg, rerun) in enumerate(parts):
        out = seg.out
        a, b = 0, int(out.n_out)
        if ends:                            # the first row and the last
            a, b = (0, 1) if i == 0 else (b - 1, b) if i == last_part else (b, b)
        elif i > 0 and mode != AT_T_EVAL:
            a = 1                       # the switch row: the chart before stored it
        if sens is not None:        # S of the scene's states: D S of each row
            S = seg.sensitivities[a:b]
            sens.append(S if chart is own else
                        chart.carry(own, out.ts[a:b], seg.y[a:b], S, p))
        pieces.append((row, row + b - a, chart, seg, a, rerun))
        row += b - a
        c = out.stats               # (steps, rejected, nfev: integers)
        steps, rejected, nfev = steps + c[0], rejected + c[1], nfev + c[2]
    return pieces, (steps, rejected, nfev), sens


_MAKERS: dict = {}


class _Piece:
    """A piece of a run that changed chart (``follow``): its loop's ``Result`` (``out``),
    its dense-output record (``dense``) and its Trajectory in its chart's scene
    (``traj``), made by ``build`` (``solve.trajectory``) from the same arguments on first
    use; its other attributes are its Trajectory's."""

    __slots__ = ("out", "dense", "_make", "_traj")

    def __init__(self, build, args, kw):
        self.out, self.dense = args[2], args[12]
        self._make, self._traj = (build, args, kw), None
        if kw.get("sens") is not None:      # (its Trajectory completes the dense record)
            self._traj = build(*args, **kw)

    @classmethod
    def maker(cls, build):
        """``build``, made lazy: the ``_Piece`` of its arguments (made once per
        ``build``)."""
        found = _MAKERS.get(build)
        if found is None:
            found = _MAKERS[build] = lambda *args, **kw: cls(build, args, kw)
        return found

    @property
    def traj(self) -> Trajectory:
        if self._traj is None:
            build, args, kw = self._make
            self._traj = build(*args, **kw)
        return self._traj

    def __getattr__(self, name):
        if name in _Piece.__slots__:     # (unset: a copy made without __init__)
            raise AttributeError(name)
        return getattr(self.traj, name)


def to_home(own, chart, t, Y, p) -> np.ndarray:
    """Rows of ``chart`` (at the times ``t``, an array) as rows of the home chart
    ``own``."""
    Y = np.ascontiguousarray(Y if getattr(Y, "ndim", 0) == 2 else np.atleast_2d(Y),
                             dtype=float)
    if chart is own or not Y.shape[0]:
        return Y.reshape(Y.shape[0], len(own.scene.state_names))
    if chart.explicit:
        q, qd, lam, A, _ = chart.universal(t, Y, p)
        return own.state(q, qd, lam, A)
    # the same numbers copied: every column of own's rows is a column of Y or of aux
    if Y.shape[0] == 1:     # one row (a run's end)
        return np.array([_home_row(own, chart, float(t[0]), Y[0], p)])
    kern = chart.kernels
    aux = np.empty((Y.shape[0], kern.layout.n_aux))
    kern.aux_rows(np.ascontiguousarray(t, dtype=float), Y, p, aux)
    return np.concatenate((Y, aux), axis=1).take(chart.columns_of(own), axis=1)


def _home_row(own, chart, t, y, p) -> list:
    """One state ``y`` (C-contiguous floats) of ``chart``, whose multipliers keep their
    values, as a row of the home chart ``own``, a list: its columns copied from ``y``
    and the aux row (the aux kernel itself, as ``aux_rows`` calls it)."""
    kern = chart.kernels                # (sets ``_n_aux``)
    aux = np.empty(chart._n_aux)
    kern.aux(t, y, p, aux)
    row = y.tolist() + aux.tolist()
    return [row[i] for i in chart.columns_of(own, as_list=True)]


# ---------------------------------------------------------------------- stitched views
class Stitched:
    """The pieces of a run that changed split: ``(lo, hi, chart, seg, a, rerun)``, rows
    ``lo:hi`` of the trajectory from rows ``a:`` of the chart's own run ``seg``; its
    trajectory's aux rows and dense output come from here (``aux``, ``at``)."""

    def __init__(self, own, pieces):
        self.own, self.pieces = own, pieces

    def rows(self, p):
        """``(t, y, n)``: the trajectory's output rows, each piece's rows of its loop's
        result (``_Piece.out``) mapped to the scene's chart (``to_home``)."""
        own, ts, ys = self.own, [], []
        if not own.explicit and all(hi - lo <= 1 for lo, hi, *_ in self.pieces):
            for lo, hi, chart, seg, a, _ in self.pieces:     # (the ends: through lists)
                if hi > lo:
                    ts.append(float(seg.out.ts[a]))
                    y = seg.out.ys[a, :len(chart.scene.state_names)]
                    ys.append(y.tolist() if chart is own else _home_row(own, chart, ts[-1], y, p))
            return np.array(ts), np.array(ys), len(ts)
        for lo, hi, chart, seg, a, _ in self.pieces:
            out = seg.out
            t = out.ts[a:a + hi - lo]
            Y = out.ys[a:a + hi - lo, :len(chart.scene.state_names)]
            ts.append(t)
            ys.append(Y if chart is own else to_home(own, chart, t, Y, p))
        t = np.concatenate(ts)          # (new float64 C-contiguous arrays: taken as they are)
        return t, np.concatenate(ys), t.shape[0]

    def aux(self, traj) -> np.ndarray:
        """The aux rows of the trajectory, each from its own chart's kernels."""
        out = np.empty((len(traj), traj.layout.n_aux))
        fill_aux(out, self.own, self.pieces, traj._p)
        return out

    def at(self, traj, times) -> np.ndarray:
        """States at ``times``: each time from the chart that ran there (its steps
        re-taken; in the part of a step that a switch cut short, the chart's loop run
        again to it), mapped to the scene's layout."""
        return _at(self, traj, times)

    def evaluate(self, traj, times, full=False) -> np.ndarray:
        """``at``; with ``full`` (a run with sensitivities) each row followed by S of
        the scene's states, row-major (``dense.evaluate``'s ``full``)."""
        return _at(self, traj, times, full)

    def stop(self, p):
        """``(t, state, aux row)`` of the scene where the run stopped after its last row
        (the last piece's stop, mapped to the scene's chart), or None
        (``Trajectory.final``)."""
        from types import SimpleNamespace

        _, _, chart, seg, _, _ = self.pieces[-1]
        stop = seg._stop
        if stop is None:
            return None
        t, y, aux = stop
        times, row = np.array([t]), y[None, :]
        out = np.empty((1, self.own.kernels.layout.n_aux))
        piece = SimpleNamespace(t=times, y=row, aux=aux[None, :])
        fill_aux(out, self.own, [(0, 1, chart, piece, 0)], p)
        return t, to_home(self.own, chart, times, row, p)[0], out[0]


class _Recorded(Stitched):
    """``Stitched`` of a run made by ``chart_driver`` (``_driven``): its pieces, as
    ``follow`` makes them, made from the driver's record when first read."""

    def __init__(self, at, plan, p, build, wall, record):
        self.own = at.own
        self._made = (at, plan, p, build, wall, record)

    @property
    def pieces(self):
        made = self.__dict__.get("_pieces")
        if made is None:
            parts = _recorded_parts(*self._made)
            made = self.__dict__["_pieces"] = tuple(
                _layout(self.own, parts, self._made[1].mode, self._made[2])[0])
        return made


def fill_aux(out, own, pieces, p):
    """``out[lo:hi]``: the aux rows of the scene (dependent velocities of its split,
    residuals, energy, integrals) of every piece ``(lo, hi, chart, seg, a, ...)``, rows
    ``a:a + hi - lo`` of the chart's run ``seg``, from the chart's own kernels."""
    k = own.k
    for lo, hi, chart, seg, a, *_ in pieces:
        rows = seg.aux[a:a + hi - lo]
        if chart is own:
            out[lo:hi] = rows
            continue
        _, qd, _, _, _ = chart.universal(seg.t[a:a + hi - lo], seg.y[a:a + hi - lo], p)
        out[lo:hi, :k] = qd[:, own.dep]
        out[lo:hi, k:] = rows[:, k:]


def _at(stitched, traj, times, full=False) -> np.ndarray:
    from .dense import _refusal, _times, evaluate

    why = _refusal(traj)
    if why:
        raise JetnhError(why)
    tau = _times(times, float(traj.t.min()), float(traj.t.max()))
    n = traj.y.shape[1]
    full = full and traj._sens is not None
    m = len(traj.sensitivity_columns) if full else 0
    out = np.full((tau.shape[0], n + n * m), np.nan)
    own = stitched.own
    sgn = 1.0 if traj.t[-1] >= traj.t[0] else -1.0
    done = np.zeros(tau.shape[0], dtype=bool)
    for lo, hi, chart, seg, a, rerun in stitched.pieces:
        t_lo, t_hi = float(seg.t[0]), float(seg.t[-1])
        mine = ~done & (sgn * (tau - t_lo) >= 0) & (sgn * (t_hi - tau) >= 0)
        if not mine.any():
            continue
        done |= mine
        idx = np.nonzero(mine)[0]
        cut = seg._dense["partial_last"] and len(seg.t) > 1
        inner = sgn * (tau[idx] - float(seg.t[-2])) > 0 if cut else np.zeros(idx.size, bool)
        n_c = len(chart.scene.state_names)
        rows = np.empty((idx.size, n_c + n_c * m))
        if (~inner).any():
            rows[~inner] = evaluate(getattr(seg, "traj", seg), tau[idx[~inner]], full=full)
        if inner.any():
            rows[inner] = _rerun(chart, seg, rerun, tau[idx[inner]], traj._p)[:, :rows.shape[1]]
        Y = np.ascontiguousarray(rows[:, :n_c])
        out[idx, :n] = to_home(own, chart, tau[idx], Y, traj._p)
        if full:
            S = rows[:, n_c:].reshape(-1, n_c, m)
            if chart is not own:
                S = chart.carry(own, tau[idx], Y, S, traj._p)
            out[idx, n:] = S.reshape(idx.size, -1)
    return out


def _rerun(chart, seg, rerun, times, p) -> np.ndarray:
    """The states at ``times`` inside the last, cut step of a segment: the segment's
    loop run again from its start with these times as t_eval (the same steps, the same
    dense output: what t_eval gives); a run with sensitivities gives them after the
    state."""
    t0, y0, t1, ctl, watch, ce, sens = rerun
    order = np.argsort(times, kind="stable")
    if seg.t[-1] < seg.t[0]:
        order = order[::-1]
    te = np.ascontiguousarray(times[order])
    out, _ = loops.call(chart.scene, seg.method, chart.kernels, ce, watch, t0, t1, y0, p,
                        ctl, te, AT_T_EVAL, None, None, sens)
    rows = np.empty((te.shape[0], out.ys.shape[1]))
    first = 1 if ctl.n_steps > 0 else 0   # a fixed-step loop stores its start row too
    if int(out.n_out) != first + te.shape[0] or int(out.status) == STOPPED:
        raise JetnhError("running the chart's loop again did not reach the times asked for")
    rows[order] = out.ys[first:first + te.shape[0]]
    return rows


def end_across(home, plan, out, y0, p):
    """The end of a run with sensitivities of ``home`` by its ``plan`` from ``y0`` (the
    state and S(t0) after it) whose loop, in the scene's own chart, stopped at the
    chart's edge or singular (``out``, the loop's tuple): taken on chart by chart as
    ``run`` takes it (the same pieces, bit for bit), each loop called without making a
    Trajectory.  Returns ``(status, t, y, S)`` at its last state, y and S in
    ``home``'s states."""
    at = atlas(home)
    own = at.own
    ctl = plan.ctl
    loops.on_constraints(own.kernels, ctl, plan.mode, own.sensitivity_kernels, out, p,
                         plan.t0)
    parts, _ = follow(at, plan.method.name, own, plan.t0, y0, plan.t1, p, (),
                      loops.NO_EVENTS, ctl, ctl.max_steps, plan.te, plan.mode, None,
                      plan.checked, plan.singular_tol, plan.newton, plan.limit, None,
                      sens=True, ran=(loops.result(out), 0.0, plan.ce, plan.watch, None))
    chart, last, _ = parts[-1]
    t, n = float(last.t), len(chart.scene.state_names)
    y, S = last.y[:n].reshape(1, n), last.y[n:].reshape(1, n, -1)
    if chart is not own:
        S = chart.carry(own, t, y, S, p)
        y = to_home(own, chart, np.array([t]), y, p)
    return int(last.status), t, y[0], S[0]
