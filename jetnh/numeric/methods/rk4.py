"""The classical fourth-order Runge-Kutta method with a fixed step.

- Order 4; four right-hand-side evaluations per step; no error estimate.
- ``n_steps`` equal steps of ``h = (t_end - t0) / n_steps``.
- Dense output: the cubic Hermite interpolant of the step (one extra evaluation, only in
  a step where an event or a singularity indicator needs it).

Reference: W. Kutta, "Beitrag zur naeherungsweisen Integration totaler
Differentialgleichungen", Z. Math. Phys. 46 (1901) 435-453; E. Hairer, S. P. Norsett,
G. Wanner, *Solving Ordinary Differential Equations I*, section II.1.

The method is the value ``RK4``; the shared loop ``loop.solve`` runs it.
"""

import numpy as np

from .loop import HERMITE, NONE, ExplicitRK

RK4 = ExplicitRK(
    "rk4", order=4, error_order=4,
    C=np.array([0.0, 0.5, 0.5, 1.0]),
    A=np.array([[0.0, 0.0, 0.0, 0.0], [0.5, 0.0, 0.0, 0.0], [0.0, 0.5, 0.0, 0.0],
                [0.0, 0.0, 1.0, 0.0]]),
    B=np.array([1.0, 2.0, 2.0, 1.0]), b_den=6.0, error=NONE, dense=HERMITE,
    D=np.zeros((0, 4)))
