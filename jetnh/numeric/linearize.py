"""Linearization on the constraint manifold, and the stability of steady motions::

    lin = linearize(system, "chetaev", at={"theta": 0.0, "phi_t": 5.0}, params={g: 9.81})
    lin.A, lin.state_names, lin.eigenvalues, lin.residual, lin.verdict
    lin.replace(params={"g": 1.62}, at={"phi_t": 2.0})      # no derivation, no compilation
    lin.steady(["phi_t"])             # solve for the rest of a steady motion
    scan = lin.along("phi_t", np.linspace(0.5, 5, 50))      # eigenvalues along a value
    scan.frame, scan.crossings, scan.plot()
    verdicts(system, at, params)      # one steady motion under every principle

The state x of a principle's reduced first-order system is the scene's (``Scene``): the
coordinates, the independent velocities qdot^mu and the multipliers of the principles
whose multipliers are states (vakonomic, Hoelder, Suslov), less the coordinates that are
dropped or follow from holonomic constraints (below); the dependent velocities follow
from the constraints (qdot^alpha = phi^alpha), so every perturbation stays on the
constraint manifold.  ``A = dx'/dx`` at the operating point comes from the Jacobian
kernel generated from the derivation by forward-mode differentiation over the shared
graph (``kernels.jacobian_kernels``), compiled once per system and principle with every
parameter read at run time: a ``replace`` costs a kernel call and an eigenvalue
problem.  ``Linearization.symbolic()`` is the same matrix in the
user's symbols, by ``dag.jacobian`` on the graph (never flattened).

Holonomic constraints g(t, q) = 0 (``system.holonomic``): the operating point must lie
on g = 0, judged against the size of g's terms there (``holonomic.bound``; else a
``ConstraintError`` with the residual and values that would put it there), and the coordinates are perturbed within g = 0.  The coordinates q^D of
``holonomic.completion_coordinates`` (the split's dependent ones where g can be solved
for them) are eliminated (``Linearization.eliminated``): near the point they follow
from the others q^I by g = 0, dq^D = T dq^I with T = -(dg/dq^D)^-1 dg/dq^I, and are no
states.  The flow keeps g constant (its equations use D g = 0), so A = P J E exactly:
J the Jacobian of the full system, E the embedding (unit columns, plus T in the rows
q^D under the q^I columns) and P the rows of the kept states.  A holonomic constraint's
multiplier under the vakonomic, Hoelder and Suslov principles enters their equations
only through its rate, as lambda_t dg/dq with lambda_t fixed by the other equations
(vakonomic: D g is a total derivative, so its Euler-Lagrange expression vanishes): no
row depends on its value, its column of J is zero, it is a pure zero mode and
bookkeeping.  Such multipliers (found on the graph, not assumed) are left out
(``Linearization.inert``) and need no value in ``at``.

Dropped coordinates (``drop="cyclic"``): those the equations of the kept states do not
depend on -- absent from them, or present with a derivative that vanishes identically
(decided by ``zero.vanishes`` on the graph, e.g. the heading of a rolling disk, which
enters phi and the accelerations only in combinations that cancel) -- and that share no
holonomic constraint with a kept coordinate.  Their rows (their drift, such as the
position of a rolling body) do not feed back, so ``A`` is the Jacobian restricted to the
kept states.

The split at the point (``numeric.regular``): past the edge of its chart (the measure
det(A_alpha)^2 / det(A A^T) below the atlas's edge) dependent velocities given with the
point are checked against the constraints f = 0 themselves, and the point is linearized
in the split of largest measure, as a run from it would go on there (its rows, states
and ``at`` are those of ``system.with_split(...)``; the multipliers keep their values,
renamed; principles whose motions depend on the split keep theirs).  Where the split is
singular (one rounding unit in an input moves phi by more than 1e-9 relative:
``regular.determined``) a point without its dependent velocities is a
``ConstraintError`` naming the split, its measure and a regular one.

Stability is spectral, and decided only at a steady motion (a relative equilibrium of
the kept states: x' = 0 there).  The point is one when every kept rate x'_i is zero to
the rounding of its inputs: |x'_i| <= ``ROUNDING`` times sum_j |dx'_i/dz_j| |z_j| over
the states, the parameters and t (the rounding of the point through the row: sin th at
the rounded pi, or sin a with a parameter a = pi; by the Jacobian kernel and central
differences, ``_inputs``), plus ``ROUNDING`` times the size of the terms that make up
the row there (``holonomic.magnitude``: the rounding of its evaluation).  The first is
a value of the row, not of how it is written: -k (x - c) and -k x + k c get the same
one (k |x| + k |c| + |x - c| |k|), so a point 0.005 off the equilibrium at c = 1e6 is
none in either form; the second differs between forms only within it.  Neither
involves the number 1 or the |x| of another state: the same point in other units, or
with a coordinate counted from another origin, gets the same verdict (a pendulum 0.005
rad off its equilibrium is none beside a cart 1000 km along its track, and so is a
point of th'' = -G sin th off th = k pi with G in any unit of time).  Elsewhere the
eigenvalues of A are still computed but say nothing about stability: the verdict is
``"not a steady motion"``, ``stable`` is None (``steady(unknowns)`` finds a steady
motion nearby, to its ``tol``
relative to the same scales).  At a
steady motion: ``unstable`` when an eigenvalue has a positive real part,
``asymptotically stable`` when every one has a negative real part, ``marginal`` when some
lie on the imaginary axis (conservative systems, families of steady motions: the
linearization does not decide).  Each eigenvalue is decided against its own error
bound e_i: a real part within e_i of zero counts as zero (on the imaginary axis), and so
does an eigenvalue of modulus within e_i.  With B = A balanced (a diagonal similarity,
LAPACK's ``gebal``), delta = ``REAL`` |B| (Frobenius norm: the rounding of
A's entries and of the eigensolver), kappa_i = 1/|y_i^H x_i| the eigenvalue's condition
number (unit left and right eigenvectors of B) and s_i half its distance to the nearest
other eigenvalue: e_i = min(delta kappa_i, max(delta, sqrt(2 delta kappa_i s_i)),
``ZERO`` |B|).  The first is the first-order bound of a simple eigenvalue; the second
that of a cluster split by rounding (a Jordan block perturbed by delta spreads to
sqrt(delta nu), and kappa ~ nu/(2 s) there), which a defective zero eigenvalue of a
family of steady motions is; ``ZERO`` = sqrt(``REAL``) caps the bound of an eigenvalue
computed exactly defective (kappa_i infinite).  A stiff mode elsewhere in A (a spring
of stiffness k: |A| ~ k) widens the other eigenvalues' bounds only through |B|, which
balancing keeps near sqrt(k).

The reduced mass matrix at the point, Psi^T H Psi (H = d^2 L/dqdot^2, Psi =
dqdot/dqdot^mu on the constraints), is what every principle's accelerations divide by.
Its condition number scaled to a unit diagonal (``Linearization.conditioning``: the
same in every unit of every coordinate; |lambda|max/|lambda|min, so an indefinite
kinetic energy is judged by its eigenvalues' moduli) above ``CONDITION`` = 1e-8/eps
means the rounding it amplifies may exceed what the steady test and the eigenvalue
bounds assume: linearize warns (``JetnhWarning``), naming the fix (coordinates in which
it is regular there).  Not at a 0/0 limit, where it is singular by construction.

Rows that depend on t (t in a kept row or a holonomic constraint with a derivative that
does not vanish identically, e.g. a periodically forced or modulated system): the state
is held and A and x' are evaluated again at the times ``t + TIMES`` (scaled by the
larger of |t| and A's time scale, 1/|B|).  The point is a steady motion only when x'
vanishes at every one of them (a point where x' vanishes at one instant only, as an equilibrium of a forced oscillator
at a zero of its forcing, is none); ``time_dependent`` is True when A or x' differ
between them.  At such a point A and its eigenvalues are those frozen at ``t``, and
they do not decide stability (a damped Mathieu equation is unstable at parametric
resonance with every frozen eigenvalue in the left half-plane): the verdict is
``TIME_DEPENDENT``, ``stable`` and ``margin`` are None and NaN.  A time-periodic A needs
Floquet's theory (the monodromy matrix over a period, from the variational equations
of a run), which linearize does not compute.  Parameter values that remove the
dependence on t (a modulation of amplitude 0) give the frozen verdict again.  Rows
that contain t but do not depend on it (the derivative vanishes identically, as in
e^(g t) L0, whose rows carry exp(g t) exp(-g t)) are evaluated at t = 0: the same
values at every t, without the overflow of those factors at g t ~ 710.  Rows that carry
such factors and depend on t otherwise are evaluated at t: where they are not finite
and an exponential in them is large (beyond ``LARGE``, half of ``OVERFLOW``: a product
such as g exp(g t) overflows before exp(g t) does) at the point, a
``LinearizationError`` names the overflow; at the later times of the test above (there
also where an exponent has grown by more than ``GROWTH`` since the point), those times
are left out.
"""

from __future__ import annotations

import math
import warnings
from collections.abc import Mapping

import numpy as np
import sympy as sp

from ..algebra import dag, linalg, zero
from ..errors import (ArgumentError, ConstraintError, JetnhError, JetnhWarning,
                      LinearizationError, PrincipleError)
from ..mechanics import holonomic, principles
from ..mechanics.system import System
from . import arguments, regular
from ..frozen import Frozen, FrozenDict

