"""Numerical simulation: compiled scenes, integrators, events, ensembles, trajectories.

``Scene(system, principle, params, initial, t_span).run(...)`` derives the equations of
one principle, generates numba kernels through ``sympy.cse`` (``codegen``), caches them
on disk keyed by the symbolic input (``kernels``), and integrates in compiled loops
(``methods``: dop853, dopri5, rk4, radau, dla, dvi) or with scipy's ``solve_ivp``.

- Singular configurations (``codegen.singular_indicators``): every run stops where the
  dependent velocities cannot be solved for or the accelerations are undefined
  (det df/dqdot^alpha, denominators and square-root arguments of phi and of the
  accelerations crossing zero or falling below ``singular_tol`` of their initial size),
  located on the dense output, with ``status`` SINGULAR and a ``stop_reason`` that names
  the indicator, the time and the way out; dla and dvi check the indicators of the
  constraints and the Lagrangian as written at their nodes.
- Charts (``atlas``): the singular set of the split is no stop for dop853, dopri5, rk4
  and radau: at the edge of the split's chart the run goes on in another regular split,
  with the state mapped, and is reported as one trajectory with ``traj.switches``.
- Precision (``precision``): 50-digit mpmath values of kernel expressions with a rounding
  error bound, against which ``benchmarks/stress_mpmath.py`` checks the compiled kernels.
- User events (``events``): ``run(events=[expr, callable, Event(...)])`` with scipy's
  semantics (terminal, direction), roots on the dense output inside the compiled loop.
- Ensembles (``ensemble``): ``scene.ensemble(initial=arrays, params=arrays, ...)`` runs
  the same compiled loop for every row, on all cores, bit-for-bit the single runs.
- Run options (``options``): ``StepControl``, ``Singular``, ``Newton`` values, or the
  keywords they stand for.
"""

from .ensemble import Ensemble, run_ensemble
from .events import Event
from .methods._common import EVENT, FINISHED, MAX_STEPS, NONFINITE, NOT_CONVERGED, SINGULAR, STATUS_TEXT, STIFF, STOPPED, TOO_SMALL_STEP, Status
from .options import Newton, Singular, StepControl
from .scene import Scene
from .trajectory import Diagnostics, Trajectory

__all__ = ["Scene", "Trajectory", "Diagnostics", "Event", "Ensemble", "run_ensemble",
           "Status", "STATUS_TEXT", "FINISHED", "MAX_STEPS", "TOO_SMALL_STEP", "NONFINITE",
           "NOT_CONVERGED", "EVENT", "SINGULAR", "STOPPED", "STIFF", "StepControl",
           "Singular", "Newton"]
