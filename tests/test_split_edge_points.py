"""Points at the edge of a split's chart (``jetnh.numeric.regular``): a sleigh in
centre-of-mass coordinates, -sin(th) X_t + cos(th) Y_t - a th_t = 0 with dependent=[Y],
near th = pi/2 where cos th vanishes (6e-17 in floats at th = pi/2).  A point is refused
with a ConstraintError naming the split, its measure and a regular split, or its answer
(linearization, run) equals the one computed with dependent=[X]; a point off the
constraints is never taken; a large residual is never a steady motion."""

import math

import numpy as np
import pytest
import sympy as sp
from hypothesis import HealthCheck, event, given, settings, strategies as st

import jetnh as jn
from jetnh import models
from jetnh.errors import ConstraintError

J = jn.JetSpace("X Y th")
X, Y, TH = J.q
XT, YT, THT = J.qd
m_, I_, a_ = sp.symbols("m I a", positive=True)
L = m_ / 2 * (XT**2 + YT**2) + I_ / 2 * THT**2
F = [-sp.sin(TH) * XT + sp.cos(TH) * YT - a_ * THT]
S = jn.System(J, L, F, dependent=[Y])
SX = jn.System(J, L, F, dependent=[X])
P = {"m": 2.0, "I": 0.7, "a": 0.4}
EDGE = {"X": 0.0, "Y": 0.0, "th": math.pi / 2}
SINGULAR = r"split dependent=\['Y'\] is singular.*measure.*dependent=\['X'\]"


def in_x(at):
    """The same point for the system with dependent=[X] (X_t follows there)."""
    return {k: v for k, v in at.items() if k != "X_t"}


def same_eigenvalues(lin, ref):
    scale = max(1.0, np.abs(ref.A).max(), np.abs(lin.A).max())
    assert np.allclose(np.sort_complex(lin.eigenvalues), np.sort_complex(ref.eigenvalues),
                       rtol=1e-8, atol=1e-8 * scale)


@pytest.fixture(scope="module")
def scenes():
    start = {"X": 0.0, "Y": 0.0, "th": 1.0, "X_t": 0.0, "th_t": 1.0}
    own = jn.Scene(S, params=P, initial=start, t_span=(0.0, 0.5))
    other = jn.Scene(SX, params=P, initial=in_x({**start, "Y_t": 0.4 / math.cos(1.0)}),
                     t_span=(0.0, 0.5))
    return own, other


# ---------------------------------------------------------------------- the audit's points
def test_a_off_the_constraints_without_Y_t_is_refused():
    """(a) X_t = 0, th_t = 1: no Y_t satisfies the constraint; phi = 0.4 / 6e-17."""
    with pytest.raises(ConstraintError, match=SINGULAR) as err:
        jn.linearize(S, at={**EDGE, "X_t": 0.0, "th_t": 1.0}, params=P)
    assert "Give Y_t too" in str(err.value) and "3.23e-33" in str(err.value)
    assert "one rounding unit in th moves Y_t" in str(err.value)
    # given with Y_t it is off the constraints: refused (Y_t = 6.5e15 would be on them
    # within half a rounding unit of th: cos th = 0.4 / Y_t = 6.15e-17)
    for yt in (0.0, -6.5e15):
        with pytest.raises(ConstraintError, match="off the constraints"):
            jn.linearize(S, at={**EDGE, "X_t": 0.0, "th_t": 1.0, "Y_t": yt}, params=P)


def test_b_on_the_constraints_not_steady():
    """(b) X_t = -0.4, th_t = 1 is on the constraints for every Y_t: without it refused;
    with it linearized in the split X, not a steady motion (v' = a th_t^2 = 0.4)."""
    at = {**EDGE, "X_t": -0.4, "th_t": 1.0}
    with pytest.raises(ConstraintError, match=SINGULAR):
        jn.linearize(S, at=at, params=P)
    for yt in (0.0, 1.5):
        lin = jn.linearize(S, at={**at, "Y_t": yt}, params=P)
        assert lin.state_names == ("th", "Y_t", "th_t") and lin.at["X_t"] == pytest.approx(-0.4)
        assert not lin.steady_motion and lin.verdict == "not a steady motion"
        assert lin.stable is None and lin.residual > 0.4
        ref = jn.linearize(SX, at=in_x({**at, "Y_t": yt}), params=P)
        same_eigenvalues(lin, ref)
        assert np.abs(lin.eigenvalues).max() < 10.0          # no 1/cos th


