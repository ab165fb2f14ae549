"""Multiple shooting in connect (``segments``): the same answers as single shooting,
and a long unstable span that single shooting cannot solve (and, where it cannot even
polish multiple shooting's answer, the segments stitched into one motion); the knife
edge's vakonomic motion to where its Chetaev motion goes in 1 s (the guess's run crosses
the edge of its split) by Newton, the collocation warm start and multiple shooting: the
same answer.

The unstable system: the Heisenberg constraint zdot = x ydot - y xdot with the
inverted potential L = (xdot^2 + ydot^2)/2 + a^2 (x^2 + y^2)/2.  Its vakonomic equations
(the Heisenberg ones plus the potential's force) are linear in (x, y, xdot, ydot) for
the constant multiplier lambda: xddot = a^2 x - 2 lambda ydot, yddot = a^2 y +
2 lambda xdot, so (x, y)(T) is exp(M T) applied to the initial state -- an independent
route to the end the answer reaches.  Its sensitivities grow like e^{a T}: e^22 for
a = 2, T = 11.
"""

import numpy as np
import pytest
import sympy as sp
from scipy.linalg import expm

import jetnh as jn
from jetnh.geometry.jet import JetSpace
from jetnh.models import get

O = {"x": 0.0, "y": 0.0, "z": 0.0}


def _inverted(a):
    J = JetSpace("x y z")
    x, y, z = J.q
    xd, yd, zd = J.qd
    s = sp.Symbol("a")
    L = (xd**2 + yd**2) / 2 + s**2 * (x**2 + y**2) / 2
    return jn.System(J, L, [zd - (x * yd - y * xd)], [z], defaults={s: a})


def _same(c, d, tol):
    assert set(c.initial) == set(d.initial)
    assert max(abs(c.initial[k] - d.initial[k]) for k in c.initial) < tol
    assert abs(c.cost - d.cost) < tol


def test_multiple_shooting_agrees_on_heisenberg():
    heis = get("heisenberg")
    end = {"x": 0.6, "y": 0.8, "z": 0.2}
    one = jn.connect(heis, "vakonomic", O, end, (0.0, 1.0), segments=1)
    three = jn.connect(heis, "vakonomic", O, end, (0.0, 1.0), segments=3)
    assert one.residual < 1e-9 and three.residual < 1e-9
    _same(one, three, 1e-8)


def test_multiple_shooting_agrees_on_the_rolling_disk():
    disk = get("rolling_disk")
    D0 = {"x": 0.0, "y": 0.0, "phi": 0.0, "psi": 0.0}
    end = {"x": 0.5, "y": 0.5, "phi": 0.5, "psi": 0.5}
    one = jn.connect(disk, "vakonomic", D0, end, (0.0, 1.0), segments=1)
    four = jn.connect(disk, "vakonomic", D0, end, (0.0, 1.0), segments=4)
    _same(one, four, 1e-8)


def test_long_unstable_span_needs_multiple_shooting():
    a, T = 2.0, 11.0
    sysm = _inverted(a)
    end = {"x": 1.0, "y": 0.5, "z": 0.3}
    with pytest.raises(jn.ConnectError, match="did not reach the end"):
        jn.connect(sysm, "vakonomic", O, end, (0.0, T), segments=1, max_iter=40,
                   max_continuation=4)
    c = jn.connect(sysm, "vakonomic", O, end, (0.0, T))      # segments from the growth
    assert c.residual < 1e-8
    lam = c.initial["lambda_z"]
    M = np.array([[0, 0, 1, 0], [0, 0, 0, 1], [a * a, 0, 0, -2 * lam],
                  [0, a * a, 2 * lam, 0]])
    xy = expm(M * T) @ np.array([0.0, 0.0, c.initial["x_t"], c.initial["y_t"]])
    # the flow's error grows like e^{a T} ~ 4e9 times the local error
    assert np.max(np.abs(xy[:2] - [1.0, 0.5])) < 1e-3
    # the same motion from 8 segments
    _same(c, jn.connect(sysm, "vakonomic", O, end, (0.0, T), segments=8), 1e-7)


