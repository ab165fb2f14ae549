"""connect on catalogue systems from the default guess: the rolling disk's vakonomic
parking manoeuvre (checked against collocation, scipy's solve_bvp, on the same compiled
equations) and the Appell-Hamel particle (closed forms).

Appell-Hamel (m = a = 1, b/a = k, gravity g): zdot = k |v|.  Chetaev: the path in (x, y)
is straight, the speed falls at c = k g / (1 + k^2) (the velocity along the line, from
``accelerations``), so v0 = d / T + c T / 2 for a distance d; the action is
int (1 + k^2) v^2 / 2 - g k s dt with s the arc length.  Vakonomic: the motions are
straight lines too (the multiplier only enters the mass matrix across the velocity,
which the straight motion never feels): the ends reachable in time T lie on the cone
z = k |(x, y)|, reached with the multiplier free (shooting Jacobian of rank 2, every
time conjugate), and the path is an abnormal extremal of the constraint (its endpoint
map cannot move z off the cone at first order).
"""

import math
import warnings

import numpy as np
import pytest
from scipy.integrate import solve_bvp

import jetnh as jn
from jetnh.models import get
from jetnh.numeric.connect.collocation import problem

DISK0 = {"x": 0.0, "y": 0.0, "phi": 0.0, "psi": 0.0}


def _collocation(scene, start, end, T, Y0):
    fun, fun_jac, bc, _, _ = problem(scene, start, end, T)
    t = np.linspace(0.0, T, Y0.shape[1])
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        return solve_bvp(fun, bc, t, Y0, fun_jac=fun_jac, tol=1e-8, max_nodes=20_000)


@pytest.mark.parametrize("end", [
    {"x": 0.0, "y": 0.3, "phi": 0.0, "psi": 0.0},          # parallel parking
    {"x": 0.5, "y": 0.5, "phi": 0.5, "psi": 0.5},
])
def test_rolling_disk_vakonomic_from_the_default_guess(end):
    disk = get("rolling_disk")
    c = jn.connect(disk, "vakonomic", DISK0, end, (0.0, 1.0))
    assert c.residual < 1e-8 and c.normal and c.rank == 4
    tr = c.trajectory
    assert all(abs(tr[k][-1] - v) < 1e-8 for k, v in end.items())
    # the same equations by collocation, from the found path disturbed by 10 %: it
    # returns to the same initial state
    times = np.linspace(0.0, 1.0, 31)
    Y0 = tr.at(times).to_numpy()[:, :len(tr.scene.state_names)].T
    Y0 = Y0 * (1.0 + 0.1 * np.cos(7.0 * np.arange(Y0.shape[0])))[:, None]
    sol = _collocation(tr.scene, DISK0, end, 1.0, Y0)
    assert sol.status == 0
    got = np.array([c.initial[k] for k in tr.scene.state_names])
    assert np.max(np.abs(sol.y[:, 0] - got)) < 1e-5
    # the same motion under Hoelder's principle (linear constraints: the same equations)
    h = jn.connect(disk, "holder", DISK0, end, (0.0, 1.0))
    assert abs(h.cost - c.cost) < 1e-9


def _appell(T=1.0, x=3.0, y=1.0):
    ah = get("appell_hamel")
    k, g = 0.5, 9.81
    d = math.hypot(x, y)
    c = k * g / (1 + k * k)
    v0 = d / T + c * T / 2
    v2 = (v0**3 - (v0 - c * T) ** 3) / (3 * c)
    s = v0 * T**2 / 2 - c * T**3 / 6
    return ah, k, d, v0, (1 + k * k) * v2 / 2 - g * k * s


