"""Compiled integrators.  One module per method; each ``solver()`` returns a numba
``solve(rhs, ...)`` whose right-hand side is a first-class function (a cfunc of the
scene's generated kernels), so the whole loop runs as machine code, is compiled once for
all scenes and is cached on disk by numba.

=========  ======  ================================  ==========================================
method     order   error estimate / step control     reference
=========  ======  ================================  ==========================================
dopri5     5(4)    embedded 4th order                 Dormand & Prince (1980); HNW I, II.4-5
dop853     8(5,3)  5th and 3rd order combination     Hairer's DOP853; HNW I, II.5 and II.10
rk4        4       none (fixed step)                  Kutta (1901); HNW I, II.1
dla        2       none (fixed step), symmetric       Cortes & Martinez (2001); McLachlan &
                                                      Perlmutter (2006); optional projection
dvi        2       none (fixed step), symmetric,     Benito & Martin de Diego (2005); Colombo
                   variational (vakonomic)           et al. (2010, 2013); Marsden & West (2001)
=========  ======  ================================  ==========================================

The Runge-Kutta methods also take the singularity indicators and the user events of the
scene as first-class functions and locate them on their dense output (``_events``); dla
and dvi check the indicators of the constraints and the Lagrangian at their nodes;
``ensemble_solver()`` of dop853, dopri5 and rk4 is a compiled driver running the same
``solve`` over the rows of an array of initial states and parameters.
"""

from ._common import STATUS_TEXT  # noqa: F401

METHODS = {
    "dopri5": "dopri5", "rk45": "dopri5", "dp5": "dopri5",
    "dop853": "dop853",
    "rk4": "rk4",
}
ADAPTIVE = ("dopri5", "dop853")