#: the relative rounding of A and its eigenvalues: delta = REAL * |B| (B: A balanced),
#: an eigenvalue's error bound about delta * kappa_i (module docstring)
REAL = 1e-12
#: an eigenvalue's error bound is at most ZERO * |B| (sqrt(REAL): a Jordan block)
ZERO = 1e-6
#: a point is a steady motion when every kept rate is at most ``ROUNDING`` times the
#: rounding of its inputs through it, sum_j |dx'_i/dx_j| |x_j| over the states, the
#: parameters and t (``_inputs``), plus the size of the terms that make it up there
#: (``_Model.sizes``, the rounding of their evaluation): 4500 eps of each
ROUNDING = 1e-12
#: the steps (relative to each state's own size) tried in turn for the limit at a 0/0:
#: the first where the extrapolation settles
STEPS = (1e-1, 1e-2, 1e-3, 1e-4, 1e-5, 1e-6, 1e-7, 1e-8)
#: the steps (in the state's own units) of states at 0, where nothing at the point gives
#: a scale: a wide sweep, largest first
SWEEP = tuple(10.0 ** k for k in range(8, -17, -1))
#: a step at a 0/0 is refused where a row that is 0/0 at the point keeps less than this
#: fraction of the size of its terms (``_Model.sizes``) at every point stepped to: its
#: rounding, eps over that fraction, exceeds the 1e-3 agreement asked of the limit, and
#: values that agree there (zeros) are no limit
DIGITS = 1e3 * float(np.finfo(float).eps)
#: the directions of approach along which that limit must agree
DIRECTIONS = 3
#: the rounding unit of a double
EPS = float(np.finfo(float).eps)
#: the scaled condition number of the reduced mass matrix above which linearize warns
#: (a JetnhWarning): the rounding it amplifies, cond * eps, exceeds 1e-8, 1e4 times
#: ``ROUNDING``, and may exceed the steady test's and the eigenvalue bounds' allowance
CONDITION = 1e-8 / EPS
#: the relative tolerance of given dependent velocities (and of f = 0 past the edge)
CONSISTENT = 1e-9
#: the largest argument of exp whose value is a double (log of the largest double)
OVERFLOW = float(np.log(np.finfo(float).max))
#: an exponent past which a non-finite value of the rows is taken for the overflow of a
#: product (g exp(g t) overflows below ``OVERFLOW``), not for a 0/0
LARGE = OVERFLOW / 2
#: the relative step of a parameter or of t in ``_inputs``' differences
NUDGE = 2.0 ** -20
#: the growth of an exponent beyond its value at the point past which a non-finite value
#: at a later time of ``_in_time`` is taken for an overflow: ln(1/eps)
GROWTH = float(-np.log(np.finfo(float).eps))
#: the verdict off a steady motion
NOT_STEADY = "not a steady motion"
#: the verdict at a steady motion of rows that depend on t
TIME_DEPENDENT = "time-dependent: the frozen eigenvalues do not decide"
#: the offsets from the point's t at which rows that contain t are evaluated again, in
#: units of the larger of |t| and A's time scale (``_in_time``)
TIMES = (0.1234567, -0.5772157, 1.4142136, 2.7182818, 7.3890561, 31.415927, 271.82818)

_MODELS: dict = {}


# ---------------------------------------------------------------------- the derived model
def _once(f):
    """A value of a private ``_Model`` computed on first use."""
    name = "_" + f.__name__

    def get(self):
        if name not in self.__dict__:
            self.__dict__[name] = f(self)
        return self.__dict__[name]

    return property(get, doc=f.__doc__)


class _Model:
    """What a system and a principle give once: the reduced rows in the user's symbols
    (dependent velocities replaced by phi), which coordinates they use, and the compiled
    kernels (every parameter a run-time parameter)."""

    def __init__(self, system: System, principle: str, form, convention):
        self.system, self.principle = system, principle
        self.form, self.convention = form, convention
        J = system.J
        eom = system.equations(principle, form=form, convention=convention)
        if eom.arbitrary:
            raise PrincipleError(
                f"the {principle} equations in the {convention!r} convention leave the "
                f"multipliers {[s.name for s in eom.arbitrary]} arbitrary: there is no "
                "first-order system to linearize; use the paper's convention")
        self.lams = tuple(principles.get(principle).multiplier_symbols(system))
        self.coordinates = tuple(J.q)
        self.velocities = tuple(system.independent_velocities)
        self.states = self.coordinates + self.velocities + self.lams
        self.names = tuple(s.name for s in self.states)
        self.dependent = tuple(system.dependent_velocities)
        self.params = tuple(sorted(s.name for s in system.parameters))
        self._eom = eom
        self._kernels = None
        self._uses: dict = {}           # (row, state) -> bool
        self._symbolic: dict = {}       # (kept states, chart) -> sympy Matrix
        self._programs: dict = {}       # (what, rows) -> _Program

    @_once
    def rows(self) -> list:
        """x' of every state, in the user's symbols: q' (qdot^s, phi^alpha for the
        dependent ones), the accelerations, the multiplier rates; dependent velocities
        replaced by phi on the graph."""
        J, sysm = self.system.J, self.system
        acc = self._eom.accelerations()
        phi = {v: sysm.phi[v] for v in self.dependent}
        rows = [phi.get(J.jet(q, 1), J.jet(q, 1)) for q in self.coordinates]
        rows += [acc[J.jet(J.split(v)[0], 2)] for v in self.velocities]
        rows += [acc[r] for r in self._eom.multiplier_rates]
        return dag.xreplace(rows, phi) if phi else rows

    @_once
    def sizes(self) -> list:
        """The size of the terms that make up each row (``holonomic.magnitude``): what
        the rounding of those terms leaves of a rate that vanishes."""
        memo: dict = {}
        return [holonomic.magnitude(e, memo) for e in self.rows]

    def sizes_at(self, rows, y, values: dict, t: float) -> np.ndarray:
        """``sizes`` of ``rows`` (state indices) at state ``y``, ``values`` and ``t``."""
        key = ("sizes", tuple(rows))
        if key not in self._programs:
            self._programs[key] = _Program([self.sizes[i] for i in rows])
        return self._programs[key](self._point(y, values, t))

    def overflow(self, rows, y, values: dict, t: float, beyond: float = OVERFLOW
                 ) -> str | None:
        """Where an exponential in ``rows`` (state indices) grows beyond ``beyond`` at
        state ``y``, ``values`` and ``t`` (exp of an argument, sinh or cosh of its
        magnitude; ``OVERFLOW``: the value itself overflows a double): a description of
        the largest, else None."""
        top, node, arg = self.growth(rows, y, values, t)
        return f"{node} is {node.func.__name__}({arg:.6g})" if top > beyond else None

    def growth(self, rows, y, values: dict, t: float) -> tuple:
        """``(exponent, node, argument)``: the largest exponent of an exponential in
        ``rows`` at state ``y``, ``values`` and ``t`` (exp's argument, sinh's or cosh's
        magnitude), its expression and its argument; ``(-inf, None, nan)`` where the
        rows have none."""
        key = ("overflow", tuple(rows))
        if key not in self._programs:
            heads = (sp.exp, sp.sinh, sp.cosh)
            nodes = [e for e in dag.nodes([self.rows[i] for i in rows])
                     if isinstance(e, heads)]
            self._programs[key] = (nodes, _Program([e.args[0] for e in nodes]))
        nodes, program = self._programs[key]
        if not nodes:
            return -np.inf, None, np.nan
        with np.errstate(all="ignore"):
            args = program(self._point(y, values, t))
        grow = [a if isinstance(e, sp.exp) else abs(a) for e, a in zip(nodes, args)]
        i = int(np.nanargmax(grow)) if not np.all(np.isnan(grow)) else 0
        return float(grow[i]), nodes[i], float(args[i])

    @_once
    def mass(self) -> "_Program":
        """The parts of the reduced mass matrix Psi^T H Psi: H = d^2 L/dqdot^2 and
        Psi = dqdot/dqdot^mu (a unit row for an independent velocity, d phi/dqdot^mu for
        a dependent one), the dependent velocities replaced by phi."""
        sysm = self.system
        exprs = list(sysm.mass_matrix) + list(sysm.Phi)
        phi = {v: sysm.phi[v] for v in self.dependent}
        return _Program(dag.xreplace(exprs, phi) if phi else exprs)

    def conditioning(self, y, values: dict, t: float) -> float:
        """The condition number (2-norm, ``|lambda|max / |lambda|min``) of the reduced
        mass matrix at state ``y`` scaled to a unit diagonal, D^-1/2 M D^-1/2 (D its
        diagonal, absolute values: an indefinite kinetic energy has negative entries; a
        zero entry D_ii is replaced by max_j M_ij^2 / D_jj, of the same unit, or, where
        all of a block's are zero, one by max_j |M_ij|): the same in every unit of every
        coordinate where the diagonal is nonzero, and for a definite M within a factor
        of its dimension of the smallest under any diagonal scaling (van der Sluis);
        infinite where it is singular."""
        n, m = len(self.coordinates), len(self.velocities)
        vals = self.mass(self._point(y, values, t))
        H = vals[:n * n].reshape(n, n)
        if m < n:
            Psi = np.vstack([np.eye(m), vals[n * n:].reshape(-1, m)])[self.psi_rows]
            H = Psi.T @ H @ Psi
        if not np.all(np.isfinite(H)):
            return np.inf
        d = np.sqrt(np.abs(np.diag(H)))
        while not np.all(d > 0):    # a zero diagonal entry: max_j |H_ij| / d_j
            near = (np.abs(H) / np.where(d > 0, d, np.inf)[None, :]).max(axis=1)
            if np.any(near[d == 0] > 0):
                d = np.where(d > 0, d, near)
                continue
            rows = np.flatnonzero((d == 0) & np.any(H != 0, axis=1))
            if not rows.size:   # a zero row: singular
                return np.inf
            d[rows[0]] = np.sqrt(np.abs(H[rows[0]]).max())  # no diagonal to scale by
        S = H / d[:, None] / d[None, :]
        if m <= 2:              # eigenvalues mean +- r of [[a, c], [c, b]], any signs
            mean, r = (S[0, 0] + S[-1, -1]) / 2, math.hypot(
                (S[0, 0] - S[-1, -1]) / 2, S[0, -1] if m == 2 else 0.0)
            return (abs(mean) + r) / abs(abs(mean) - r) if abs(mean) != r else np.inf
        ev = np.abs(np.linalg.eigvalsh(S))   # symmetric, definite or not
        return float(ev.max() / ev.min()) if ev.min() > 0 else np.inf

    @_once
    def psi_rows(self) -> list:
        """Row s of Psi (``conditioning``): the unit row of qdot^s when independent, else
        m + its row in dphi/dqdot^mu."""
        m = len(self.velocities)
        return [self.velocities.index(v) if v in self.velocities
                else m + self.dependent.index(v) for v in self.system.J.qd]

    def _point(self, y, values: dict, t: float) -> dict:
        """The state ``y``, the parameters and ``t`` keyed by Symbol."""
        point = {s: float(v) for s, v in zip(self.states, y)}
        point.update((s, values[s.name]) for s in self.system.parameters)
        point[self.system.J.t] = t
        return point

    def uses(self, row: int, state: int) -> bool:
        """Whether row ``row`` depends on state ``state``: the symbol is in it and its
        derivative does not vanish identically (``zero.vanishes``)."""
        key = (row, state)
        if key not in self._uses:
            e, q = self.rows[row], self.states[state]
            self._uses[key] = (q in dag.free_symbols(e)
                               and not zero.vanishes(dag.diff(e, q)))
        return self._uses[key]

    def has_time(self, rows) -> bool:
        """Whether one of ``rows`` (state indices) or a holonomic constraint contains t
        with a derivative that does not vanish identically (``zero.vanishes``)."""
        key = ("t", tuple(rows))
        if key not in self._uses:
            t = self.system.J.t
            self._uses[key] = any(t in dag.free_symbols(e)
                                  and not zero.vanishes(dag.diff(e, t))
                                  for e in self._with_holonomic(rows))
        return self._uses[key]

    def _with_holonomic(self, rows) -> list:
        """The expressions of ``rows`` (state indices) and the holonomic constraints."""
        return [self.rows[i] for i in rows] + list(self.system.holonomic)

    def free_of_time(self, rows) -> bool:
        """Whether ``rows`` (state indices) and the holonomic constraints have the same
        values at every t: no derivative in t (``has_time``) and no kink in t either (an
        Abs or sign of t, rewritten sqrt(u**2) or u/sqrt(u**2), has a vanishing
        derivative on each side of its kink but other values on the other side)."""
        if self.has_time(rows):
            return False
        key = ("kink", tuple(rows))
        if key not in self._uses:
            t = self.system.J.t
            self._uses[key] = any(
                isinstance(e, sp.Pow) and not e.exp.is_integer
                and isinstance(e.base, sp.Pow) and e.base.exp == 2
                and t in dag.free_symbols(e.base.base)
                for x in self._with_holonomic(rows) for e in dag.nodes(x))
        return not self._uses[key]

    def frozen_time(self, rows, t: float) -> float:
        """The time at which ``rows`` (state indices) are evaluated at the point's ``t``:
        ``t`` itself, or 0 where they are the same at every t (``free_of_time``): a
        factor that cancels only on paper, such as exp(g t) exp(-g t) (a time-dependent
        Lagrangian e^(g t) L0), overflows the compiled rows at g t ~ 710; at t = 0 it
        is 1."""
        return 0.0 if self.free_of_time(rows) else t

    @_once
    def tied(self) -> dict:
        """Coordinate index -> the indices of the coordinates sharing a holonomic
        constraint with it (on g = 0 one moves with the others)."""
        out = {i: set() for i in range(len(self.coordinates))}
        for g in self.system.holonomic:
            used = [i for i, q in enumerate(self.coordinates) if q in dag.free_symbols(g)]
            for i in used:
                out[i].update(j for j in used if j != i)
        return out

    def cyclic(self) -> tuple[int, ...]:
        """Indices of the coordinates no kept row depends on and that share no holonomic
        constraint with a kept coordinate (the largest such set: a coordinate whose only
        users are dropped coordinates' rows is dropped too)."""
        n = len(self.coordinates)
        dropped = set(range(n))
        changed = True
        while changed:
            changed = False
            kept_rows = [i for i in range(len(self.states))
                         if i not in dropped and i not in self.inert]
            for c in sorted(dropped):
                if (any(self.uses(i, c) for i in kept_rows)
                        or self.tied[c] - dropped):
                    dropped.discard(c)
                    changed = True
                    break
        return tuple(sorted(dropped))

    @_once
    def inert(self) -> tuple[int, ...]:
        """State indices of the holonomic constraints' multipliers that no row depends on
        (a multiplier of D g = 0 enters the vakonomic, Hoelder and Suslov equations only
        through its rate): each is a pure zero mode, bookkeeping, left out of A."""
        n = len(self.coordinates) + len(self.velocities)
        rows = range(len(self.states))
        return tuple(n + a for a in self.system.holonomic_rows if a < len(self.lams)
                     and not any(self.uses(i, n + a) for i in rows))

    def kernels(self, params: dict, state: dict, t: float):
        """The compiled kernels (``rhs``, ``aux``, ``jac``), built on first use."""
        if self._kernels is None:
            from .kernels import jacobian_kernels
            from .scene import Scene

            scene = Scene(self.system, self.principle, params=params,
                          initial=state, t_span=(t, t + 1.0), form=self.form,
                          convention=self.convention, runtime_params=self.params)
            self._kernels = jacobian_kernels(scene)
        return self._kernels


