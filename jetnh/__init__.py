"""jetnh: nonholonomic constrained mechanics on jet bundles.

The public contract (DESIGN.md section 4): ``JetSpace``, ``System``, ``System.equations``,
``Equations.accelerations``, ``Scene`` and its ``Trajectory``; ``compare`` decides when two
principles share solutions.
"""

from .constraints import PRINCIPLES, System
from .equations import Equations
from .equivalence import compare
from .errors import (ConstraintError, IntegrationError, JetnhError, JetSpaceError,
                     LagrangianError, ModelFileError, PrincipleError)
from .jet import JetSpace

__version__ = "0.1.0"

__all__ = ["JetSpace", "System", "Equations", "PRINCIPLES", "compare", "Scene", "Trajectory",
           "Diagnostics", "Event", "Ensemble", "JetnhError",
           "JetSpaceError", "ConstraintError", "LagrangianError", "PrincipleError",
           "ModelFileError", "IntegrationError"]


def __getattr__(name):
    """The numeric names load numba and scipy: import them on first use."""
    if name in ("Scene", "Trajectory", "Diagnostics", "Event", "Ensemble"):
        from . import numeric

        return getattr(numeric, name)
    raise AttributeError(f"module 'jetnh' has no attribute {name!r}")
