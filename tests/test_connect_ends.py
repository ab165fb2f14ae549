"""Free end coordinates in the vakonomic and Hoelder two-point problems: an ``end``
that names only some coordinates leaves the others free, and their transversality
conditions close the problem -- the coefficient of each free eta^i in the boundary term
P_s eta^s of the composite action's variation (13) vanishes at t1, i.e. the momentum
P_i = d(L + lambda f)/dqdot^i (``connect.problem.transversality``).

Closed form: the Heisenberg system (zdot = x ydot - y xdot, L = m |v|^2 / 2) with z free:
P_z = lambda_z, a constant of its motions, so lambda = 0 and the motion is the straight
line, of action |end - start|^2 / (2 T).  Independent route: the free-end answer
minimizes the fixed-end action over the free coordinate's end value, whose derivative
by that value is the momentum at t1 (the rolling disk with psi free: I2 psi_t(t1) = 0),
checked by central differences of fixed-end connects.
"""

import numpy as np
import pytest
import sympy as sp

import jetnh as jn
from jetnh.models import get
from jetnh.numeric.connect.problem import transversality

O = {"x": 0.0, "y": 0.0, "z": 0.0}
DISK0 = {"x": 0.0, "y": 0.0, "phi": 0.0, "psi": 0.0}


def test_transversality_is_the_composite_momentum():
    heis, disk = get("heisenberg"), get("rolling_disk")
    lam = sp.Symbol("lambda_z")
    x, y = heis.J.q[:2]
    xd = heis.J.qd[0]
    m = next(iter(heis.parameters))
    (pz,) = transversality(heis, "vakonomic", ["z"])
    assert (pz - lam).expand() == 0
    (px,) = transversality(heis, "holder", ["x"])
    assert (px - (m * xd + lam * y)).expand() == 0
    (ppsi,) = transversality(disk, "vakonomic", ["psi"])
    assert str(ppsi) == "I2*psi_t"


@pytest.mark.parametrize("principle", ["vakonomic", "holder"])
def test_heisenberg_with_z_free_is_the_straight_line(principle):
    x1, y1, T = 1.0, -0.5, 2.0
    c = jn.connect(get("heisenberg"), principle, O, {"x": x1, "y": y1}, (0.0, T),
                   guess={"x_t": 0.2, "y_t": 0.9, "lambda_z": 1.5})
    assert c.residual < 1e-9 and c.conditions == ("x", "y", "p_z")
    assert abs(c.initial["x_t"] - x1 / T) < 1e-8 and abs(c.initial["y_t"] - y1 / T) < 1e-8
    assert abs(c.initial["lambda_z"]) < 1e-8
    assert abs(c.cost - (x1**2 + y1**2) / (2 * T)) < 1e-9
    z = c.trajectory["z"]
    assert np.max(np.abs(z)) < 1e-8        # the line through the origin keeps z = 0


def test_rolling_disk_free_heading_minimizes_the_fixed_end_action():
    disk = get("rolling_disk")
    end = {"x": 0.5, "y": 0.3, "phi": 0.2}
    c = jn.connect(disk, "vakonomic", DISK0, end, (0.0, 1.0))
    tr = c.trajectory
    assert c.residual < 1e-9 and abs(tr["psi_t"][-1]) < 1e-9
    psi = float(tr["psi"][-1])

    def fixed(p):
        return jn.connect(disk, "vakonomic", DISK0, {**end, "psi": p}, (0.0, 1.0),
                          guess=[c.initial[u] for u in c.unknowns])

    h = 1e-3
    lo, mid, hi = fixed(psi - h), fixed(psi), fixed(psi + h)
    assert abs(mid.cost - c.cost) < 1e-9
    assert lo.cost > c.cost and hi.cost > c.cost                 # a minimum over psi(t1)
    assert abs(hi.cost - lo.cost) / (2 * h) < 1e-5               # stationary: p_psi = 0
    # away from it the derivative of the fixed-end action is the momentum I2 psi_t(t1)
    p = psi + 0.3
    a, b, there = fixed(p - h), fixed(p + h), fixed(p)
    I2 = disk.defaults[next(s for s in disk.parameters if s.name == "I2")]
    slope = (b.cost - a.cost) / (2 * h)
    assert abs(slope - float(I2) * there.trajectory["psi_t"][-1]) < 1e-5


