"""Compiled integrators.  An explicit Runge-Kutta method is a small value (``ExplicitRK``:
tableau, order, error estimator, dense output; one short module each) run by the one
compiled loop of ``loop``; radau has its own loop over the same helpers (``_common``,
``_events``); dla and dvi are discrete variational steps sharing one Newton solver
(``newton``).  Every right-hand side is a C callback of the scene's generated kernels,
passed by its address (``_common.function_at``), so each loop runs as machine code, is
compiled once for all scenes
and is kept on disk in jetnh's signed store (``kernels.loop_cache``; ``jetnh cache warm``
compiles the common ones ahead, ``numeric.precompile``).

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
as callbacks at their addresses and locate them on their dense output (``_events``); dla and dvi
check the indicators of the constraints and the Lagrangian and the user events at their
nodes (a terminal event ends the run at the node after it).

``METHODS`` is the one table of the methods, as ``Method`` values (with scipy's
``solve_ivp`` methods as ``scipy-<M>``); ``method(name)`` reads a name or an alias.  Every
question about a method (is it adaptive, has it dense output, does it run as an
ensemble, how is it solved) is asked of its ``Method``, never of its name.
"""

from __future__ import annotations

import enum
from dataclasses import dataclass

from ...errors import JetnhError
from ._common import STATUS_TEXT, Status, entry_point  # noqa: F401
from .dop853 import DOP853
from .dopri5 import DOPRI5
from .loop import ExplicitRK
from .rk4 import RK4


class Solver(enum.Enum):
    """How a method is solved."""

    EXPLICIT = "the compiled explicit Runge-Kutta loop (loop.py)"
    IMPLICIT = "the compiled Radau IIA loop with simplified Newton (radau.py)"
    DISCRETE = "a discrete variational step solved by Newton (dla.py, dvi.py)"
    SCIPY = "scipy's solve_ivp on the compiled right-hand side"


@dataclass(frozen=True)
class Method:
    """An integration method: its ``name`` (as trajectories report it), ``aliases``,
    ``order`` (None: variable), whether it controls its step (``adaptive``; else
    ``fixed_step``: ``n_steps`` or ``h``), has ``dense`` output (``t_eval``), runs as a
    compiled batched ``ensemble``, takes ``newton`` options and dla's ``projection``, and
    how it is solved (``solver``; ``tableau`` of an explicit method, ``scipy`` the name of
    solve_ivp's method)."""

    name: str
    solver: Solver
    order: int | None
    adaptive: bool
    dense: bool
    ensemble: bool
    aliases: tuple = ()
    newton: bool = False
    projection: bool = False
    tableau: ExplicitRK | None = None
    scipy: str = ""

    @property
    def fixed_step(self) -> bool:
        return not self.adaptive


def _explicit(rk: ExplicitRK, aliases=()) -> Method:
    return Method(rk.name, Solver.EXPLICIT, rk.order, rk.adaptive, dense=rk.adaptive,
                  ensemble=True, aliases=aliases, tableau=rk)


def _scipy(name: str, order, aliases=()) -> Method:
    return Method(f"scipy-{name}", Solver.SCIPY, order, adaptive=True, dense=True,
                  ensemble=False, aliases=aliases, scipy=name)


#: every method, by name (radau's Newton options: ``radau.newton_options``; dla's and
#: dvi's: ``Scene.run``)
METHODS = {m.name: m for m in (
    _explicit(DOP853),
    _explicit(DOPRI5, aliases=("rk45", "dp5")),
    _explicit(RK4),
    Method("radau", Solver.IMPLICIT, 5, adaptive=True, dense=True, ensemble=True,
           aliases=("radau5",), newton=True),
    Method("dla", Solver.DISCRETE, 2, adaptive=False, dense=False, ensemble=False,
           aliases=("lda", "nh-midpoint"), newton=True, projection=True),
    Method("dvi", Solver.DISCRETE, 2, adaptive=False, dense=False, ensemble=False,
           aliases=("vakonomic-midpoint",), newton=True),
    _scipy("RK45", 5, aliases=("scipy-dopri5",)),
    _scipy("RK23", 3),
    _scipy("DOP853", 8),
    _scipy("Radau", 5),
    _scipy("BDF", None),
    _scipy("LSODA", None))}
#: the methods of scipy's solve_ivp (``method="scipy-<name>"``)
SCIPY_METHODS = tuple(m.scipy for m in METHODS.values() if m.solver is Solver.SCIPY)
_BY_NAME = {n.lower(): m for m in METHODS.values() for n in (m.name, *m.aliases)}


def method(name, backend=None) -> Method:
    """The method called ``name`` (case-insensitive, aliases accepted; a ``Method`` is
    returned as it is); ``backend="scipy"``: scipy's method of that name (``"DOP853"``,
    ``"dopri5"``: ``scipy-RK45``)."""
    if isinstance(name, Method):
        return name
    key = str(name).lower()
    if backend not in (None, "numba", "scipy"):
        raise JetnhError(f"unknown backend {backend!r}; choose 'numba' or 'scipy'")
    if backend == "scipy" and not key.startswith("scipy-"):
        key = "scipy-" + key
    found = _BY_NAME.get(key)
    if found is None and key.startswith("scipy"):
        raise JetnhError(f"unknown scipy method {str(name).split('-', 1)[-1]!r}; choose one "
                         f"of {SCIPY_METHODS}")
    if found is None:
        compiled = [m.name for m in METHODS.values() if m.solver is not Solver.SCIPY]
        raise JetnhError(f"unknown method {name!r}; choose one of {', '.join(compiled)} or "
                         f"scipy-<{'|'.join(SCIPY_METHODS)}>")
    return found


def explicit_solver(m, parts):
    """The compiled loop of the explicit method ``m`` (a ``Method`` or its name) with the
    ``parts`` a run needs (``loop.features``; each compiled on first use), called as
    ``solve(rhs_at, sing_at, uev_at, hol_at, t0, t_end, y0, p, ctl, t_eval, mode, watch,
    halt)`` (the callbacks' addresses; ``loop.solver``): its machine-code entry point (no
    type dispatch per call: ``_common.entry_point``), which a plan keeps."""
    m = method(m)
    key = (m.name, tuple(parts))
    if key not in _ENTRIES:
        from .loop import solver

        _ENTRIES[key] = entry_point(solver(m.tableau, key[1]))
    return _ENTRIES[key]


def implicit_solver(parts):
    """The compiled loop of radau with the ``parts`` a run needs, called as ``solve(rhs,
    jac, sing, uev, hol, t0, t_end, y0, p, ctl, newton, t_eval, mode, watch, halt)``
    (``radau.solver``): its entry point, as ``explicit_solver``."""
    key = ("radau", tuple(parts)[:3])         # (every radau loop stores each step)
    if key not in _ENTRIES:
        from . import radau

        _ENTRIES[key] = entry_point(radau.solver(key[1]))
    return _ENTRIES[key]


_ENTRIES: dict = {}
