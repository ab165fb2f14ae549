"""The exceptions jetnh raises: one base class, one subclass per kind of mistake.

Every message says what is wrong and how to fix it.
"""


class JetnhError(Exception):
    """Base class of every error jetnh raises on purpose.

    ``argument``: the name of the argument the error refuses, or None.  With one, the
    message is the argument's name and then ``detail``, the rest (``"rtol must be
    positive"``: ``argument`` "rtol", ``detail`` "must be positive"); ``named(name)`` is
    the message with another name for it (the command line's ``--rtol``).
    """

    def __init__(self, message: str = "", *, argument: str | None = None):
        self.argument, self.detail = argument, message
        super().__init__(self.named(argument))

    def named(self, name: str | None) -> str:
        """The message with ``name`` for the refused argument."""
        return f"{name} {self.detail}" if self.argument is not None else self.detail


class JetSpaceError(JetnhError, ValueError):
    """Bad coordinates, or an expression that does not live on the jet space."""


class ConstraintError(JetnhError, ValueError):
    """Constraints that are dependent, unsolvable for the split, or inconsistent."""


class LagrangianError(JetnhError, ValueError):
    """A Lagrangian that is singular where a principle needs it regular."""


class PrincipleError(JetnhError, ValueError):
    """An unknown principle, or a request a principle cannot answer."""


class ModelFileError(JetnhError, ValueError):
    """A model file that cannot be read as data."""


class ArgumentError(JetnhError, ValueError):
    """A run argument (state, parameter, tolerance, step, budget) that is refused before
    it reaches compiled code."""


class IntegrationError(JetnhError, RuntimeError):
    """A numerical integration that cannot go on.  ``stop``: where the run stopped and
    what it had done by then, where known (a dict with ``t``, ``steps``, ``rejected``,
    ``rhs_evaluations``; a count None when the method does not keep it), else None."""

    def __init__(self, message: str = "", *, argument: str | None = None, stop=None):
        super().__init__(message, argument=argument)
        self.stop = stop


class ConnectError(JetnhError, RuntimeError):
    """``connect`` found no motion joining two configurations; ``best`` is the closest
    ``Connection`` it reached (or None), with its residual."""

    def __init__(self, message, best=None):
        super().__init__(message)
        self.best = best


class FrozenError(JetnhError, AttributeError):
    """An assignment to an immutable object (a Scene, a Trajectory)."""


class JetnhWarning(UserWarning):
    """Input jetnh accepts but that is probably not what was meant (e.g. a parameter
    named like a velocity, which is a constant, not the velocity)."""


class KernelCacheWarning(JetnhWarning):
    """The kernel cache cannot be used as configured; kernels go to a temporary cache."""


class LinearizationError(JetnhError, ValueError):
    """A linearization that cannot be made: equations undefined at the operating point
    with no limit there, or no steady motion where one was asked for."""