class _Program:
    """Expressions on the shared graph as one straight-line Python function of numpy
    scalars, one line per distinct node, children first: ``dag.evaluate_numpy``'s
    operations in its order (a sum from 0 left to right, products left to right, numpy
    powers and the same numpy heads), so the same numbers bit for bit, without walking
    the graph at each call.  Called with a point (Symbol -> number), it returns the
    values as a float array; nodes it cannot write (none of the four kinds) leave the
    work to ``dag.evaluate_numpy``."""

    def __init__(self, exprs):
        self.exprs = [sp.sympify(e, strict=True) for e in exprs]
        try:
            self.symbols, self.function = self._compile()
        except (TypeError, ValueError, KeyError, NameError, SyntaxError):
            self.symbols, self.function = None, None

    def _compile(self):
        order = dag.nodes(self.exprs)
        symbols = [e for e in order if isinstance(e, sp.Symbol)]
        env, name, lines = {"power": np.power}, {}, []
        for k, e in enumerate(order):
            v = name[id(e)] = f"n{k}"
            args = [name[id(a)] for a in e.args]
            if isinstance(e, sp.Symbol):
                name[id(e)] = f"s{symbols.index(e)}"
            elif e.is_Number or e.is_NumberSymbol:
                env[v] = np.float64(float(e))
            elif e.is_Add:
                lines.append(f"{v} = 0 + {' + '.join(args)}")
            elif e.is_Mul:
                lines.append(f"{v} = {' * '.join(args)}")
            elif e.is_Pow:
                lines.append(f"{v} = power({args[0]}, {args[1]})")
            elif isinstance(e, sp.Function):
                xs = sp.symbols(f"a:{len(args)}", cls=sp.Dummy)
                env[f"h{k}"] = sp.lambdify(xs, e.func(*xs), "numpy")
                lines.append(f"{v} = h{k}({', '.join(args)})")
            else:
                raise ValueError(f"cannot write {e!r}")
        out = ", ".join(name[id(e)] for e in self.exprs)
        source = (f"def f({', '.join(f's{i}' for i in range(len(symbols)))}):\n"
                  + "".join(f"    {line}\n" for line in lines) + f"    return [{out}]\n")
        exec(compile(source, "<linearize sizes>", "exec"), env)
        return symbols, env["f"]

    def __call__(self, point: dict) -> np.ndarray:
        if self.function is None or any(s not in point for s in self.symbols):
            out = dag.evaluate_numpy(self.exprs, point)
        else:
            with np.errstate(all="ignore"):
                out = self.function(*[np.float64(point[s]) for s in self.symbols])
        return np.array([float(v) for v in out], dtype=float)


_KEEP_MODELS = 64         # systems whose derived model and kernels stay in memory


def _model(system, principle, form=None, convention="paper") -> _Model:
    """The model of ``system`` under ``principle`` (the last ``_KEEP_MODELS`` kept)."""
    key = (system, principle, form, convention)
    if key not in _MODELS:
        if len(_MODELS) >= _KEEP_MODELS:
            _MODELS.pop(next(iter(_MODELS)))
        _MODELS[key] = _Model(system, principle, form, convention)
    return _MODELS[key]


