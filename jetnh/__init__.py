"""jetnh: nonholonomic constrained mechanics on jet bundles."""

from .errors import (ConstraintError, IntegrationError, JetnhError, JetSpaceError,
                     LagrangianError, ModelFileError, PrincipleError)
from .jet import JetSpace

__version__ = "0.1.0"
