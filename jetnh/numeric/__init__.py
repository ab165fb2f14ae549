"""Numerical simulation: compiled scenes, integrators and trajectories.

``Scene(system, principle, params, initial, t_span).run(...)`` derives the equations of
one principle, generates numba kernels through ``sympy.cse`` (``codegen``), caches them
on disk keyed by the symbolic input (``cache``), and integrates in compiled loops
(``integrators``: dop853, dopri5, rk4) or with scipy's ``solve_ivp``.
"""

from .scene import Scene
from .trajectory import Diagnostics, Trajectory

__all__ = ["Scene", "Trajectory", "Diagnostics"]