def test_segments_must_be_a_positive_integer():
    with pytest.raises(jn.JetnhError, match="segments"):
        jn.connect(get("heisenberg"), "vakonomic", O, {"x": 1.0}, (0.0, 1.0), segments=0)


def test_knife_edge_vakonomic_by_newton_collocation_and_multiple_shooting():
    """The straight-line guess's run crosses the edge of the split (y dependent, cos phi
    small) and goes on in another (runs with sensitivities change split), so Newton
    goes from it; the collocation warm start (solve_bvp on the same equations) from the
    straight line, and multiple shooting on 3 segments from the line's inner states,
    reach the same motion."""
    from jetnh.numeric.connect import collocation
    from jetnh.numeric.connect.problem import _scene
    from jetnh.numeric.connect.solve import Search

    knife = get("knife_edge")
    ini = jn.models.initial("knife_edge")
    chetaev = jn.Scene(knife, "chetaev", initial=ini, t_span=(0.0, 1.0)).run()
    start = {c: float(chetaev[c][0]) for c in ("x", "y", "phi")}
    end = {c: float(chetaev[c][-1]) for c in ("x", "y", "phi")}
    warm = jn.connect(knife, "vakonomic", start, end, (0.0, 1.0))
    assert warm.route == "Newton from the guess"
    line = {"x_t": end["x"] - start["x"], "phi_t": end["phi"] - start["phi"],
            "lambda_y": 0.0}
    scene = _scene(knife, "vakonomic", None, {**start, **line}, (0.0, 1.0))
    guess_run = scene.run(sensitivities=True, y0={**start, **line})
    assert guess_run.status == 0 and guess_run.switches
    multiple = jn.connect(knife, "vakonomic", start, end, (0.0, 1.0), guess=line,
                          segments=3)
    assert multiple.route.startswith("multiple shooting")
    assert multiple.residual < 1e-9 and warm.residual < 1e-9
    _same(multiple, warm, 1e-7)
    search = Search(scene, start, end, tuple(line), {}, 1e-10, 1e-12, "dop853", 1e-9)
    u = collocation.warm_start(search, u=np.array(list(line.values())))
    assert u is not None
    assert max(abs(u[i] - warm.initial[k]) for i, k in enumerate(line)) < 1e-3


def test_cli_segments_and_free_end(capsys):
    """``jetnh connect --segments 3`` gives connect's answer; a vakonomic ``--to`` that
    leaves y and z free gives the straight line (their momenta vanish at t1)."""
    import json

    from jetnh.cli import main

    code = main(["connect", "heisenberg", "--from", "x=0,y=0,z=0", "--to",
                 "x=0.6,y=0.8,z=0.2", "--t-end", "1", "--segments", "3", "--format",
                 "json", "-q"])
    assert code == 0
    data = json.loads(capsys.readouterr().out)
    c = jn.connect(get("heisenberg"), "vakonomic", O, {"x": 0.6, "y": 0.8, "z": 0.2},
                   (0.0, 1.0))
    assert abs(data["cost"] - c.cost) < 1e-9
    code = main(["connect", "heisenberg", "--from", "x=0,y=0,z=0", "--to", "x=0.6",
                 "--t-end", "1", "--format", "json", "-q"])
    assert code == 0
    data = json.loads(capsys.readouterr().out)
    assert abs(data["cost"] - 0.6**2 / 2) < 1e-9


def test_cli_restarts_replace_a_geodesic_past_its_conjugate_point(capsys):
    """The geodesic with omega = 2 pi / 0.6 over [0, 1] is no minimizer (conjugate at
    0.6); ``--restarts`` finds the minimizing circle to the same end: one turn of a
    circle with |omega| < 2 pi, whose action is smaller and which has no conjugate time."""
    import json
    import math

    from jetnh.cli import main

    omega, theta = 2 * math.pi / 0.6, -0.7
    w = 1 / (1j * omega) * np.exp(1j * theta) * (np.exp(1j * omega) - 1)
    z = (1 - math.sin(omega) / omega) / omega
    to = f"x={float(w.real)!r},y={float(w.imag)!r},z={z!r}"
    base = ["connect", "heisenberg", "--from", "x=0,y=0,z=0", "--to", to, "--t-end", "1",
            "--guess", "x_t=0.7,y_t=-0.6,lambda_z=5", "-q"]
    assert main(base + ["--format", "json"]) == 0
    first = json.loads(capsys.readouterr().out)
    assert first["minimizer"] is False and abs(first["cost"] - 0.5) < 1e-7
    assert main(base + ["--restarts", "4"]) == 0
    out = capsys.readouterr().out
    assert "minimizer: no" not in out and "search:" in out
    assert main(base + ["--restarts", "4", "--format", "json"]) == 0
    best = json.loads(capsys.readouterr().out)
    assert best["minimizer"] is True and best["conjugate_times"] == []
    assert abs(best["cost"] - 0.21287016487) < 1e-7 and best["residual"] < 1e-9


