"""One steady motion of every catalogue model and its linear stability under each
principle (``jetnh.linearize``; ``verdicts``).

For the principles whose multipliers are states, the multipliers are solved for so that
the point is a steady motion of that principle too (``Linearization.steady``); where no
multiplier values make it steady, the table says so and gives the residual with the
multipliers at 0.  Writes results/stability_survey.json; prints a table.

    PYTHONPATH=. python benchmarks/stability_survey.py
"""

from __future__ import annotations

import math

import numpy as np

import jetnh as jn
from jetnh import models
from jetnh.errors import JetnhError

try:
    from _common import parser, write
except ImportError:          # run from the repository root
    from benchmarks._common import parser, write

PI2 = math.pi / 2
#: name -> (options, params, operating point, what it is)
MOTIONS = {
    "rolling_disk": ({}, {}, dict(phi_t=1.0, psi_t=0.7), "rolling on a circle"),
    "appell_hamel": ({}, {}, dict(x_t=3.0, y_t=1.0), "none (the speed decays); shown: x_t = 3, y_t = 1"),
    "knife_edge": ({}, {"alpha": 0.0}, dict(phi=0.3, x_t=math.cos(0.3), phi_t=0.0),
                   "straight, on a level plane (alpha = 0)"),
    "chaplygin_sleigh": ({}, {}, dict(theta=0.0, x_t=1.0, theta_t=0.0), "straight, forwards"),
    "nonholonomic_particle": ({}, {}, dict(y=0.0, x_t=1.0, y_t=0.0), "straight along x at y = 0"),
    "heisenberg": ({}, {}, dict(x=0.0, y=0.0, x_t=1.0, y_t=0.5), "straight line"),
    "isokinetic_particle": ({}, {}, dict(y=0.0, y_t=0.0), "none in gravity; shown: y_t = 0"),
    "rheonomic_knife_edge": ({}, {}, dict(x=0.0, x_t=0.5), "none (time-dependent); shown: t = 0"),
    "bead_on_parabola": ({}, {}, dict(x=0.0, x_t=0.0), "rest at the bottom"),
    "radial_line": ({}, {}, dict(x=1.0, y=0.0, x_t=0.0),
                    "none (repulsive centre; the origin is singular for the split); shown: rest at x = 1"),
    "rolling_ball": ({}, {}, dict(phi=0.0, theta=PI2, psi=0.0, phi_t=1.0, theta_t=0.0, psi_t=0.0),
                     "spinning in place about the vertical"),
    "ball_on_turntable": ({}, {}, dict(x=0.0, y=0.0, phi=0.0, theta=PI2, psi=0.0, phi_t=0.0,
                                       theta_t=0.0, psi_t=0.0), "at rest at the centre"),
    "suslov_rigid_body": ({}, {}, dict(phi=0.0, theta=PI2, psi=0.0, phi_t=1.0, theta_t=0.0),
                          "rotation about the second body axis"),
    "rolling_coin": ({}, {}, dict(theta=0.0, psi_t=0.0, theta_t=0.0, phi_t=3.0),
                     "upright, straight, spin 3 (above the critical 1.808)"),
    "n_trailer": ({"N": 2}, {}, dict(theta0=0.0, theta1=0.0, theta2=0.0, x_t=1.0, theta0_t=0.0),
                  "straight, forwards"),
    "particle_chain": ({"N": 3}, {}, {}, "rest"),
    "damped_knife_edge": ({}, {}, dict(phi=0.3, x_t=0.0, phi_t=0.0), "rest"),
    "damped_chaplygin_sleigh": ({}, {}, dict(theta=0.0, x_t=0.0, theta_t=0.0), "rest"),
}


def survey(name):
    opts, params, at, what = MOTIONS[name]
    s = models.get(name, **opts)
    point = {q.name: 0.0 for q in s.J.q}
    point.update({v.name: 0.0 for v in s.independent_velocities})
    point.update(at)
    rows = {}
    for pr in jn.PRINCIPLES:
        lams = [m.name for m in jn.mechanics.principles.get(pr).multiplier_symbols(s)]
        here = {**point, **{m: 0.0 for m in lams}}
        try:
            lin = jn.linearize(s, pr, at=here, params=params)
            note = ""
            if lams and lin.residual > 1e-10:
                try:
                    lin = lin.steady(lams)
                except JetnhError:
                    note = "no multipliers make it steady"
        except JetnhError as err:
            rows[pr] = {"error": str(err).splitlines()[0][:160]}
            continue
        rows[pr] = {"residual": lin.residual, "verdict": lin.verdict,
                    "max_real": float(lin.eigenvalues.real.max(initial=-np.inf)),
                    "states": list(lin.state_names), "note": note,
                    "multipliers": {m: lin.at[m] for m in lams},
                    "eigenvalues": [[z.real, z.imag] for z in lin.eigenvalues.tolist()]}
    return {"motion": what, "at": point, "params": params, "principles": rows}


def main():
    args = parser(__doc__, "stability_survey").parse_args()
    out = {name: survey(name) for name in MOTIONS}
    for name, r in out.items():
        print(f"{name}: {r['motion']}")
        for pr, v in r["principles"].items():
            if "error" in v:
                print(f"  {pr:10s} error: {v['error']}")
            else:
                print(f"  {pr:10s} {v['verdict']:22s} max Re {v['max_real']: .4g}  "
                      f"residual {v['residual']:.2g} {v['note']}")
    write("stability_survey", {"models": out}, args.out, args.quick)


if __name__ == "__main__":
    main()