# ---------------------------------------------------------------------- the value
class Linearization(Frozen):
    """``x' = A x`` about an operating point (module docstring); from ``linearize``.

    ``A`` (read-only k x k), ``state_names``, ``eigenvalues`` (complex, by decreasing
    real part), ``rates`` (x' at the point), ``residual`` (its 2-norm: 0 for a steady
    motion), ``limit`` (True where the kernels are undefined at the point and A is
    their limit),
    ``at`` (every coordinate, velocity and multiplier at the point), ``params``,
    ``dropped`` (cyclic coordinate names left out), ``eliminated`` (coordinates that
    follow from the holonomic constraints), ``inert`` (holonomic multipliers left out),
    ``steady_motion`` (whether every kept rate is zero to the rounding of its inputs
    and terms, ``ROUNDING``, at every t for rows that depend on t), ``time_dependent`` (whether A or x' at the point change with t),
    ``verdict``, ``stable`` (the last two only at a steady motion whose A does not
    change with t), ``conditioning`` (of the reduced mass matrix at the point, scaled
    to a unit diagonal; linearize warns above ``CONDITION``).
    """

    def __init__(self, model: _Model, at: dict, params: dict, keep: tuple, chart: tuple,
                 E: np.ndarray, t: float, y: np.ndarray, p: np.ndarray, A: np.ndarray,
                 rates: np.ndarray, limit: bool, bound: np.ndarray, conditioning: float):
        self._model = model
        #: the condition number of the reduced mass matrix at the point, scaled to a
        #: unit diagonal (``_Model.conditioning``): above ``CONDITION`` linearize warns
        self.conditioning = conditioning
        self.system = model.system
        self.principle = model.principle
        self.t = t
        self.at = FrozenDict(at)
        self.params = FrozenDict(params)
        self._keep, self._chart, self._E = keep, chart, E
        E.setflags(write=False)
        self._y, self._p = y, p
        self.state_names = tuple(model.names[i] for i in keep)
        self.dropped = tuple(n.name for i, n in enumerate(model.coordinates)
                             if i not in keep and i not in chart)
        #: the coordinates that follow from the holonomic constraints g = 0 near the point
        self.eliminated = tuple(model.names[i] for i in chart)
        #: the holonomic constraints' multipliers left out (no equation depends on them)
        self.inert = tuple(model.names[i] for i in model.inert)
        A.setflags(write=False)
        self.A = A
        self.rates = rates
        rates.setflags(write=False)
        self.residual = float(np.linalg.norm(rates))
        ev, self._bounds = _spectrum(A)
        self.eigenvalues = ev
        #: True when A is the limit at a point where the kernel itself is undefined
        self.limit = limit
        changes, steady = False, bool(np.all(np.abs(rates) <= bound))
        if not model.free_of_time(keep):
            changes, steady = _in_time(self, bound)
        #: whether A or x' at the point change with t (rows that depend on t; module
        #: docstring): the frozen eigenvalues then decide nothing
        self.time_dependent = changes
        #: whether the point is a steady motion: every kept rate within ``ROUNDING`` of
        #: the rounding of its inputs and of the size of its terms, at ``t``
        #: and, for rows that depend on t, at the times ``t + TIMES`` too (module
        #: docstring)
        self.steady_motion = bool(steady)

    # ------------------------------------------------------------------ verdicts
    @property
    def margin(self) -> float:
        """The largest real part less its error bound, Re lambda_i - e_i (module
        docstring): > 0 unstable, <= 0 not; NaN off a steady motion and where A changes
        with t (``time_dependent``)."""
        if not self.steady_motion or self.time_dependent:
            return float("nan")
        return _margin(self.eigenvalues, self._bounds)

    @property
    def stable(self) -> bool | None:
        """No eigenvalue with a positive real part (spectral stability); None off a
        steady motion and where A changes with t, where the eigenvalues do not decide
        stability."""
        if not self.steady_motion or self.time_dependent:
            return None
        return self.margin <= 0

    @property
    def verdict(self) -> str:
        """``"unstable"``, ``"asymptotically stable"`` or ``"marginal"`` at a steady
        motion, ``"not a steady motion"`` elsewhere, ``TIME_DEPENDENT`` at a steady
        motion whose A changes with t (module docstring)."""
        ev = self.eigenvalues
        if not self.steady_motion:
            return NOT_STEADY
        if self.time_dependent:
            return TIME_DEPENDENT
        if self.margin > 0:
            return "unstable"
        if ev.size and np.all(ev.real < -self._bounds):
            return "asymptotically stable"
        return "marginal"

    # ------------------------------------------------------------------ other points
    def replace(self, params=None, at=None, t=None) -> "Linearization":
        """The linearization at other parameter values and/or another operating point:
        a kernel call, no derivation.

        Parameters
        ----------
        params : dict, optional
            Parameter values to change (the others keep theirs).
        at : dict, optional
            Values of the point to change: names not given keep their values,
            dependent velocities follow from the constraints again.
        t : float, optional
            Another time of the point.
        """
        point = {k: v for k, v in self.at.items()
                 if k not in {d.name for d in self._model.dependent}}
        if at is not None:
            point.update(_keyed(at, "at"))
        values = dict(self.params)
        if params is not None:
            values = _params(self._model, {**values, **_keyed(params, "params")}, {})
        return _evaluate(self._model, point, values, self._keep,
                         self.t if t is None else arguments.finite(t, "t"))

    def steady(self, unknowns, tol: float = 1e-10) -> "Linearization":
        """The linearization at a steady motion: the values of ``unknowns`` that make
        x' vanish, starting from this point's values (the others held).
        ``LinearizationError`` when none is found near them, or, for equations that
        depend on t, when x' vanishes at this t only.

        Parameters
        ----------
        unknowns : str or list of str
            Names of kept states (e.g. the multipliers) to solve for.
        tol : float, default 1e-10
            The accepted size of each rate, relative to the size of its terms and the
            rounding of this point's states, parameters and t through it (the scale of
            ``steady_motion``'s test;
            where a rate has neither, the smallest other one's).  The result counts as a
            steady motion to that accuracy.
        """
        from scipy.optimize import least_squares

        tol = arguments.positive(tol, "tol")
        unknowns = [arguments.name_of(u, "unknowns") for u in (
            [unknowns] if isinstance(unknowns, (str, sp.Symbol)) else unknowns)]
        if not unknowns:
            raise ArgumentError("names no state to solve for: give the kept states whose "
                                "values make x' vanish (e.g. the multipliers, or a "
                                f"velocity), from {', '.join(self.state_names)}",
                                argument="unknowns")
        model = self._model
        idx = []
        for u in unknowns:
            if u not in self.state_names:
                raise ArgumentError(
                    f"cannot solve for {u!r}: the unknowns of a steady motion are kept "
                    f"states ({', '.join(self.state_names)})")
            idx.append(model.names.index(u))
        ck = self._kernels
        keep = list(self._keep)
        cols = [keep.index(i) for i in idx]
        y, p, t = self._y.copy(), self._p, model.frozen_time(self._keep, self.t)
        f = np.empty(len(model.names))
        Jm = np.empty((len(model.names), len(model.names)))
        moves = self._chart and any(i < len(model.coordinates) for i in idx)

        def put(u):             # the unknowns, and the coordinates g = 0 then gives
            y[idx] = u
            if moves:
                for nm, v in self._on_g({model.names[i]: y[i] for i in idx}, {}).items():
                    y[model.names.index(nm)] = v

        ck.jac(t, y, p, Jm)
        weight = (model.sizes_at(keep, y, dict(self.params), t)
                  + np.abs(Jm[keep]) @ np.abs(y) + _inputs(ck, t, y, p, keep))
        weight[~np.isfinite(weight)] = 0.0
        weight[weight == 0] = weight[weight > 0].min(initial=1.0)

        def residual(u):
            put(u)
            ck.rhs(t, y, p, f)
            return f[keep] / weight

        def jacobian(u):
            put(u)
            ck.jac(t, y, p, Jm)
            if not moves:
                return Jm[np.ix_(keep, idx)] / weight[:, None]
            G = holonomic.jacobian_at(self.system, _configuration(
                model, y, dict(self.params), t))
            return (Jm[keep] @ _embedding(model, self._keep, self._chart, G))[:, cols] \
                / weight[:, None]

        u0 = self._y[idx].copy()
        with np.errstate(all="ignore"):     # the unknowns in units of unit columns
            unit = np.linalg.norm(jacobian(u0), axis=0)
        unit[~(np.isfinite(unit) & (unit > 0))] = 1.0
        try:                    # (the gradient test gtol is then relative to the rates)
            sol = least_squares(lambda w: residual(w / unit), u0 * unit,
                                jac=lambda w: jacobian(w / unit) / unit, method="trf",
                                xtol=1e-15, ftol=1e-15, gtol=1e-15, max_nfev=200)
            x, bad = sol.x / unit, not np.all(np.isfinite(sol.fun))
        except ValueError:       # a non-finite residual at the start
            x, bad = u0, True
        size = float(np.abs(residual(x)).max()) if not bad else float("nan")
        if bad or not size <= tol:
            given = ", ".join(f"{n} = {self.at[n]:.6g}" for n in self.state_names
                              if n not in unknowns)
            raise LinearizationError(
                f"no steady motion found by solving for {', '.join(unknowns)} with "
                f"{given} held (the largest rate is {size:.3g} of its scale at the best point, "
                f"{dict(zip(unknowns, np.round(x, 12).tolist()))}); start from another "
                "guess (replace(at=...)), solve for other values, or fix fewer of them")
        put(x)
        point = {k: v for k, v in self.at.items()
                 if k not in {d.name for d in model.dependent}}
        point.update((model.names[i], float(y[i])) for i in (*idx, *self._chart))
        found = _evaluate(model, point, dict(self.params), self._keep, self.t, tol * weight)
        if found.time_dependent and not found.steady_motion:
            raise LinearizationError(
                f"x' vanishes at t = {self.t:g} with {', '.join(unknowns)} = "
                f"{np.round(x, 12).tolist()}, but not at other times: the equations depend "
                "on t, and a point where x' vanishes for an instant is no steady motion; "
                "solve for other values, or hold those that keep x' = 0 at every t")
        return found

    def along(self, name, values) -> "StabilityScan":
        """Eigenvalues along a parameter or an operating-point value (every other value
        held, but the ``eliminated`` coordinates, which follow from g = 0): a
        ``StabilityScan`` with the crossings of Re lambda = 0 (between neighbouring
        values that are both steady motions).

        Parameters
        ----------
        name : str or Symbol
            A parameter or a value of the operating point.
        values : array_like
            The values of ``name`` to linearize at, in order.
        """
        name = arguments.name_of(name, "along")
        values = arguments.real_array(values, "values")
        if values.size == 0:
            raise ArgumentError("along needs at least one value to linearize at, got none; "
                                "give values, e.g. np.linspace(0.5, 5, 50)")
        if name not in self.params and name not in self.at:
            raise ArgumentError(f"{name!r} is neither a parameter ({', '.join(self.params)}) "
                             f"nor a value of the operating point ({', '.join(self.at)})")

        def move(v):
            if name in self.params:
                return self.replace(params={name: v}, at=self._on_g({}, {name: v}))
            return self.replace(at={**self._on_g({name: v}, {}), name: v})
        lins = [move(float(v)) for v in values]
        ev = np.array([lin.eigenvalues for lin in lins])
        margins = np.array([lin.margin for lin in lins])
        steady = np.array([lin.steady_motion for lin in lins])
        timed = np.array([lin.time_dependent for lin in lins])
        crossings = []
        for i in range(len(values) - 1):
            a, b = margins[i], margins[i + 1]
            if np.isfinite(a) and np.isfinite(b) and (a > 0) != (b > 0):
                crossings.append(_crossing(move, float(values[i]), float(values[i + 1]),
                                            lins[i], lins[i + 1]))
        return StabilityScan(name, values, ev, margins, tuple(crossings), self.state_names,
                             steady, timed)

    def _on_g(self, at: dict, params: dict) -> dict:
        """The eliminated coordinates solved from g = 0 (Newton's method from their
        values here) with ``at`` and ``params`` changed: name -> value."""
        if not self.eliminated:
            return {}
        model = self._model
        y = self._y.copy()
        for nm, v in at.items():
            y[model.names.index(nm)] = v
        point = _configuration(model, y, {**self.params, **params}, self.t)
        done, _ = holonomic.check(self.system, point, complete=list(self.eliminated))
        return {model.names[i]: float(done[model.coordinates[i]]) for i in self._chart}

    # ------------------------------------------------------------------ symbolic
    def symbolic(self) -> sp.Matrix:
        """A in the user's symbols (states, parameters, t): ``dag.jacobian`` of the
        kept rows on the shared graph (evaluate it with ``dag.evaluate``).  With
        holonomic constraints it holds every coordinate, the eliminated ones too (give
        them their values on g = 0): the columns of the kept coordinates carry the
        eliminated ones' motion -(dg/dq^D)^-1 dg/dq^I.  Rows that do not depend on t
        (identically) hold no t: it is set to 0 in them, which cancels factors such as
        exp(g t) exp(-g t)."""
        return _symbolic(self._model, self._keep, self._chart)

    @property
    def _kernels(self):
        return self._model._kernels

    def __repr__(self):
        return (f"Linearization({self.principle}, states={list(self.state_names)}, "
                f"residual={self.residual:.3g}, verdict={self.verdict!r})")


