"""Runs whose method does not project onto the holonomic constraints g(t, q) = 0 say how
far their rows left them.

jetnh's own loops (dop853, dopri5, rk4, radau) and scipy's one-step methods (RK23, RK45,
DOP853, Radau) move every step onto g = 0 (``methods.projection``), so ``|g|`` stays at
rounding level over any number of steps.  Three kinds of run do not, by design:

- dla and dvi keep g = 0 through their discrete constraint only, D g imposed at each
  step's midpoint, G((q_k + q_k+1)/2) (q_k+1 - q_k) = 0: exact where g is quadratic in
  q (a Cartesian pendulum), else g changes by O(h^3) a step, and ``|g|`` wanders by O(h^2)
  over a run.  Projecting the nodes orthogonally would break what these integrators are
  chosen for: dla's symmetry (time reversibility, the source of its bounded energy
  error) and dvi's variational, symplectic structure (Hairer, Lubich & Wanner,
  *Geometric Numerical Integration* (2006), IV.4 and V.4: the standard projection is
  neither symmetric nor symplectic).  dla's ``projection=True``, which gives up the
  symmetry for its velocity projection already, moves its nodes onto g = 0 too.
- scipy's BDF and LSODA are multistep methods: a projected value would contradict the
  history they carry (BDF's differences, LSODA's Nordsieck array), so their ``|g|`` grows
  with the global error.

After such a run ``report`` measures max ``|g_i|`` over its rows (the trajectory's
``holonomic_residual``, also ``diagnostics.holonomic_residual_max``) and, where it
exceeds ``DRIFT`` max(1, ``max |q|``) (rounding, not drift, lies below), warns with a
``JetnhWarning`` that names the figure, the time, why the method does not project and
what does.
"""

from __future__ import annotations

import warnings

import numpy as np

from ..errors import JetnhWarning

#: |g| / max(1, max |q|) above which a run that does not project reports its drift: a
#: thousand units of rounding (a projected run stays within a few)
DRIFT = 1e3 * float(np.finfo(float).eps)


def report(traj, why: str) -> float:
    """max |g_i| over the rows of ``traj`` (a run whose steps were not projected onto g
    = 0, ``why`` says so), with a ``JetnhWarning`` where it exceeds ``DRIFT`` relative
    to max(1, max |q|); 0 without holonomic constraints."""
    g = np.abs(traj.holonomic_residual)
    if not g.size:
        return 0.0
    worst = float(np.max(g))
    n = traj.scene.system.J.n
    scale = max(1.0, float(np.max(np.abs(traj.y[:, :n]))))
    if not worst <= DRIFT * scale:         # (NaN too)
        i = int(np.argmax(np.max(g, axis=1)))
        warnings.warn(
            f"{traj.method}: the run left the holonomic constraints g = 0 by up to |g| = "
            f"{worst:.3g} (at t = {float(traj.t[i]):.6g}; diagnostics."
            f"holonomic_residual_max): {why}.  For g = 0 to rounding use a method that "
            "projects every step: dop853, dopri5, rk4, radau, or scipy-RK45, scipy-RK23, "
            "scipy-DOP853, scipy-Radau", JetnhWarning, stacklevel=4)
    return worst