def test_free_end_by_multiple_shooting_and_collocation():
    """The same free-end answer by multiple shooting (its last block carries the
    transversality condition) and from the collocation warm start."""
    from jetnh.numeric.connect import collocation

    disk = get("rolling_disk")
    end = {"x": 0.5, "y": 0.3, "phi": 0.2}
    one = jn.connect(disk, "vakonomic", DISK0, end, (0.0, 1.0))
    three = jn.connect(disk, "vakonomic", DISK0, end, (0.0, 1.0), segments=3)
    assert three.residual < 1e-9
    assert max(abs(one.initial[k] - three.initial[k]) for k in one.initial) < 1e-7
    # solve_bvp on the same equations with the transversality condition at t1, from
    # the run of unknowns 20 % off bent onto the end
    shooter = _search(disk, end)
    u = collocation.warm_start(shooter, u=1.2 * np.array([one.initial[k]
                                                          for k in one.unknowns]))
    assert u is not None
    assert max(abs(u[i] - one.initial[k]) for i, k in enumerate(one.unknowns)) < 1e-4


def _search(system, end):
    """The search connect sets up for the vakonomic problem to ``end``."""
    from jetnh.numeric.connect.problem import Momenta, _scene
    from jetnh.numeric.connect.solve import Search

    unknowns = ("phi_t", "psi_t", "lambda_x", "lambda_y")
    scene = _scene(system, "vakonomic", None, {**DISK0, **{u: 0.0 for u in unknowns}},
                   (0.0, 1.0))
    free = [c for c in DISK0 if c not in end]
    return Search(scene, DISK0, end, unknowns, {}, 1e-11, 1e-12, "dop853", 1e-9,
                  momenta=Momenta(scene, free))


def test_transversality_derived_once_per_system_principle_and_free_set():
    """``Momenta`` of one system, principle and free coordinates share one derivation
    (the same tuples), equal to ``transversality`` derived afresh; another principle,
    free set or system gets its own; a system that only shares a cached entry's id
    (the id of a collected system reused) derives its own."""
    from jetnh.numeric.connect import problem
    from jetnh.numeric.connect.problem import Momenta, _scene

    disk, heis = get("rolling_disk"), get("heisenberg")
    unknowns = {"phi_t": 0.0, "psi_t": 0.0, "lambda_x": 0.0, "lambda_y": 0.0}
    scenes = {p: _scene(disk, p, None, {**DISK0, **unknowns}, (0.0, 1.0))
              for p in ("vakonomic", "holder")}
    one, two = Momenta(scenes["vakonomic"], ["psi"]), Momenta(scenes["vakonomic"], ["psi"])
    assert one.exprs is two.exprs and one.jacobian is two.jacobian
    assert one.exprs == transversality(disk, "vakonomic", ["psi"])
    both = Momenta(scenes["vakonomic"], ["phi", "psi"])
    assert both.free == ("phi", "psi")
    assert both.exprs == transversality(disk, "vakonomic", ["phi", "psi"])
    holder = Momenta(scenes["holder"], ["phi", "psi"])
    assert holder.exprs == transversality(disk, "holder", ["phi", "psi"])
    assert holder.exprs is not both.exprs            # its own entry (equal for the disk)
    # the values at a state: the same numbers from either Momenta
    y = np.linspace(0.1, 0.8, len(scenes["vakonomic"].state_names))
    assert all(np.array_equal(a, b) for a, b in zip(one(0.5, y), two(0.5, y)))
    # a stale entry under the id of another system is not taken
    hscene = _scene(heis, "vakonomic", None, {**O, "x_t": 0.0, "y_t": 0.0,
                                              "lambda_z": 0.0}, (0.0, 1.0))
    key = (id(heis), "vakonomic", ("z",), hscene.state_names)
    problem._MOMENTA[key] = (disk, problem._MOMENTA[next(iter(problem._MOMENTA))][1])
    (pz,) = Momenta(hscene, ["z"]).exprs
    assert (pz - sp.Symbol("lambda_z")).expand() == 0
    assert problem._MOMENTA[key][0] is heis
