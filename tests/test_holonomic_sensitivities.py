"""Sensitivities of runs projected onto holonomic constraints: after every accepted step
the state is projected onto g = 0 (``methods.projection``) and its sensitivities with it,
by the derivative of the projection, so that ``traj.sensitivity`` is the derivative of
the projected run.

Two routes: central differences of projected runs (in the initial values that g does not
involve, along the constraint for the coordinates it does, and in a runtime parameter),
and the property that the projected sensitivities of the coordinates lie in the tangent
space of g = 0 (G S_q = 0 from the start: S(t0) varies the configuration along g = 0 in
the split's chart, z following th; ``numeric.initial``).
"""

from __future__ import annotations

import numpy as np
import pytest

from jetnh.errors import JetnhError
from jetnh.numeric import Scene

from holonomic_systems import knife_slider

A = 0.4


@pytest.fixture(scope="module")
def scene():
    ini = {"x": 0.1, "y": -0.2, "th": 0.3, "z": A * np.sin(0.3), "x_t": 1.0, "th_t": 0.7}
    return Scene(knife_slider(), "chetaev", params={"a": A, "k": 3.0, "I": 0.7},
                 initial=ini, t_span=(0.0, 1.5), runtime_params=["k"])


KW = {"dop853": dict(rtol=1e-12, atol=1e-14), "rk4": dict(n_steps=400),
      "radau": dict(rtol=1e-10, atol=1e-12)}


@pytest.mark.parametrize("method", ["dop853", "rk4"])
def test_projected_sensitivities_against_central_differences(scene, method):
    kw = KW[method]
    tr = scene.run(method=method, sensitivities=True, split="fixed", **kw)
    names = scene.state_names
    S = tr.sensitivities[-1]
    col = {c: i for i, c in enumerate(tr.sensitivity_columns)}
    base = dict(zip(names, scene.y0.tolist()))
    h = 1e-6

    def final(y0=None, params=None):
        return scene.run(method=method, y0=y0, params=params, save="final", split="fixed",
                         **kw).y[-1]

    def check(fd, s, what):
        assert np.max(np.abs(fd - s)) < 2e-7 * max(1.0, np.max(np.abs(s))), (what, fd, s)

    # initial values that g does not involve
    for to in [n for n in names if n not in ("th", "z")]:
        fd = (final({**base, to: base[to] + h}) - final({**base, to: base[to] - h})) / (2 * h)
        check(fd, S[:, col[to]], to)
    # along g = 0: th with z = a sin(th)
    th = base["th"]
    up, down = ({**base, "th": th + s * h, "z": A * np.sin(th + s * h)} for s in (1, -1))
    fd = (final(up) - final(down)) / (2 * h)
    check(fd, S[:, col["th"]], "th along g = 0")
    # z follows th on g = 0: no initial value of its own, its column zero and refused
    assert not S[:, col["z"]].any()
    with pytest.raises(JetnhError, match="differentiate by x, y, th"):
        tr.sensitivity("x", "z")
    # the runtime parameter
    fd = (final(params={"k": 3.0 + h}) - final(params={"k": 3.0 - h})) / (2 * h)
    check(fd, S[:, col["k"]], "k")


@pytest.mark.parametrize("method", ["dop853", "rk4", "radau"])
def test_projected_sensitivities_are_tangent(scene, method):
    """G S_q = 0 at every output row (G = dg/dq = (0, 0, -a cos th, 1)), for every
    column, to roundoff; S(t0) is the identity but for z's row (dz/dth = a cos th) and
    column (zero)."""
    tr = scene.run(method=method, sensitivities=True, split="fixed", **KW[method])
    names = scene.state_names
    iq = [names.index(n) for n in ("x", "y", "th", "z")]
    S = tr.sensitivities
    want = np.eye(len(names), S.shape[2])
    want[iq[3], iq[3]], want[iq[3], iq[2]] = 0.0, A * np.cos(tr["th"][0])
    assert np.allclose(S[0], want, rtol=0.0, atol=1e-16)
    th = tr["th"]
    GS = -A * np.cos(th)[:, None] * S[:, iq[2], :] + S[:, iq[3], :]
    assert np.max(np.abs(GS)) < 1e-13 * max(1.0, np.max(np.abs(S)))
    # the state itself on g = 0 at every step
    assert np.max(np.abs(tr["z"] - A * np.sin(th))) < 1e-15


@pytest.fixture(scope="module")
def scene_a():
    """The knife slider with the constraint's own parameter a (z = a sin th) at run
    time: the projection map depends on a."""
    ini = {"x": 0.1, "y": -0.2, "th": 0.3, "z": A * np.sin(0.3), "x_t": 1.0, "th_t": 0.7}
    return Scene(knife_slider(), "chetaev", params={"a": A, "k": 3.0, "I": 0.7},
                 initial=ini, t_span=(0.0, 1.5), runtime_params=["a", "k"])


@pytest.mark.parametrize("method", ["dop853", "rk4"])
def test_projected_sensitivities_in_a_parameter_of_g(scene_a, method):
    """dy/da where g = z - a sin th: central differences of projected runs, each from
    its own start on g = 0 (z0 = a sin th0, as S_a's start moves z: S_z0 is zero), and
    the derivative of g(q(t; a), a) = 0 along the run: G S_q,a = sin th at every row
    (without the chart's dz0/da = sin th0 and the projection's -G^+ dg/da it is 0)."""
    kw = KW[method]
    tr = scene_a.run(method=method, sensitivities=True, split="fixed", **kw)
    S = tr.sensitivities
    col = {c: i for i, c in enumerate(tr.sensitivity_columns)}
    base = dict(zip(scene_a.state_names, scene_a.y0.tolist()))
    th0, h = base["th"], 1e-6

    def final(a):
        return scene_a.run(method=method, y0={**base, "z": a * np.sin(th0)},
                           params={"a": a, "k": 3.0}, save="final", split="fixed",
                           **kw).y[-1]

    fd = (final(A + h) - final(A - h)) / (2 * h)
    want = S[-1][:, col["a"]] + np.sin(th0) * S[-1][:, col["z"]]
    assert np.max(np.abs(fd - want)) < 2e-7 * max(1.0, np.max(np.abs(want))), (fd, want)
    names = scene_a.state_names
    th = tr["th"]
    GS = -A * np.cos(th) * S[:, names.index("th"), col["a"]] + S[:, names.index("z"),
                                                                col["a"]]
    assert np.max(np.abs(GS - np.sin(th))) < 1e-13 * max(1.0, np.max(np.abs(S)))
    assert np.max(np.abs(GS[1:])) > 0.1          # the term matters here