def test_stitched_segments_where_single_shooting_cannot_polish():
    """a = 4, T = 10: sensitivities ~ e^40, past what single shooting can hold at rtol
    1e-11, so the answer is the segments' runs stitched into one motion; its end, its
    chained sensitivities and its action against the closed form (the linear flow
    exp(M T)) and a quadrature of its own dense output."""
    a, T = 4.0, 10.0
    end = {"x": 1.0, "y": 0.5, "z": 0.3}
    c = jn.connect(_inverted(a), "vakonomic", O, end, (0.0, T))
    tr = c.trajectory
    assert "stitched" in tr.stop_reason and c.residual < 1e-8
    assert all(abs(tr[k][-1] - v) < 1e-8 for k, v in end.items())
    lam = c.initial["lambda_z"]
    M = np.array([[0, 0, 1, 0], [0, 0, 0, 1], [a * a, 0, 0, -2 * lam],
                  [0, a * a, 2 * lam, 0]])
    E = expm(M * T)
    S = tr.sensitivities[-1]
    names = tr.scene.state_names
    rows = [names.index("x"), names.index("y")]
    cols = [names.index("x_t"), names.index("y_t")]
    assert np.max(np.abs(S[np.ix_(rows, cols)] - E[:2, 2:]) / np.abs(E[:2, 2:])) < 1e-5
    # the dense output: continuous across the inner nodes, the action by Simpson
    t = np.linspace(0.0, T, 20001)
    Y = tr.at(t)
    L = 0.5 * (Y["x_t"] ** 2 + Y["y_t"] ** 2 + a * a * (Y["x"] ** 2 + Y["y"] ** 2))
    w = np.full(t.size, 2.0)
    w[1::2], w[0], w[-1] = 4.0, 1.0, 1.0
    assert abs(np.sum(w * L) * (t[1] - t[0]) / 3 - c.cost) < 1e-6 * c.cost
    assert np.max(np.abs(np.diff(Y["x"].to_numpy()))) < 1e-2


def test_cli_names_the_start_coordinates_it_set_to_zero(capsys, tmp_path):
    """A model file without initial coordinates and a partial ``--from``: the coordinate
    not given starts at 0, and the output says so (text and json)."""
    import json

    from jetnh.cli import main

    model = tmp_path / "sleigh.toml"
    model.write_text('coordinates = ["x", "y", "th"]\ndependent = ["y"]\n'
                     'lagrangian = "(x_t**2 + y_t**2 + th_t**2) / 2"\n'
                     'constraints = ["-sin(th)*x_t + cos(th)*y_t"]\n')
    args = ["connect", str(model), "-p", "chetaev", "--from", "x=0,y=0", "--to", "x=0.5",
            "--t-end", "1", "-q"]
    assert main(args) == 0
    out = capsys.readouterr().out
    assert "from:      x = 0, y = 0, th = 0" in out and "(not given, set to 0: th)" in out
    assert main(args + ["--format", "json"]) == 0
    data = json.loads(capsys.readouterr().out)
    assert data["zero_start"] == ["th"] and data["start"]["th"] == 0.0


def test_cli_timeout_reports_where_the_search_stopped(capsys):
    from jetnh.cli import main

    code = main(["connect", "heisenberg", "--from", "x=0,y=0,z=0", "--to", "x=1,y=0.5,z=3",
                 "--t-end", "1", "--timeout", "1e-6", "-q"])
    err = capsys.readouterr().err
    assert code == 1 and "connect stopped at its timeout of 1e-06 s" in err
    assert "Traceback" not in err