def test_c_scene_replace_run_and_ensemble_refuse_the_point(scenes):
    own, _ = scenes
    bad = {**EDGE, "X_t": 0.0, "th_t": 1.0}
    with pytest.raises(ConstraintError, match=SINGULAR):
        jn.Scene(S, params=P, initial=bad)
    with pytest.raises(ConstraintError, match=SINGULAR):
        own.replace(initial=bad)
    with pytest.raises(ConstraintError, match="y0: .*" + SINGULAR):
        own.run(y0={"th": math.pi / 2})
    with pytest.raises(ConstraintError, match="y0: .*" + SINGULAR):
        own.run(y0=np.array([0.0, 0.0, math.pi / 2, 0.0, 1.0]))
    with pytest.raises(ConstraintError, match="run 1: .*" + SINGULAR):
        own.ensemble(initial={"th": np.array([1.0, math.pi / 2])}, save="final")
    with pytest.raises(ConstraintError, match="run 1: the point is off the constraints"):
        own.ensemble(initial={"th": np.array([1.0, math.pi / 2]),
                              "Y_t": np.array([0.4 / math.cos(1.0), 1.0])}, save="final")


def test_d_on_the_constraints_with_every_velocity():
    """(d) X_t = th_t = 0, Y_t = 1 at cos th = 0: on the constraints (Y_t is free there);
    linearized in the split X, equal to the system built with dependent=[X]."""
    at = {**EDGE, "X_t": 0.0, "th_t": 0.0, "Y_t": 1.0}
    lin = jn.linearize(S, at=at, params=P)
    ref = jn.linearize(SX, at=in_x(at), params=P)
    assert lin.state_names == ref.state_names == ("th", "Y_t", "th_t")
    assert lin.at["Y_t"] == 1.0 and abs(lin.at["X_t"]) < 1e-15
    assert np.array_equal(lin.A, ref.A) and lin.verdict == ref.verdict == "marginal"
    same_eigenvalues(lin, ref)
    # the sleigh moving straight along its axis at v = Y_t = 1 (heading pi/2):
    # eigenvalues 0, 0 and -m a v / (I + m a^2)
    assert np.allclose(np.sort(lin.eigenvalues.real), [-0.4 * 2.0 / (0.7 + 2 * 0.16), 0, 0])
    # a scene's state (the independent velocities of Y) cannot hold it: refused with the
    # split to build it in, not with a false claim about the constraints
    with pytest.raises(ConstraintError, match=r"on the constraints.*with_split\(\['X'\]\)"):
        jn.Scene(S, params=P, initial=at)


def test_past_the_edge_linearized_in_the_best_split():
    """Past the edge of the chart (measure below 1/(4N)), a point without its dependent
    velocities is linearized where a run from it would go on: at cos th = 3e-7 the
    sleigh running straight has the closed-form eigenvalue -m a v / (I + m a^2) to the
    rounding of v = 1 / cos th (in the split Y itself A would hold 1/cos^2 and lose three
    digits); the catalogue sleigh with x dependent at heading 0.3 (sin^2 = 0.087 < 1/8)
    is the one with y dependent."""
    d = 3e-7
    at = {"X": 0.0, "Y": 0.0, "th": math.pi / 2 - d, "X_t": 1.0, "th_t": 0.0}
    lin = jn.linearize(S, at=at, params=P)
    assert lin.state_names == ("th", "Y_t", "th_t") and lin.steady_motion
    v = 1.0 / math.cos(math.pi / 2 - d)
    assert lin.eigenvalues.real.min() == pytest.approx(-0.8 * v / 1.02, rel=1e-9)
    sleigh = models.get("chaplygin_sleigh")
    J = sleigh.J
    in_x = jn.System(J, sleigh.L, sleigh.constraints, [J.q[0]], defaults=sleigh.defaults)
    a = jn.linearize(sleigh, at={"theta": 0.3, "x_t": 1.3 * math.cos(0.3), "theta_t": 0.0})
    b = jn.linearize(in_x, at={"theta": 0.3, "y_t": 1.3 * math.sin(0.3), "theta_t": 0.0})
    assert a.state_names == b.state_names == ("theta", "x_t", "theta_t")
    assert np.allclose(a.A, b.A, rtol=1e-12, atol=1e-12)


