"""The Whipple bicycle as a sympy.physics.mechanics Kane model with all its coordinates.

Meijaard, Papadopoulos, Ruina and Schwab (2007), "Linearized dynamics equations for the
balance and steer of a bicycle: a benchmark and review", Proc. R. Soc. A 463, 1955-1982:
four rigid bodies (rear wheel, rear frame with rider, front fork with handlebar, front
wheel), knife-edge wheels rolling without slipping on a level ground, no forces but
gravity.  The geometry and the parameter names follow sympy's own benchmark test
(``sympy/physics/mechanics/tests/test_kane3.py``, ported from Autolev), which keeps only
yaw, roll, pitch and steer and sets the rear contact point at rest; here every
coordinate is kept, so that the kinematics hold for every motion::

    x, y   the rear contact point          q1  yaw        q2  roll
    q3     the rear wheel's rotation       q4  pitch      q5  steer
    q6     the front wheel's rotation

with speeds u_i = q_i' (ux, uy, u1..u6), rolling without slip at both contacts (four
nonholonomic constraints) and the front contact on the ground (the configuration
constraint, which fixes the pitch q4).  ``whipple_kane()`` returns the ``KanesMethod``
(Kane's equations formed); ``benchmark_parameters()`` the benchmark's values in these
parameters; ``DEPENDENT`` the split of the benchmark's linearization; ``upright(system,
speed, params)`` the state of upright straight running.
"""

from __future__ import annotations

import sympy as sp

#: the parameters, in the order of sympy's benchmark test
PARAMETER_NAMES = ("WFrad WRrad htangle forkoffset forklength framelength forkcg1 forkcg3 "
                   "framecg1 framecg3 Iwr11 Iwr22 Iwf11 Iwf22 Iframe11 Iframe22 Iframe33 "
                   "Iframe31 Ifork11 Ifork22 Ifork33 Ifork31 g mframe mfork mwf mwr").split()
#: the dependent coordinates of the benchmark's split (``from_mechanics(..., dependent=)``):
#: roll, rear wheel and steer rates independent
DEPENDENT = ("x", "y", "q1", "q4", "q6")


def whipple_kane():
    """The Whipple bicycle's ``KanesMethod`` (Kane's equations formed), see the module
    docstring.  Independent speeds: roll u2, rear wheel u3, steer u5."""
    from sympy.physics.mechanics import (KanesMethod, Point, ReferenceFrame, RigidBody,
                                         dynamicsymbols, inertia)

    (WFrad, WRrad, htangle, forkoffset, forklength, framelength, forkcg1, forkcg3,
     framecg1, framecg3, Iwr11, Iwr22, Iwf11, Iwf22, Iframe11, Iframe22, Iframe33,
     Iframe31, Ifork11, Ifork22, Ifork33, Ifork31, g, mframe, mfork, mwf,
     mwr) = sp.symbols(PARAMETER_NAMES)
    x, y, q1, q2, q3, q4, q5, q6 = dynamicsymbols("x y q1:7")
    ux, uy, u1, u2, u3, u4, u5, u6 = dynamicsymbols("u_x u_y u1:7")
    q = [x, y, q1, q2, q3, q4, q5, q6]
    u = [ux, uy, u1, u2, u3, u4, u5, u6]

    N = ReferenceFrame("N")
    Y = N.orientnew("Y", "Axis", [q1, N.z])                       # yaw
    R = Y.orientnew("R", "Axis", [q2, Y.x])                       # roll
    Frame = R.orientnew("Frame", "Axis", [q4 + htangle, R.y])     # pitch
    WR = Frame.orientnew("WR", "Axis", [q3, Frame.y])             # rear wheel
    TempFrame = Frame.orientnew("TempFrame", "Axis", [-htangle, Frame.y])
    Fork = Frame.orientnew("Fork", "Axis", [q5, Frame.x])         # steer
    TempFork = Fork.orientnew("TempFork", "Axis", [-htangle, Fork.y])
    WF = Fork.orientnew("WF", "Axis", [q6, Fork.y])               # front wheel

    O = Point("O")
    O.set_vel(N, 0)
    WR_cont = O.locatenew("WR_cont", x * N.x + y * N.y)
    WR_mc = WR_cont.locatenew("WR_mc", WRrad * R.z)
    Steer = WR_mc.locatenew("Steer", framelength * Frame.z)
    Frame_mc = WR_mc.locatenew("Frame_mc", -framecg1 * Frame.x + framecg3 * Frame.z)
    Fork_mc = Steer.locatenew("Fork_mc", -forkcg1 * Fork.x + forkcg3 * Fork.z)
    WF_mc = Steer.locatenew("WF_mc", forklength * Fork.x + forkoffset * Fork.z)
    WF_cont = WF_mc.locatenew("WF_cont", WFrad * (Fork.y.dot(Y.z) * Fork.y - Y.z).normalize())

    WR_cont.set_vel(N, x.diff() * N.x + y.diff() * N.y)
    WR_mc.v2pt_theory(WR_cont, N, R)
    Steer.v2pt_theory(WR_mc, N, Frame)
    Frame_mc.v2pt_theory(WR_mc, N, Frame)
    Fork_mc.v2pt_theory(Steer, N, Fork)
    WF_mc.v2pt_theory(Steer, N, Fork)

    # the wheels' material points at the contacts
    rear_slip = WR_mc.vel(N) + WR.ang_vel_in(N).cross(WR_cont.pos_from(WR_mc))
    front_slip = WF_mc.vel(N) + WF.ang_vel_in(N).cross(WF_cont.pos_from(WF_mc))
    height = WF_cont.pos_from(O).dot(N.z)

    bodies = [
        RigidBody("BodyFrame", Frame_mc, Frame, mframe,
                  (inertia(TempFrame, Iframe11, Iframe22, Iframe33, 0, 0, Iframe31), Frame_mc)),
        RigidBody("BodyFork", Fork_mc, Fork, mfork,
                  (inertia(TempFork, Ifork11, Ifork22, Ifork33, 0, 0, Ifork31), Fork_mc)),
        RigidBody("BodyWR", WR_mc, WR, mwr, (inertia(Frame, Iwr11, Iwr22, Iwr11), WR_mc)),
        RigidBody("BodyWF", WF_mc, WF, mwf, (inertia(Fork, Iwf11, Iwf22, Iwf11), WF_mc)),
    ]
    loads = [(b.masscenter, -b.mass * g * N.z) for b in bodies]
    km = KanesMethod(
        N, q_ind=[x, y, q1, q2, q3, q5, q6], u_ind=[u2, u3, u5],
        kd_eqs=[qi.diff() - ui for qi, ui in zip(q, u)],
        q_dependent=[q4], configuration_constraints=[height],
        u_dependent=[ux, uy, u1, u4, u6],
        velocity_constraints=[rear_slip.dot(Y.x), rear_slip.dot(Y.y), front_slip.dot(Y.x),
                              front_slip.dot(Y.y), height.diff(dynamicsymbols._t)],
        constraint_solver="CRAMER")
    km.kanes_equations(bodies, loads)
    return km