@pytest.mark.parametrize("principle", ["chetaev", "suslov"])
def test_appell_hamel_chetaev_closed_form(principle):
    """The straight-line guess stops before t1 (its speed falls to the singular zero):
    connect moves it, then finds v0 = d / T + c T / 2."""
    ah, k, d, v0, cost = _appell()
    c = jn.connect(ah, principle, {"x": 0, "y": 0, "z": 0}, {"x": 3.0, "y": 1.0}, (0, 1))
    assert c.residual < 1e-9
    assert abs(c.initial["x_t"] - 3 * v0 / d) < 1e-8 and abs(c.initial["y_t"] - v0 / d) < 1e-8
    assert abs(c.cost - cost) < 1e-8
    assert not c.normal           # a straight line of zdot = k |v|: abnormal (see above)


def test_appell_hamel_vakonomic_reaches_the_cone_only():
    ah, k, d, v0, cost = _appell()
    O = {"x": 0, "y": 0, "z": 0}
    c = jn.connect(ah, "vakonomic", O, {"x": 3.0, "y": 1.0, "z": k * d}, (0, 1))
    assert c.residual < 1e-9 and c.rank == 2 and not c.normal
    assert abs(c.initial["x_t"] - 3 * v0 / d) < 1e-8 and abs(c.cost - cost) < 1e-8
    assert c.conjugate_times == (1.0,)       # rank-deficient throughout: no crossings
    with pytest.raises(jn.ConnectError, match="reach a 2-dimensional set"):
        jn.connect(ah, "vakonomic", O, {"x": 3.0, "y": 1.0, "z": k * d + 0.3}, (0, 1),
                   max_iter=20, max_continuation=4)


def test_chetaev_against_vakonomic_in_process_cli(capsys):
    """``jetnh connect --compare``: the Chaplygin sleigh's Chetaev motion to (x, y) and
    the vakonomic motion to the configuration it reached -- the same endpoints, the
    vakonomic action no larger (the answer below is a minimizer: no conjugate time), the
    paths apart; checked against connect called directly."""
    import json

    from jetnh.cli import main

    code = main(["connect", "chaplygin_sleigh", "-p", "chetaev", "--from",
                 "x=0,y=0,theta=0", "--to", "x=0.5,y=0.5", "--t-end", "1", "--compare",
                 "vakonomic", "--format", "json", "-q"])
    assert code == 0
    data = json.loads(capsys.readouterr().out)
    a, b = data, data["compared"]
    assert a["principle"] == "chetaev" and b["principle"] == "vakonomic"
    assert b["residual"] < 1e-8 and b["conjugate_times"] == []
    assert b["cost"] < a["cost"] - 1e-5
    sleigh = get("chaplygin_sleigh")
    O = {"x": 0.0, "y": 0.0, "theta": 0.0}
    c = jn.connect(sleigh, "chetaev", O, {"x": 0.5, "y": 0.5}, (0.0, 1.0))
    reached = {n: float(c.trajectory[n][-1]) for n in O}
    v = jn.connect(sleigh, "vakonomic", O, reached, (0.0, 1.0))
    assert abs(v.cost - b["cost"]) < 1e-9 and abs(c.cost - a["cost"]) < 1e-9
    t = np.linspace(0.0, 1.0, 50)
    assert np.max(np.abs(c.trajectory.at(t)["y"] - v.trajectory.at(t)["y"])) > 1e-3
    # the rolling disk's Chetaev motions are vakonomic (multipliers -(xdot, ydot))
    disk = get("rolling_disk")
    ch = jn.connect(disk, "chetaev", DISK0, {"x": 0.5, "y": 0.3}, (0.0, 1.0))
    full = {n: float(ch.trajectory[n][-1]) for n in DISK0}
    vk = jn.connect(disk, "vakonomic", DISK0, full, (0.0, 1.0),
                    guess={"phi_t": 1.0, "psi_t": 1.0, "lambda_x": -0.5, "lambda_y": -0.2})
    assert abs(vk.cost - ch.cost) < 1e-9
    assert abs(vk.initial["lambda_x"] + ch.initial["x_t"]) < 1e-7
    assert abs(vk.initial["lambda_y"] + ch.initial["y_t"]) < 1e-7