def test_a_large_residual_is_no_steady_motion():
    """x'' = -K x + K + 1 at x = 1 (K = 1e6): x'' = 1 is 5e-7 of the terms K x, K + 1
    that make it up, far above their rounding: no steady motion, however large |A| is;
    at x = 1 + 1/K it is zero to rounding (K = 1e6 and 1e9)."""
    Jx = jn.JetSpace("x")
    x, = Jx.q
    K = sp.Symbol("K", positive=True)
    s = jn.System(Jx, Jx.qd[0]**2 / 2 - K * x**2 / 2 + (K + 1) * x)
    lin = jn.linearize(s, at={"x": 1.0, "x_t": 0.0}, params={"K": 1e6})
    assert lin.residual == pytest.approx(1.0, rel=1e-6)
    assert not lin.steady_motion and lin.verdict == "not a steady motion"
    for k in (1e6, 1e9):
        rest = jn.linearize(s, at={"x": 1.0 + 1 / k, "x_t": 0.0}, params={"K": k})
        assert rest.steady_motion                            # x'' = 0 to rounding


# ---------------------------------------------------------------------- near the edge
OFFSETS = st.builds(lambda s, e: s * 10.0**e, st.sampled_from([-1.0, 1.0]),
                    st.floats(-17.0, -2.0)) | st.just(0.0)


@settings(max_examples=25, deadline=None, suppress_health_check=list(HealthCheck))
@given(OFFSETS, st.floats(-1.0, 1.0), st.floats(-1.0, 1.0) | st.just(0.0), st.booleans())
def test_near_the_edge_refused_or_equal_to_the_other_split(scenes, d, u, w, every):
    """th = pi/2 + d: without Y_t (the point is (X_t = u, th_t = w)), with every velocity
    (on the constraints: Y_t = u, th_t = w, X_t from them); refused, or the linearization
    equals the one in the split X (A itself where it was taken there; the eigenvalues at
    a steady motion, th_t = 0, where they do not depend on the chart) and so does the run."""
    th = math.pi / 2 + d
    if every:
        at = {"X": 0.0, "Y": 0.0, "th": th, "Y_t": u, "th_t": w,
              "X_t": (math.cos(th) * u - 0.4 * w) / math.sin(th)}
    else:
        at = {"X": 0.0, "Y": 0.0, "th": th, "X_t": u, "th_t": w}
    try:
        lin = jn.linearize(S, at=at, params=P)
    except ConstraintError as err:
        assert "split dependent=['Y'] is singular" in str(err) and "['X']" in str(err)
        event("refused: no Y_t")
        assert not every and "one rounding unit in" in str(err)
        assert abs(math.cos(th)) < 1e-5       # phi's rounding error is u / |cos th|
        return
    full = dict(lin.at)
    ref = jn.linearize(SX, at=in_x(full), params=P)
    if "Y_t" in lin.state_names:             # linearized in the split X
        assert np.array_equal(lin.A, ref.A) and lin.verdict == ref.verdict
    assert lin.steady_motion == ref.steady_motion
    if lin.steady_motion:       # (off a steady motion A depends on the chart)
        same_eigenvalues(lin, ref)
    own, other = scenes
    try:
        tr = own.replace(initial=at).run(save="final", rtol=1e-11, atol=1e-12)
    except ConstraintError as err:      # a scene's state cannot hold Y_t at the edge
        event("scene refused")
        assert every and "with_split(['X'])" in str(err)
        return
    event("linearized in " + ("X" if "Y_t" in lin.state_names else "Y") + ", run")
    tx = other.replace(initial=in_x(full)).run(save="final", rtol=1e-11, atol=1e-12)
    scale = max(1.0, max(abs(v) for v in full.values()))
    for name in ("X", "Y", "th", "X_t", "Y_t", "th_t"):
        assert abs(tr[name][-1] - tx[name][-1]) <= 1e-7 * scale, name


def test_a_scene_of_many_constraints_counts_no_splits(monkeypatch):
    """The check at the start point stays cheap where the atlas does not apply (more
    than atlas.MAX_K constraints: runs keep their split): it never tests the rank of
    every minor (C(n, k) of them, with mpmath: 26 s for the 12-trailer, unbounded for
    the 64-trailer), and the edge it uses is 1/(4 C(n, k))."""
    from jetnh.numeric import atlas, regular

    def refuse(system):
        raise AssertionError("atlas.splits called for a system the atlas does not take")

    monkeypatch.setattr(atlas, "splits", refuse)
    system = models.get("n_trailer", N=6)
    assert system.k > atlas.MAX_K
    sc = jn.Scene(system, "chetaev", initial=models.initial("n_trailer", N=6),
                  t_span=(0.0, 0.1))
    assert sc.run().success
    assert regular.edge(system) == 1.0 / (4 * math.comb(system.J.n, system.k))
