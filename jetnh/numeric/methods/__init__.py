"""Compiled integrators.  An explicit Runge-Kutta method is a small value (``ExplicitRK``:
tableau, order, error estimator, dense output; one short module each) run by the one
compiled loop of ``loop``; radau has its own loop over the same helpers (``_common``,
``_events``); dla and dvi are discrete variational steps sharing one Newton solver
(``newton``).  Every right-hand side is a first-class function (a cfunc of the scene's
generated kernels), so each loop runs as machine code, is compiled once for all scenes
and is cached on disk by numba.

==========  ======  ================================  ==========================================
method      order   error estimate / step control     reference
==========  ======  ================================  ==========================================
dopri5      5(4)    embedded 4th order                Dormand & Prince (1980); HNW I, II.4-5
dop853      8(5,3)  5th and 3rd order combination     Hairer's DOP853; HNW I, II.5 and II.10
rk4         4       none (fixed step)                 Kutta (1901); HNW I, II.1
radau       5(3)    embedded 3rd order, predictive    Radau IIA, simplified Newton; Hairer &
                    (Gustafsson) controller           Wanner II, IV.8 (RADAU5)
dla         2       none (fixed step), symmetric      Cortes & Martinez (2001); McLachlan &
                                                      Perlmutter (2006); optional projection
dvi         2       none (fixed step), symmetric,     Benito & Martin de Diego (2005); Colombo
                    variational (vakonomic)           et al. (2010, 2013); Marsden & West (2001)
==========  ======  ================================  ==========================================

The Runge-Kutta methods take the singularity indicators and the user events of the scene
as first-class functions and locate them on their dense output (``_events``); dla and dvi
check the indicators of the constraints and the Lagrangian and the user events at their
nodes (a terminal event ends the run at the node after it).

``METHODS`` is the one table of method names (``method(name)`` reads a name or an alias).
"""

from ...errors import JetnhError
from ._common import STATUS_TEXT, Status, entry_point  # noqa: F401
from .dop853 import DOP853
from .dopri5 import DOPRI5
from .rk4 import RK4

#: the explicit Runge-Kutta methods, as values
EXPLICIT = {m.name: m for m in (DOP853, DOPRI5, RK4)}
#: every method of the compiled backend: name -> kind
METHODS = {"dop853": "explicit", "dopri5": "explicit", "rk4": "explicit",
           "radau": "implicit", "dla": "discrete", "dvi": "discrete"}
ALIASES = {"rk45": "dopri5", "dp5": "dopri5", "radau5": "radau", "lda": "dla",
           "nh-midpoint": "dla", "vakonomic-midpoint": "dvi"}
#: the methods of scipy's solve_ivp (``method="scipy-<name>"``)
SCIPY_METHODS = ("RK45", "RK23", "DOP853", "Radau", "BDF", "LSODA")


def method(name) -> str:
    """The method called ``name`` (case-insensitive, aliases accepted)."""
    key = str(name).lower()
    key = ALIASES.get(key, key)
    if key not in METHODS:
        raise JetnhError(f"unknown method {name!r}; choose one of {', '.join(METHODS)} or "
                         f"scipy-<{'|'.join(SCIPY_METHODS)}>")
    return key


def explicit_solver(name: str):
    """The compiled loop of the explicit method ``name`` as its machine-code entry point
    (``loop.solver``; no type dispatch per call: ``_common.entry_point``)."""
    if name not in _ENTRIES:
        from .loop import solver

        _ENTRIES[name] = entry_point(solver(EXPLICIT[name]))
    return _ENTRIES[name]


_ENTRIES: dict = {}


def adaptive(name: str) -> bool:
    """Whether the method ``name`` controls its step size (and has dense output)."""
    return name == "radau" or (name in EXPLICIT and EXPLICIT[name].adaptive)
