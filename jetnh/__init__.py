"""jetnh: nonholonomic constrained mechanics on jet bundles.

The public contract: ``JetSpace``, ``System``, ``System.equations``,
``Equations.accelerations``, ``Scene`` and its ``Trajectory``; ``PRINCIPLES`` names the
four principles (``Principle`` values and aliases: ``jetnh.mechanics.principles``); ``compare``
decides when two principles share solutions; ``sweep`` runs a scene over a grid of
parameters and initial values (here or on Dask); ``from_mechanics`` reads a
sympy.physics.mechanics ``LagrangesMethod``; ``conserved_quantities``,
``noether_symmetries``, ``lie_symmetries`` and ``is_noether`` find and prove first
integrals and symmetries under each principle; ``linearize`` gives the linearization
about an operating point (a ``Linearization``: A, eigenvalues, stability) under each.
"""

from .mechanics.system import System
from .mechanics.equations import Equations
from .mechanics.equivalence import compare
from .errors import (ArgumentError, ConnectError, ConstraintError, IntegrationError,
                     JetnhError, JetnhWarning, JetSpaceError, LagrangianError,
                     LinearizationError, ModelFileError, PrincipleError)
from .mechanics.integrals import conserved_quantities
from .geometry.jet import JetSpace
from .mechanics.sympy_bridge import from_mechanics
from .mechanics.principles import PRINCIPLES, Principle
from .mechanics.symmetries import LieSymmetry, NoetherSymmetry, is_noether, lie_symmetries, noether_symmetries
# jetnh.sweep is the module, and calling it runs a sweep (jetnh/sweep.py: a callable
# module); it is light (pandas, Dask and numba are imported when it runs)
from . import sweep

__version__ = "0.1.0"

__all__ = ["JetSpace", "System", "Equations", "PRINCIPLES", "Principle", "compare", "conserved_quantities",
           "noether_symmetries", "lie_symmetries", "is_noether", "NoetherSymmetry",
           "LieSymmetry", "Scene", "Trajectory", "linearize", "Linearization", "connect",
           "Connection", "ConnectError",
           "Diagnostics", "Event", "Ensemble", "sweep", "from_mechanics", "JetnhError",
           "JetSpaceError", "ConstraintError", "LagrangianError", "PrincipleError",
           "ModelFileError", "IntegrationError", "ArgumentError", "JetnhWarning",
           "LinearizationError"]


def __getattr__(name):
    """The numeric names load numba and scipy: import them on first use."""
    if name in ("Scene", "Trajectory", "Diagnostics", "Event", "Ensemble"):
        from . import numeric

        return getattr(numeric, name)
    if name in ("linearize", "Linearization"):
        from .numeric import linearize

        return getattr(linearize, name)
    if name in ("connect", "Connection"):
        from .numeric import connect as module

        return getattr(module, name)
    raise AttributeError(f"module 'jetnh' has no attribute {name!r}")