def benchmark_parameters() -> dict[str, float]:
    """The benchmark bicycle (Meijaard et al. 2007, Table 1) in the parameters of
    ``whipple_kane`` (the transformation of sympy's benchmark test), keyed by name."""
    from sympy import acos, cos, pi, sin, sqrt

    rad_rear, rad_front = 0.3, 0.35
    hta = pi / 2 - pi / 10
    trail, wheelbase = 0.08, 1.02
    frame_cg_x, frame_cg_z, fork_cg_x, fork_cg_z = 0.3, 0.9, 0.9, 0.7
    rake = -(trail * sin(hta) - rad_front * cos(hta))
    frame_length = wheelbase * sin(hta) - (rake - (rad_front - rad_rear) * cos(hta))
    frame_cg_norm = (frame_cg_z - rad_rear - (frame_cg_x / sin(hta)) * cos(hta)) * sin(hta)
    frame_cg_par = (frame_cg_x / sin(hta)
                    + (frame_cg_z - rad_rear - frame_cg_x / sin(hta) * cos(hta)) * cos(hta))
    ta, tb = fork_cg_z - rad_front, wheelbase - fork_cg_x
    tc = sqrt(ta**2 + tb**2)
    fork_length = wheelbase * cos(hta) - (rad_front - rad_rear) * sin(hta)
    fork_cg_norm = rake + tc * sin(pi / 2 - hta - acos(ta / tc))
    fork_cg_par = tc * cos((pi / 2 - hta) - acos(ta / tc)) - fork_length
    values = dict(WFrad=rad_front, WRrad=rad_rear, htangle=hta, forkoffset=rake,
                  forklength=fork_length, framelength=frame_length, forkcg1=fork_cg_par,
                  forkcg3=fork_cg_norm, framecg1=frame_cg_norm, framecg3=frame_cg_par,
                  Iwr11=0.0603, Iwr22=0.12, Iwf11=0.1405, Iwf22=0.28, Ifork11=0.05892,
                  Ifork22=0.06, Ifork33=0.00708, Ifork31=0.00756, Iframe11=9.2, Iframe22=11,
                  Iframe33=2.8, Iframe31=-2.4, mfork=4, mframe=85, mwf=3, mwr=2, g=9.81)
    return {k: float(sp.N(v, 30)) for k, v in values.items()}


def upright(system, speed: float, params: dict) -> dict[str, float]:
    """Upright straight running at forward speed ``speed`` (m/s) of ``system`` (the bicycle
    from ``from_mechanics(whipple_kane(), dependent=DEPENDENT)``): every coordinate 0 (the
    pitch q4 = 0 is on the ground for the benchmark's geometry), roll and steer rates 0,
    the rear wheel's rate speed / WRrad."""
    at = {q.name: 0.0 for q in system.J.q}
    at.update(q2_t=0.0, q5_t=0.0, q3_t=speed / params["WRrad"])
    return at