def _symbolic(model: _Model, keep, chart) -> sp.Matrix:
    key = (keep, chart)
    if key not in model._symbolic:
        rows = [model.rows[i] for i in keep]
        if model.free_of_time(keep):        # t = 0 cancels exp(g t) exp(-g t)
            rows = dag.xreplace(rows, {model.system.J.t: sp.Integer(0)})
        A = dag.jacobian(rows, [model.states[i] for i in keep])
        if chart:
            G = holonomic.jacobian(model.system)
            ind = [c for c, i in enumerate(keep) if i < len(model.coordinates)]
            T = -linalg.solve(G[:, list(chart)], G[:, [keep[c] for c in ind]])
            moved = linalg.matmul(dag.jacobian(rows, [model.states[i] for i in chart]), T)
            for k, c in enumerate(ind):
                A[:, c] = A[:, c] + moved[:, k]
        model._symbolic[key] = A
    return model._symbolic[key]


def _spectrum(A: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """The eigenvalues of A by decreasing real part, and each one's error bound e_i
    (module docstring); read-only."""
    from scipy.linalg import eig, get_lapack_funcs

    if not A.size:
        ev, bounds = np.zeros(0, complex), np.zeros(0)
    else:
        B = get_lapack_funcs("gebal", (A,))(A, scale=1, permute=1)[0]   # A balanced
        ev, left, right = eig(B, left=True, right=True)
        with np.errstate(divide="ignore"):
            kappa = 1.0 / np.abs(np.sum(left.conj() * right, axis=0))
        delta = REAL * float(np.linalg.norm(B))
        apart = np.abs(ev[:, None] - ev[None, :])
        np.fill_diagonal(apart, np.inf)
        gap = apart.min(axis=1) / 2
        with np.errstate(invalid="ignore"):
            second = np.where(gap > 0, np.sqrt(2 * delta * kappa * gap), np.inf)
        bounds = np.minimum.reduce([delta * kappa, np.maximum(delta, second),
                                    np.full(len(ev), ZERO / REAL * delta)])
        order = np.lexsort((ev.imag, -ev.real))
        ev, bounds = ev[order].astype(complex), bounds[order]
    ev.setflags(write=False)
    bounds.setflags(write=False)
    return ev, bounds


def _margin(ev: np.ndarray, bounds: np.ndarray) -> float:
    """max_i (Re lambda_i - e_i): > 0 when an eigenvalue lies right of the imaginary
    axis by more than its error bound (0 without eigenvalues)."""
    return float((ev.real - bounds).max()) if ev.size else 0.0


def _in_time(lin: Linearization, bound: np.ndarray) -> tuple[bool, bool]:
    """``(changes, steady)`` of a point whose rows contain t: whether A or x' differ at
    the times ``t + TIMES`` times the larger of ``|t|`` and A's time scale 1/|B| (B: A
    balanced, Frobenius norm; 1 where A is 0) (A by more than ``REAL`` of its size in
    balanced units, ``_difference``; a rate by more than its ``bound``) and whether
    every rate is within its bound at t and at each of them: no number 1 in another
    unit of time.  The state is held;
    with holonomic constraints it must stay on g = 0 and A is taken in the chart there.
    A time where the point leaves g = 0 or the equations are undefined changes and is
    not steady; one where an exponential overflows (``_Model.overflow``: exp(g t) of
    rows that cancel it on paper), or where the rows are undefined and an exponent is
    beyond ``LARGE`` or has grown by ``GROWTH`` since t (a product such as g exp(g t)
    overflowed), is left out, and fewer than two left is a LinearizationError."""
    model, keep, chart = lin._model, lin._keep, lin._chart
    y, p, ck = lin._y, lin._p, lin._kernels
    changes, steady = False, bool(np.all(np.abs(lin.rates) <= bound))
    model_values = dict(lin.params)
    D = _balanced(lin.A)
    size = float(np.linalg.norm(lin.A * D[None, :] / D[:, None])) if lin.A.size else 0.0
    span = max(abs(lin.t), 1.0 / size if 0 < size < np.inf else 0.0) or 1.0
    same = np.zeros(len(lin.rates))
    over, top = [], model.growth(keep, y, model_values, lin.t)[0]
    for s in TIMES:
        t = lin.t + s * span
        if model.overflow(keep, y, model_values, t) is not None:
            over.append(t)
            continue
        E = lin._E
        if model.system.holonomic:
            point = _configuration(model, y, dict(lin.params), t)
            g = holonomic.residual(model.system, point)
            if not np.all(np.abs(g) <= holonomic.bound(model.system, point)):
                return True, False
            E = _embedding(model, keep, chart, holonomic.jacobian_at(model.system, point))
        try:
            A, rates, _, here = _jacobian(model, ck, y, p, model_values, t, keep, E)
        except LinearizationError:
            if model.growth(keep, y, model_values, t)[0] > min(LARGE, top + GROWTH):
                over.append(t)              # a product such as g exp(g t) overflowed
                continue
            return True, False
        changes = changes or bool(
            _difference(A, lin.A, same, same, same) > REAL
            or np.any(np.abs(rates - lin.rates) > np.maximum(bound, here)))
        steady = steady and bool(np.all(np.abs(rates) <= here))
    if len(TIMES) - len(over) < 2:
        raise LinearizationError(
            f"the equations overflow at the times t = {', '.join(f'{v:.6g}' for v in over)} "
            f"that decide whether the point is a steady motion at every t "
            f"({model.overflow(keep, y, model_values, over[0], -np.inf)}): factors such as "
            "exp(g t) exp(-g t) do not cancel in the compiled equations; linearize at "
            "another t, or with the factor cancelled in the equations")
    return changes, steady


def _crossing(move, a: float, b: float, lo: "Linearization", hi: "Linearization") -> float:
    """Where the margin changes sign in [a, b]; then, where the largest real part
    crosses 0 transversally (well clear of its error bound on both sides within 1e-6,
    1e-4 or 1e-2 of the interval), its own root.  The eigenvalues zero at both ends
    (within their bounds: a family of steady motions) are left out of that largest real
    part, the others kept (a real eigenvalue passing through 0 is zero within its bound
    near its root)."""
    zeros = min(int(np.sum(np.abs(x.eigenvalues) <= x._bounds)) for x in (lo, hi))

    def top(v):
        lin = move(v)
        rest = np.argsort(np.abs(lin.eigenvalues), kind="stable")[zeros:]
        if not rest.size:
            return 0.0, 0.0, 0.0
        k = rest[np.argmax(lin.eigenvalues.real[rest])]
        slack = lin.eigenvalues.real[rest] - lin._bounds[rest]
        return float(lin.eigenvalues.real[k]), float(lin._bounds[k]), float(slack.max())

    def margin(v):
        return top(v)[2]
    if (margin(a) > 0) == (margin(b) > 0):
        return _root(lambda v: move(v).margin, a, b)
    r = _root(margin, a, b)
    for h in (1e-6 * (b - a), 1e-4 * (b - a), 1e-2 * (b - a)):
        lo_, hi_ = max(a, r - h), min(b, r + h)
        (fl, tol, _), (fh, tol_h, _) = top(lo_), top(hi_)
        if min(abs(fl), abs(fh)) > 100 * max(tol, tol_h):
            return _root(lambda v: top(v)[0], lo_, hi_) if (fl > 0) != (fh > 0) else r
    return r


def _root(f, a: float, b: float) -> float:
    """The point in [a, b] where ``f`` changes sign (Brent, to 1e-13 relative)."""
    from scipy.optimize import brentq

    return float(brentq(f, a, b, xtol=1e-14, rtol=4 * np.finfo(float).eps, maxiter=200))


class StabilityScan(Frozen):
    """Eigenvalues along one value: ``values``, ``eigenvalues`` (one row per value, each
    by decreasing real part), ``margins`` (``Linearization.margin``: NaN off a steady
    motion and where A changes with t), ``steady_motion`` and ``time_dependent``
    (``Linearization``'s at each value), ``crossings`` (the values where the motion
    gains or loses stability, to 1e-13 relative), ``frame`` and ``plot``."""

    def __init__(self, name, values, eigenvalues, margins, crossings, state_names,
                 steady_motion, time_dependent):
        self.name = name
        for a in (values, eigenvalues, margins, steady_motion, time_dependent):
            a.setflags(write=False)
        self.values, self.eigenvalues, self.margins = values, eigenvalues, margins
        self.steady_motion, self.time_dependent = steady_motion, time_dependent
        self.crossings = crossings
        self.state_names = state_names

    @property
    def stable(self) -> np.ndarray:
        """True where the value gives a steady motion without an eigenvalue of positive
        real part; False elsewhere, off steady motions and where A changes with t too
        (undecided there: see ``steady_motion`` and ``time_dependent``)."""
        return self.margins <= 0

    @property
    def frame(self):
        """pandas DataFrame: one row per value, the value, ``re_i`` and ``im_i`` of each
        eigenvalue (i = 1..k by decreasing real part), ``steady_motion``,
        ``time_dependent`` and ``stable``."""
        import pandas as pd

        k = self.eigenvalues.shape[1] if self.eigenvalues.ndim == 2 else 0
        data = {self.name: self.values}
        for i in range(k):
            data[f"re_{i + 1}"] = self.eigenvalues[:, i].real
        for i in range(k):
            data[f"im_{i + 1}"] = self.eigenvalues[:, i].imag
        data["steady_motion"] = self.steady_motion
        data["time_dependent"] = self.time_dependent
        data["stable"] = self.stable
        return pd.DataFrame(data)

    def plot(self, ax=None):
        """Re and Im of the eigenvalues against the value, the stable ranges shaded and
        the crossings marked: a matplotlib Axes."""
        import matplotlib.pyplot as plt

        if ax is None:
            _, ax = plt.subplots(figsize=(6.4, 4.0))
        v, ev = self.values, self.eigenvalues
        k = ev.shape[1] if ev.ndim == 2 else 0
        for i in range(k):
            ax.plot(v, ev[:, i].real, ".", color="C0", ms=3,
                    label="Re λ" if i == 0 else None)
            ax.plot(v, ev[:, i].imag, ".", color="C1", ms=2, alpha=0.6,
                    label="Im λ" if i == 0 else None)
        stable = self.stable
        start = None
        for i, s in enumerate(list(stable) + [False]):
            if s and start is None:
                start = i
            elif not s and start is not None:
                ax.axvspan(v[start], v[i - 1], color="C2", alpha=0.15,
                           label="stable" if start == np.argmax(stable) else None)
                start = None
        for c in self.crossings:
            ax.axvline(c, color="k", lw=0.8, ls="--")
        ax.axhline(0.0, color="k", lw=0.5)
        ax.set_xlabel(self.name)
        ax.set_ylabel("eigenvalue λ")
        ax.legend(loc="best")
        return ax

    def __repr__(self):
        return (f"StabilityScan({self.name}, {len(self.values)} values, "
                f"crossings={[round(c, 10) for c in self.crossings]})")


# ---------------------------------------------------------------------- entry points
def linearize(system, principle="chetaev", at=None, params=None, drop="cyclic", *,
              t=0.0, form=None, convention="paper") -> Linearization:
    """``x' = A x`` of ``principle``'s reduced system about the point ``at`` (module
    docstring).

    Parameters
    ----------
    system : jetnh.System
        The constrained system.
    principle : str, default "chetaev"
        "chetaev", "vakonomic", "holder" or "suslov".
    at : dict
        The operating point: coordinates, independent velocities and multipliers keyed
        by Symbol or name.  Dependent velocities follow from the constraints (if given
        they must agree); dropped coordinates that no holonomic constraint uses and
        inert multipliers may be omitted (their values do not enter A).  The
        coordinates must satisfy the holonomic constraints g = 0.
    params : dict, optional
        Parameter values keyed by Symbol or name; the system's defaults otherwise.
    drop : {"cyclic"} or list or None, default "cyclic"
        The coordinates left out of the state: the cyclic ones (no equation depends on
        them), a list of names, or None for none.
    t : float, default 0.0
        The time of the point (for systems that depend on t: A and the eigenvalues are
        those frozen at this t, and decide no stability; module docstring).
    form, convention : optional
        The equations' form and the multipliers' sign convention, as for ``Scene``.

    Returns
    -------
    Linearization
        A, its eigenvalues, the residual x' at the point and the verdict.
    """
    if not isinstance(system, System):
        raise ArgumentError(f"linearize needs a jetnh System, got {type(system).__name__}")
    principle = principles.canonical(principle)
    model = _model(system, principle, form, convention)
    if not isinstance(at, Mapping):
        raise ArgumentError("at must be a dict of the operating point's values keyed by "
                         f"Symbol or name ({', '.join(model.names)}), got "
                         f"{type(at).__name__}")
    point = _keyed(at, "at")
    values = _params(model, params or {}, system.defaults)
    keep = _kept(model, drop)
    return _evaluate(model, point, values, keep, arguments.finite(t, "t"))


def verdicts(system, at, params=None, principles_=None, drop="cyclic", solve_for=None):
    """One operating point under several principles: a pandas DataFrame, one row per
    principle, with its residual, state size, largest real part, verdict and
    eigenvalues (a principle that fails has its error in the verdict column; one for
    which the point is no steady motion has the verdict "not a steady motion", one whose
    A changes with t ``TIME_DEPENDENT``).

    Parameters
    ----------
    system : jetnh.System
        The constrained system.
    at : dict
        The operating point as for ``linearize``; missing multipliers start at 0.
    params : dict, optional
        Parameter values; the system's defaults otherwise.
    principles_ : list of str, optional
        The principles compared; all four by default.
    drop : {"cyclic"} or list or None, default "cyclic"
        As for ``linearize``.
    solve_for : list of str or dict, optional
        Names (or a dict principle -> names, e.g. the multipliers) solved for first
        so that each point is steady (``Linearization.steady``).
    """
    import pandas as pd

    rows = []
    for pr in principles_ or principles.PRINCIPLES:
        pr = principles.canonical(pr)
        model = _model(system, pr)
        point = dict(_keyed(at, "at"))
        for lam in model.lams:
            point.setdefault(lam.name, 0.0)
        try:
            lin = linearize(system, pr, at=point, params=params, drop=drop)
            unknown = solve_for.get(pr) if isinstance(solve_for, Mapping) else solve_for
            if unknown:
                lin = lin.steady(unknown)
        except JetnhError as err:
            rows.append({"principle": pr, "residual": np.nan, "states": None,
                         "max_real": np.nan, "verdict": f"error: {err}",
                         "eigenvalues": None})
            continue
        rows.append({"principle": pr, "residual": lin.residual,
                     "states": len(lin.state_names),
                     "max_real": float(lin.eigenvalues.real.max(initial=-np.inf)),
                     "verdict": lin.verdict, "eigenvalues": lin.eigenvalues})
    return pd.DataFrame(rows).set_index("principle")


# ---------------------------------------------------------------------- helpers
def _keyed(values, what) -> dict[str, float]:
    if not isinstance(values, Mapping):
        raise ArgumentError(f"{what} must be a dict keyed by Symbol or name, got "
                         f"{type(values).__name__}")
    out = {}
    for k, v in values.items():
        name = arguments.name_of(k, what)
        out[name] = arguments.real(v, f"{what}[{name!r}]")
        if not np.isfinite(out[name]):
            raise ArgumentError(f"{what}[{name!r}] is {out[name]}; give a finite value")
    return out


def _params(model: _Model, params, defaults) -> dict[str, float]:
    out = {s.name: float(v) for s, v in defaults.items()}
    for name, v in _keyed(params, "params").items():
        if name not in model.params:
            raise ArgumentError(f"params has {name!r}, which is not a parameter of this "
                             f"system; its parameters are {list(model.params) or 'none'}")
        out[name] = v
    missing = [n for n in model.params if n not in out]
    if missing:
        raise ArgumentError(f"missing parameter values: {', '.join(missing)}; give them in "
                         "params={...}")
    return {n: out[n] for n in model.params}


def _kept(model: _Model, drop) -> tuple[int, ...]:
    """The state indices kept: every state but the dropped coordinates and the inert
    multipliers (``_Model.inert``)."""
    n = len(model.coordinates)
    names = [q.name for q in model.coordinates]
    if drop is None:
        gone: tuple = ()
    elif isinstance(drop, str) and drop == "cyclic":
        gone = model.cyclic()
    elif isinstance(drop, (list, tuple, set, frozenset)):
        gone = []
        for d in drop:
            name = arguments.name_of(d, "drop")
            if name not in names:
                raise ArgumentError(f"drop has {name!r}, which is not a coordinate; the "
                                 f"coordinates are {', '.join(names)}")
            gone.append(names.index(name))
        gone = tuple(sorted(set(gone)))
        kept_rows = [i for i in range(len(model.states))
                     if i not in gone and i not in model.inert]
        cyclic = ", ".join(names[i] for i in model.cyclic()) or "nothing"
        for c in gone:
            users = [model.names[i] for i in kept_rows if model.uses(i, c)]
            if users:
                raise ArgumentError(
                    f"cannot drop {names[c]!r}: the equations of {', '.join(users)} depend "
                    f"on it; keep it, or use drop='cyclic' (drops {cyclic})")
            tied = [names[j] for j in sorted(model.tied[c]) if j not in gone]
            if tied:
                raise ArgumentError(
                    f"cannot drop {names[c]!r}: a holonomic constraint ties it to "
                    f"{', '.join(tied)}, which is kept; keep it, drop those too, or use "
                    f"drop='cyclic' (drops {cyclic})")
    else:
        raise ArgumentError(f"drop must be 'cyclic', a list of coordinates or None, not "
                         f"{drop!r}")
    return tuple(i for i in range(len(model.states))
                 if not (i < n and i in gone) and i not in model.inert)


def _evaluate(model: _Model, point: dict, values: dict, keep, t: float,
              floor=None) -> Linearization:
    """The Linearization at one point (checked) with the compiled kernels; ``floor``:
    rates accepted as zero in the steady test besides its own bound (``steady``'s)."""
    names = model.names
    dep = [v.name for v in model.dependent]
    allowed = set(names) | set(dep)
    for k in point:
        if k not in allowed:
            raise ArgumentError(
                f"at has {k!r}, which is not a state of the {model.principle} system; the "
                f"states are {', '.join(names)} (and the dependent velocities "
                f"{', '.join(dep) or 'none'})")
    n = len(model.coordinates)
    on_g = {q.name for q in model.coordinates
            if any(q in dag.free_symbols(g) for g in model.system.holonomic)}
    missing = [nm for i, nm in enumerate(names) if nm not in point and i not in model.inert
               and (i >= n or i in keep or nm in on_g)]
    if missing:
        lams = [s.name for s in model.lams]
        raise ArgumentError(
            f"missing operating-point values: {', '.join(missing)}"
            + (f" (the {model.principle} state includes the multipliers {', '.join(lams)})"
               if set(missing) & set(lams) else "")
            + "; give them in at={...}")
    state = {nm: point.get(nm, 0.0) for nm in names}
    other = _split(model, point, state, values, keep, t)
    if other is not None:
        return _evaluate(*other)
    y = np.array([state[nm] for nm in names], dtype=float)
    chart, G = _chart(model, y, values, t)
    rows = tuple(i for i in keep if i not in chart)
    E = _embedding(model, rows, chart, G)
    ck = model.kernels(values, state, t)
    p = np.array([values[nm] for nm in model.params], dtype=float)
    aux = np.empty(ck.layout.n_aux)
    k = len(dep)
    coordinate = {v.name: model.coordinates.index(q) for v, q in zip(
        model.dependent, (model.system.J.split(v)[0] for v in model.dependent))}
    ta = model.frozen_time(tuple(coordinate.values()), t)    # phi's time
    ck.aux(ta, y, p, aux)
    at = dict(state)
    for a, nm in enumerate(dep):
        v = float(aux[a])
        if not np.isfinite(v):
            raise ConstraintError(
                f"the constraints give no finite value for {nm} at this point: it is "
                f"singular for the split {[s.name for s in model.system.dependent]}; "
                "choose another operating point or another split (dependent=)")
        if nm in point and abs(point[nm] - v) > CONSISTENT * _size(
                model, coordinate[nm], ck, y, p, values, ta, v, abs(point[nm] - v)):
            raise ConstraintError(
                f"the point is off the constraints: at gives {nm} = {point[nm]!r} but the "
                f"constraints give {v!r}; omit it (dependent velocities follow from the "
                "constraints)")
        at[nm] = v
    if k and not np.all(np.isfinite(aux[k:2 * k])):
        raise ConstraintError("the constraints are undefined at this point")
    te = model.frozen_time(rows, t)
    A, rates, limit, bound = _jacobian(model, ck, y, p, values, te, rows, E)
    if floor is not None and len(floor) == len(bound):
        bound = np.maximum(bound, floor)
    cond = model.conditioning(y, values, te)
    if not limit and not cond <= CONDITION:
        warnings.warn(
            f"linearize: the reduced mass matrix is nearly singular at this point "
            f"(condition number {cond:.3g} scaled to a unit diagonal, above "
            f"{CONDITION:.3g} = 1e-8/eps): A and the rates may carry relative errors "
            f"of about {cond * EPS:.2g}, beyond what the verdict assumes; linearize in "
            "coordinates in which the mass matrix is regular here, or away from this "
            "configuration or these parameter values", JetnhWarning, stacklevel=3)
    return Linearization(model, at, values, rows, chart, E, t, y, p, A, rates, limit, bound,
                         cond)


def _size(model: _Model, i: int, ck, y, p, values: dict, t: float, v: float,
          miss: float) -> float:
    """The scale against which a given dependent velocity is compared with the value
    ``v`` the constraints give (row ``i``, the rate of its coordinate): the size of the
    terms of phi there and the rounding of the point through it, never the number 1
    (the terms only where ``miss`` exceeds the others)."""
    m = len(y)
    Jm = np.empty((m, m))
    ck.jac(t, y, p, Jm)
    rounding = float(np.abs(Jm[i]) @ np.abs(y))
    if miss <= CONSISTENT * max(abs(v), rounding if math.isfinite(rounding) else 0.0):
        return max(abs(v), rounding)
    terms = float(model.sizes_at([i], y, values, t)[0])
    return max(abs(v), terms if math.isfinite(terms) else 0.0,
               rounding if math.isfinite(rounding) else 0.0)


def _split(model: _Model, point: dict, state: dict, values: dict, keep, t: float):
    """None to linearize in the model's own split; ``(model, point, values, keep, t)``
    of the split of largest measure where the own one is past the edge of its chart
    (module docstring): the point's velocities are those given, on the constraints, or
    the dependent ones from phi where the split determines them.  A ConstraintError for
    a point off the constraints, or one without its dependent velocities where the split
    is singular."""
    sysm = model.system
    dep = [v.name for v in model.dependent]
    if not dep:
        return None
    given = all(nm in point for nm in dep)
    qd = {v.name: state[v.name] for v in model.velocities}
    found = regular.phi(sysm, t, state, qd, values)
    phi = [found[nm] for nm in dep]
    qd.update((nm, point[nm] if given else phi[a]) for a, nm in enumerate(dep))
    A, f = regular.at_point(sysm, t, state, qd, values)
    m = float(regular.measure(sysm, A))
    if not regular.past_edge(sysm, m):
        return None
    ok, why, finite = regular.determined(sysm, t, state, qd, values, CONSISTENT)
    if not given and not ok:
        raise regular.singular(sysm, m, A, "linearize", why, finite)
    if given and not regular.on_constraints(sysm, t, state, qd, values, CONSISTENT):
        raise regular.off(sysm, f, "linearize")
    from .atlas import split_invariant

    own = [s.name for s in sysm.dependent]
    split, _ = regular.best(sysm, A)
    explicit = bool(model.lams) and principles.get(model.principle).form(model.form).explicit
    if set(split) == set(own):
        return None
    if not split_invariant(model.principle, model.convention) or explicit:
        if not given or ok:     # the own split still determines the point: _evaluate
            return None         # judges given velocities against it
        why = ("the multipliers of the explicit form weigh the singular split"
               if explicit else f"the {model.principle} motions in the "
               f"{model.convention!r} convention depend on the split")
        raise ConstraintError(
            f"linearize: the point is on the constraints, but the split dependent={own} is "
            f"past the edge of its chart here (measure {m:.3g}) and {why}: linearize the "
            f"system built with dependent={split} (or another regular split)")
    new = _model(sysm.with_split(split), model.principle, model.form, model.convention)
    moved = {q.name: state[q.name] for q in model.coordinates}
    moved.update(qd)
    moved.update((b.name, state[a.name]) for a, b in zip(model.lams, new.lams))
    n = len(model.coordinates)
    keep = tuple(i for i in range(len(new.states))
                 if (i >= n or i in keep) and i not in new.inert)
    return new, moved, values, keep, t


def _configuration(model: _Model, y, values: dict, t: float) -> dict:
    """t, the coordinates of state ``y`` and the parameters, by name (for
    ``mechanics.holonomic``)."""
    return {"t": t, **{q.name: float(v) for q, v in zip(model.coordinates, y)}, **values}


def _chart(model: _Model, y, values: dict, t: float):
    """``(chart, G)``: the indices of the coordinates that follow from g = 0 near the
    configuration of ``y`` (``holonomic.completion_coordinates``: the split's dependent
    ones where they can be solved for) and dg/dq there; ``((), None)`` without holonomic
    constraints.  A configuration off g = 0 is a ConstraintError with the residual and
    values that would put it on g = 0."""
    sysm = model.system
    if not sysm.holonomic:
        return (), None
    point = _configuration(model, y, values, t)
    g = holonomic.residual(sysm, point)
    if not np.all(np.isfinite(g)) or np.any(np.abs(g) > holonomic.bound(sysm, point)):
        told = "; ".join(f"g{i + 1} = {e} is {v:.6g}"
                         for i, (e, v) in enumerate(zip(sysm.holonomic, g)))
        try:
            _, moved = holonomic.check(sysm, point, complete=True)
            fix = (", e.g. " + ", ".join(f"{nm} = {new!r}" for nm, (_, new) in
                                         moved.items()) + " with the others held")
        except ConstraintError:
            fix = ""
        raise ConstraintError(
            f"the operating point is off the holonomic constraints: {told} (should be 0). "
            f"A linearization perturbs within g = 0: give coordinates on it{fix}")
    deps = holonomic.completion_coordinates(sysm, point)
    chart = tuple(model.coordinates.index(q) for q in deps)
    return chart, holonomic.jacobian_at(sysm, point)


def _embedding(model: _Model, rows, chart, G) -> np.ndarray:
    """E (all states x kept states): a kept state's column is its unit vector, plus, for
    a coordinate, the motion of the ``chart`` coordinates that keeps g = 0 to first
    order (dq^D = -(dg/dq^D)^-1 dg/dq^I dq^I).  A = (rows of x') E."""
    E = np.zeros((len(model.states), len(rows)))
    E[list(rows), range(len(rows))] = 1.0
    if chart:
        ind = [(c, i) for c, i in enumerate(rows) if i < len(model.coordinates)]
        T = -np.linalg.solve(G[:, list(chart)], G[:, [i for _, i in ind]])
        for a, d in enumerate(chart):
            E[d, [c for c, _ in ind]] = T[a]
    return E


def _jacobian(model: _Model, ck, y, p, values: dict, t, rows, E):
    """(A, x', limit, bound): the kernels at the point, A = (rows of dx'/dx) E, and
    the largest rate of each kept row at a steady motion (``ROUNDING``);
    where they are undefined (0/0), the limit by ``_settled``, or an error."""
    with np.errstate(invalid="ignore", over="ignore"):   # (NaN rows are checked here)
        return _settled(model, ck, y, p, values, t, list(rows), E)


def _balanced(A: np.ndarray) -> np.ndarray:
    """The diagonal D of A's balancing (LAPACK's ``gebal``, no permutation): differences
    of A are measured as D^-1 (A1 - A2) D, whatever the units of the states."""
    from scipy.linalg import get_lapack_funcs

    if not A.size or not np.all(np.isfinite(A)):
        return np.ones(A.shape[0])
    return get_lapack_funcs("gebal", (A,))(A, scale=1, permute=0)[3]


def _difference(A1, A2, r1, r2, b) -> float:
    """How far (A1, r1) and (A2, r2) are apart, relative: the matrices in A's balanced
    units (``_balanced``: Frobenius norms), the rates row by row beyond ``b`` (their
    rounding); infinite where one is not finite."""
    if not (np.all(np.isfinite(A1)) and np.all(np.isfinite(A2))
            and np.all(np.isfinite(r1)) and np.all(np.isfinite(r2))):
        return np.inf
    D = _balanced((A1 + A2) / 2)
    dA = np.linalg.norm((A1 - A2) * D[None, :] / D[:, None])
    size = np.linalg.norm((A1 + A2) * D[None, :] / D[:, None]) / 2
    with np.errstate(divide="ignore", invalid="ignore"):
        dr = np.where(np.abs(r1 - r2) <= b, 0.0,
                      np.abs(r1 - r2) / (np.abs(r1) + np.abs(r2)))
    return float(max(dA / size if size > 0 else (0.0 if dA == 0 else np.inf),
                     dr.max(initial=0.0)))


def _settled(model, ck, y, p, values, t, rows, E):
    """``_jacobian``'s work (under its error state).  At a 0/0 the limit is taken along
    ``DIRECTIONS`` random kept directions by symmetric differences and Richardson
    extrapolation, at the largest step where the differences from h and h/2 agree to
    1e-3 (in A's balanced units).  Each kept state is stepped by its own scale
    (``_scales``): ``STEPS`` times its size, or ``SWEEP`` at 0; where that settles
    nowhere, every state on ``SWEEP`` (a 0/0 away from the origin, whose scale is no
    state's size); never a state the kept rows do not depend on.  A step where a
    row that is 0/0 at the point has lost its digits to cancellation (below ``DIGITS``
    of its terms) is refused: values that agree there are zeros, no limit.  The limit is
    accepted only when every direction gives the same one at that step (a value that
    depends on the direction of approach, as at the pole of polar coordinates or Euler
    angles, is none)."""
    m = len(y)
    Jm, f = np.empty((m, m)), np.empty(m)

    def at(z):
        ck.jac(t, z, p, Jm)
        ck.rhs(t, z, p, f)
        return Jm[rows] @ E, f[rows].copy(), ROUNDING * (np.abs(Jm[rows]) @ np.abs(z))

    def bound(z, rounding, rates=None):     # each part only where the others do not do
        b = rounding
        for part in (lambda: _inputs(ck, t, z, p, rows),
                     lambda: model.sizes_at(rows, z, values, t)):
            if rates is not None and np.all(np.abs(rates) <= b):
                break
            more = part()
            b = b + ROUNDING * np.where(np.isfinite(more), more, 0.0)
        return b

    A, rates, rounding = at(y)
    if np.all(np.isfinite(A)) and np.all(np.isfinite(rates)):
        return A, rates, False, bound(y, rounding, rates)
    over = model.overflow(rows, y, values, t, LARGE)
    if over is not None:
        in_t = model.system.J.t in model.growth(rows, y, values, t)[1].free_symbols
        raise LinearizationError(
            f"the equations overflow at this point (t = {t:g}): {over}, which (or its "
            "products in the equations) is beyond double precision; "
            + ("factors that cancel on paper, such as exp(g t) exp(-g t) of a "
               "Lagrangian e^(g t) L0 whose other terms depend on t too, do not cancel in "
               "the compiled equations: linearize at a t of smaller |argument|, in a unit "
               "of time or with parameter values that keep it well below "
               f"{OVERFLOW:.6g}, or with the factor cancelled in the equations (e^(g t) "
               "L0 is L0 with the forces -g dL0/dq_t)" if in_t else
               "linearize at states or parameter values that keep the argument well "
               f"below {OVERFLOW:.6g}, or in other units or coordinates"))
    undefined = ~np.isfinite(A)
    singular = [c for c in range(len(rows))
                if undefined[c].any() or not np.isfinite(rates[c])]
    sized, free = _scales(model, y, rows, E)
    rng = np.random.default_rng(0)
    dirs = []
    for _ in range(DIRECTIONS):
        r = rng.standard_normal(E.shape[1])
        dirs.append(r / np.linalg.norm(r))
    scales = [(sized, free)]
    if sized.any():                         # then every state it steps on the sweep
        scales.append((0 * sized, np.sign(sized + free)))

    def step(d, h):                         # the step along d: states on their scales
        return E @ (d * (h[0] * scales[0][0] + h[1] * scales[0][1]))

    def kept(z):                            # the largest fraction of its terms a 0/0 row keeps
        _, r, _ = at(z)
        terms = model.sizes_at([rows[c] for c in singular], z, values, t)
        with np.errstate(divide="ignore", invalid="ignore"):
            return np.where(terms > 0, np.abs(r[singular]) / terms, np.inf)

    def mean(d, h):
        z1, z2 = y + step(d, h), y - step(d, h)
        (A1, r1, b1), (A2, r2, b2) = at(z1), at(z2)
        terms = DIGITS * np.maximum(model.sizes_at(rows, z1, values, t),
                                    model.sizes_at(rows, z2, values, t))
        return (A1 + A2) / 2, (r1 + r2) / 2, np.maximum(np.maximum(b1, b2), terms)

    def limit(d, h):
        half = (h[0] / 2, h[1] / 2)
        (A1, r1, _), (A2, r2, b2) = mean(d, h), mean(d, half)
        return (4 * A2 - A1) / 3, (4 * r2 - r1) / 3, b2, max(
            _difference(A1, A2, r1, r2, b2), _entries(A1, A2, undefined))

    best, h_best, lost = None, None, False
    while best is None and scales:
        steps = ([(min(h, STEPS[0]), h) for h in SWEEP] if scales[0][1].any()
                 else [(h, 0.0) for h in STEPS])
        for h in steps:
            found = [limit(d, h) for d in dirs]
            if max(f[3] for f in found) <= 1e-3:
                digits = np.max([kept(y + s * step(d, (h[0] / 2, h[1] / 2)))
                                 for d in dirs for s in (1, -1)], axis=0)
                if np.all(digits > DIGITS):
                    best, h_best = found, h
                else:
                    lost = True
                break
        if best is None:
            scales.pop(0)
    if best is None:
        raise LinearizationError(
            "the equations are undefined at this point (0/0: a singular point of the "
            "coordinates, where the mass matrix of the reduced equations is singular, as "
            "at the pole of polar coordinates or of Euler angles; a singular configuration "
            "of the principle's equations or of the split; or parameter values that make "
            "them degenerate, e.g. a mass of 0; or values beyond double precision, such as "
            "exp(g t) at large g t), and no limit could be established there "
            + ("(the steps where the values settle lose every digit of the 0/0 rows to "
               "cancellation) " if lost else "")
            + "with steps of each state's size times "
            f"{STEPS[0]:g}..{STEPS[-1]:g}, then of {SWEEP[0]:g}..{SWEEP[-1]:g} in its "
            "own units; "
            "linearize in other coordinates, or choose another operating point, another "
            "split (dependent=) or other parameter values")
    A, rates, b, _ = best[0]
    for A2, r2, b2, _ in best[1:]:
        if _difference(A, A2, rates, r2, np.maximum(b, b2)) > 1e-3:
            raise LinearizationError(
                "the equations are undefined at this point (0/0) and their limit depends "
                "on the direction of approach: a singular point of the coordinates (the "
                "mass matrix of the reduced equations is singular there, as at the pole "
                "of polar coordinates or of Euler angles), where A does not describe the "
                "motions nearby; linearize in other coordinates (Cartesian ones, or "
                "angles whose pole is elsewhere), or at a point off the singularity")
    z = y + step(dirs[0], (h_best[0] / 2, h_best[1] / 2))
    return A, rates, True, np.maximum(b, bound(z, at(z)[2]))


def _inputs(ck, t: float, y, p, rows) -> np.ndarray:
    """sum_k |dx'_i/dp_k| |p_k| + |dx'_i/dt| |t| of each row ``i`` of ``rows`` at state
    ``y``: the rounding of the parameters and of t through the rates, by central
    differences (relative step ``NUDGE``: the error, NUDGE^2 of the value and
    eps/NUDGE of the terms, is far below what the steady test needs of it); a value of
    the rows and their derivatives, not of their form (a term is 0 where its own
    difference is undefined: the others keep their share)."""
    m = len(y)
    f1, f2, out = np.empty(m), np.empty(m), np.zeros(len(rows))

    def add():
        with np.errstate(invalid="ignore", over="ignore"):
            d = np.abs(f1[rows] - f2[rows]) / (2 * NUDGE)
        out[:] += np.where(np.isfinite(d), d, 0.0)

    for k in np.flatnonzero(p):
        q = p.copy()
        q[k] = p[k] * (1 + NUDGE)
        ck.rhs(t, y, q, f1)
        q[k] = p[k] * (1 - NUDGE)
        ck.rhs(t, y, q, f2)
        add()
    if t != 0.0:
        ck.rhs(t * (1 + NUDGE), y, p, f1)
        ck.rhs(t * (1 - NUDGE), y, p, f2)
        add()
    return out


def _entries(A1, A2, where) -> float:
    """How far the entries ``where`` (a mask) of A1 and A2 are apart, each relative to
    its own size (in A's balanced units; a difference within eps of A counts as none):
    an entry that is 0/0 at the point is not judged against the sizes of the others."""
    if not (np.all(np.isfinite(A1)) and np.all(np.isfinite(A2))):
        return np.inf
    D = _balanced((A1 + A2) / 2)
    B1, B2 = A1 * D[None, :] / D[:, None], A2 * D[None, :] / D[:, None]
    floor = EPS * np.linalg.norm(B1 + B2) / 2
    d, size = np.abs(B1 - B2)[where], (np.abs(B1) + np.abs(B2))[where] / 2
    return float(np.max(np.where(d <= floor, 0.0, d / np.maximum(size, floor)),
                        initial=0.0))


def _scales(model, y, rows, E):
    """``(sized, free)`` over the kept states (E's columns): ``|y|`` of a nonzero state
    the kept rows depend on (relative steps); ``free`` 1 for one at 0 (absolute steps,
    swept: no other state's value is its scale); 0 in both for a state no kept row
    depends on, itself or through the coordinates that follow it on g = 0 (never
    stepped)."""
    sized, free = np.zeros(len(rows)), np.zeros(len(rows))
    for c, j in enumerate(rows):
        if any(model.uses(i, k) for k in np.flatnonzero(E[:, c]) for i in rows):
            sized[c], free[c] = abs(y[j]), float(y[j] == 0)
    return sized, free
