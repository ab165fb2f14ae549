"""Dormand-Prince 5(4): explicit Runge-Kutta, order 5, embedded order-4 error estimate.

- Order 5 (local extrapolation), FSAL: six right-hand-side evaluations per step.
- Error estimate: the difference to the embedded 4th-order solution, measured in the
  RMS norm scaled by ``atol + rtol * max(|y_n|, |y_n+1|)``.
- Step control: ``h_new = h * min(10, max(0.2, 0.9 * err^(-1/5)))``, no increase right
  after a rejection; starting step by the heuristic of Hairer-Norsett-Wanner II.4.
  This is the controller of scipy's ``RK45``, so both take the same steps.
- Dense output: Hairer's 4th-order continuous extension (``contd5`` of DOPRI5), free
  (no extra evaluation); used for ``t_eval``, events and singularity stops (``_events``).
- Stiffness: Hairer's test (``loop``): h |lambda| estimated from the 6th stage and
  f(t + h, y_new) every 1000th step (every step after a positive test); beyond 3.25
  in 15 tests in a row, the run stops with status ``STIFF``: its steps are limited
  by stability, not accuracy (a stiff problem, or a motion running into a singular
  set of its equations); radau solves stiff problems.  The test changes no
  accepted step.

References: J. R. Dormand, P. J. Prince, "A family of embedded Runge-Kutta formulae",
J. Comput. Appl. Math. 6 (1980) 19-26; E. Hairer, S. P. Norsett, G. Wanner, *Solving
Ordinary Differential Equations I*, 2nd ed., Springer 1993, sections II.4-II.6.

The method is the value ``DOPRI5``; the shared loop ``loop.solve`` runs it.
"""

import numpy as np

from .loop import EMBEDDED, HERMITE, ExplicitRK

C = np.array([0.0, 1 / 5, 3 / 10, 4 / 5, 8 / 9, 1.0])
A = np.array([
    [0.0, 0.0, 0.0, 0.0, 0.0],
    [1 / 5, 0.0, 0.0, 0.0, 0.0],
    [3 / 40, 9 / 40, 0.0, 0.0, 0.0],
    [44 / 45, -56 / 15, 32 / 9, 0.0, 0.0],
    [19372 / 6561, -25360 / 2187, 64448 / 6561, -212 / 729, 0.0],
    [9017 / 3168, -355 / 33, 46732 / 5247, 49 / 176, -5103 / 18656],
])
B = np.array([35 / 384, 0.0, 500 / 1113, 125 / 192, -2187 / 6784, 11 / 84])
# y5 - y4, over the 7 stages (the 7th is f(t + h, y_new))
E = np.array([71 / 57600, 0.0, -71 / 16695, 71 / 1920, -17253 / 339200, 22 / 525, -1 / 40])
# Hairer's contd5 coefficients
DENSE = np.array([-12715105075 / 11282082432, 0.0, 87487479700 / 32700410799,
                  -10690763975 / 1880347072, 701980252875 / 199316789632,
                  -1453857185 / 822651844, 69997945 / 29380423])

DOPRI5 = ExplicitRK("dopri5", order=5, error_order=4, C=C, A=A, B=B, error=EMBEDDED,
                    dense=HERMITE, E=E, D=DENSE[None, :], stiff_bound=3.25)
