"""Scenes against closed-form solutions and first integrals, and the error paths."""

import numpy as np
import pytest
from hypothesis import given, settings, strategies as st
import sympy as sp

import jetnh as jn
from jetnh import models
from jetnh.mechanics.system import System
from jetnh.errors import ConstraintError, FrozenError, IntegrationError, JetnhError
from jetnh.numeric import Scene

R_, I1_, I2_ = 1.5, 0.5, 0.25
DISK0 = dict(x=0.1, y=-0.2, phi=0.3, psi=0.4, phi_t=1.0, psi_t=0.7)


@pytest.fixture(scope="module")
def disk():
    """The catalogue's rolling disk without its default parameters (the tests give them)."""
    s = models.rolling_disk().replace(defaults=None)
    R, I1, I2 = sp.symbols("R I1 I2")
    return s, {R: R_, I1: I1_, I2: I2_}


@pytest.fixture(scope="module")
def disk_scene(disk):
    s, params = disk
    return Scene(s, "chetaev", params=params, initial=DISK0, t_span=(0.0, 10.0),
                 cache=False).compile()


def disk_exact(t):
    """phi_t, psi_t constant; x = x0 + R phi_t/psi_t (sin psi - sin psi0), etc."""
    w, u = DISK0["psi_t"], DISK0["phi_t"]
    psi = DISK0["psi"] + w * t
    return dict(
        x=DISK0["x"] + R_ * u / w * (np.sin(psi) - np.sin(DISK0["psi"])),
        y=DISK0["y"] - R_ * u / w * (np.cos(psi) - np.cos(DISK0["psi"])),
        phi=DISK0["phi"] + u * t, psi=psi, phi_t=np.full_like(t, u),
        psi_t=np.full_like(t, w), x_t=R_ * u * np.cos(psi), y_t=R_ * u * np.sin(psi))


def rel_err(a, b):
    return np.max(np.abs(a - b)) / max(np.max(np.abs(b)), 1e-300)


@pytest.mark.parametrize("method", ["dop853", "dopri5"])
def test_disk_closed_form(disk_scene, method):
    traj = disk_scene.run(rtol=1e-11, atol=1e-13, method=method)
    exact = disk_exact(traj.t)
    for name, col in exact.items():
        assert rel_err(traj[name], col) < 1e-9, name
    assert traj.success and traj.diagnostics.stop_reason.startswith("reached")
    assert traj.t[0] == 0.0 and traj.t[-1] == 10.0


def test_disk_access_by_symbol_and_name(disk, disk_scene):
    s, _ = disk
    J = s.J
    traj = disk_scene.run(rtol=1e-10, atol=1e-12)
    x, phi_t, x_t = J.q[0], J.qd[2], J.qd[0]
    assert np.array_equal(traj[x], traj["x"])
    assert np.array_equal(traj[phi_t], traj["phi_t"])
    assert rel_err(traj[x_t], disk_exact(traj.t)["x_t"]) < 1e-8
    assert set(traj.final) >= {"x", "y", "phi", "psi", "phi_t", "psi_t", "x_t", "y_t"}
    with pytest.raises(JetnhError, match="not in this trajectory"):
        traj["nope"]


def test_disk_diagnostics(disk_scene):
    traj = disk_scene.run(rtol=1e-11, atol=1e-13)
    d = traj.diagnostics
    assert d.residual_max < 1e-12
    assert d.energy_drift_relative < 1e-11
    assert abs(d.energy_initial - (0.5 * (R_**2 + I1_) * 1.0**2 + 0.5 * I2_ * 0.7**2)) < 1e-12
    assert d.steps > 0 and d.rhs_evaluations == 12 * (d.steps + d.rejected) + 2
    assert "residual" in str(d)


def test_disk_t_eval_dense_output(disk_scene):
    te = np.linspace(0.0, 10.0, 41)
    for method in ("dop853", "dopri5"):
        traj = disk_scene.run(rtol=1e-11, atol=1e-13, t_eval=te, method=method)
        assert np.array_equal(traj.t, te)
        assert rel_err(traj["x"], disk_exact(te)["x"]) < 1e-8


def test_disk_save_final(disk_scene):
    traj = disk_scene.run(rtol=1e-11, atol=1e-13, save="final")
    assert len(traj) == 2 and traj.t[-1] == 10.0
    assert rel_err(traj["y"][-1:], disk_exact(traj.t[-1:])["y"]) < 1e-9


def test_disk_scipy_backend_same_steps(disk_scene):
    """Same controller as scipy: the same number of right-hand-side evaluations."""
    for ours, theirs in (("dop853", "scipy-DOP853"), ("dopri5", "scipy-RK45")):
        a = disk_scene.run(rtol=1e-8, atol=1e-10, method=ours)
        b = disk_scene.run(rtol=1e-8, atol=1e-10, method=theirs)
        assert a.diagnostics.rhs_evaluations == b.diagnostics.rhs_evaluations
        # the same steps up to rounding (the error norms are summed in another order)
        assert np.allclose(a.t, b.t, rtol=1e-6, atol=1e-6)
        assert np.max(np.abs(a.y - b.y)) < 1e-6
    c = disk_scene.run(rtol=1e-8, atol=1e-10, method="DOP853", backend="scipy")
    assert c.method == "scipy-DOP853"


def test_disk_rk4(disk_scene):
    traj = disk_scene.run(method="rk4", n_steps=2000)
    assert len(traj) == 2001
    assert rel_err(traj["x"], disk_exact(traj.t)["x"]) < 1e-9
    with pytest.raises(JetnhError, match="n_steps"):
        disk_scene.run(method="rk4")


def test_disk_vakonomic_energy(disk):
    s, params = disk
    sc = Scene(s, "vakonomic", params=params, initial=dict(DISK0, lambda_x=0.1, lambda_y=-0.2),
               t_span=(0.0, 10.0), cache=False)
    assert sc.state_names[-2:] == ("lambda_x", "lambda_y")
    traj = sc.run(rtol=1e-11, atol=1e-13)
    assert traj.diagnostics.energy_drift_relative < 1e-10
    assert "lambda_x" in traj.names


# ---------------------------------------------------------------------- the particle
PART0 = dict(x=0.1, y=-0.5, z=0.2, x_t=1.0, y_t=0.3)


@pytest.fixture(scope="module")
def particle():
    J = jn.JetSpace("x y z")
    x, y, z = J.q
    xd, yd, zd = J.qd
    L = (xd**2 + yd**2 + zd**2) / 2
    return System(J, L, [zd - y * xd], dependent=[z])


def particle_exact(t):
    """Chetaev: ydd = 0, xd sqrt(1 + y^2) = c, so with y = y0 + v t
    x = x0 + c/v (asinh y - asinh y0), z = z0 + c/v (sqrt(1 + y^2) - sqrt(1 + y0^2))."""
    v, y0 = PART0["y_t"], PART0["y"]
    c = PART0["x_t"] * np.sqrt(1 + y0**2)
    y = y0 + v * t
    return dict(x=PART0["x"] + c / v * (np.arcsinh(y) - np.arcsinh(y0)), y=y,
                z=PART0["z"] + c / v * (np.sqrt(1 + y**2) - np.sqrt(1 + y0**2)),
                x_t=c / np.sqrt(1 + y**2), z_t=c * y / np.sqrt(1 + y**2))


def test_particle_closed_form_and_integrals(particle):
    J = particle.J
    x, y, z = J.q
    xd = J.qd[0]
    sc = Scene(particle, "chetaev", initial=PART0, t_span=(0.0, 20.0), cache=False,
               integrals={"p": xd * sp.sqrt(1 + y**2)})
    traj = sc.run(rtol=1e-11, atol=1e-13)
    exact = particle_exact(traj.t)
    for name, col in exact.items():
        assert rel_err(traj[name], col) < 1e-9, name
    d = traj.diagnostics
    assert d.energy_drift_relative < 1e-10
    assert abs(d.energy_initial - 0.5 * (1.0 * 1.25 + 0.09)) < 1e-14
    assert d.integral_drift["p"] < 1e-10
    assert np.allclose(traj["p"], np.sqrt(1.25))


# ---------------------------------------------------------------------- error paths
def test_missing_initial_values(disk):
    s, params = disk
    ini = dict(DISK0)
    del ini["psi_t"], ini["x"]
    with pytest.raises(JetnhError, match="missing initial values: x, psi_t"):
        Scene(s, "chetaev", params=params, initial=ini)
    with pytest.raises(JetnhError, match="lambda_x, lambda_y"):
        Scene(s, "vakonomic", params=params, initial=DISK0)


def test_missing_and_unknown_parameters(disk):
    s, params = disk
    with pytest.raises(JetnhError, match="missing parameter values: I2, R"):
        Scene(s, "chetaev", params={"I1": 1.0}, initial=DISK0)
    with pytest.raises(JetnhError, match="'Q'"):
        Scene(s, "chetaev", params=dict(params, Q=1.0), initial=DISK0)
    with pytest.raises(JetnhError, match="not a state"):
        Scene(s, "chetaev", params=params, initial=dict(DISK0, w=1.0))


def test_inconsistent_dependent_velocity(disk):
    s, params = disk
    ini = dict(DISK0, x_t=5.0)
    with pytest.raises(ConstraintError, match="x_t = 5.0 but the constraints give"):
        Scene(s, "chetaev", params=params, initial=ini)
    sc = Scene(s, "chetaev", params=params, initial=ini, project=True, cache=False)
    assert abs(sc.initial["x_t"] - R_ * np.cos(0.4)) < 1e-15
    assert sc.projected["x_t"][0] == 5.0
    # consistent values are accepted
    ok = dict(DISK0, x_t=R_ * np.cos(0.4), y_t=R_ * np.sin(0.4))
    Scene(s, "chetaev", params=params, initial=ok)


def test_singular_initial_configuration():
    J = jn.JetSpace("x y")
    x, y = J.q
    xd, yd = J.qd
    s = System(J, (xd**2 + yd**2) / 2, [x * xd - yd], dependent=[x])
    with pytest.raises(ConstraintError, match="no finite value for x_t"):
        Scene(s, "chetaev", initial=dict(x=0.0, y=0.0, y_t=1.0))


@pytest.fixture(scope="module")
def sqrt_potential():
    """xdd = 1/(2 sqrt(x)): NaN once x < 0."""
    J = jn.JetSpace("x")
    (x,), (xd,) = J.q, J.qd
    s = System(J, xd**2 / 2 + sp.sqrt(x), [])
    return Scene(s, "chetaev", initial=dict(x=1.0, x_t=-3.0), t_span=(0.0, 2.0), cache=False)


def test_nonfinite_state_is_an_error(sqrt_potential):
    """With the singularity checks off; with them on, the indicator x explains the NaN and
    the run stops at the singular configuration (tests/test_numeric_events.py)."""
    with pytest.raises(IntegrationError, match=r"NaN or infinite .* t = 0\.\d+.*x = "):
        sqrt_potential.run(method="rk4", n_steps=50, singular="ignore")
    with pytest.raises(IntegrationError, match="NaN or infinite"):
        sqrt_potential.run(method="dop853", singular="ignore")


def test_bad_arguments(disk_scene):
    with pytest.raises(JetnhError, match="unknown method"):
        disk_scene.run(method="euler")
    with pytest.raises(JetnhError, match="t_eval"):
        disk_scene.run(t_eval=[0.0, 20.0])
    with pytest.raises(JetnhError, match="t_span"):
        Scene(disk_scene.system, "chetaev", params=disk_scene.params, initial=DISK0,
              t_span=(0.0,))


def test_parameters_default_to_the_system_defaults():
    from jetnh.models import rolling_disk

    s = rolling_disk()
    x, y, phi, psi = s.J.q
    scene = Scene(s, "chetaev", initial={x: 0, y: 0, phi: 0, psi: 0, "phi_t": 1.0,
                                         "psi_t": 0.5}, t_span=(0.0, 1.0))
    assert scene.params == {"R": 1.0, "I1": 0.5, "I2": 0.25}
    scene2 = Scene(s, "chetaev", params={"R": 2.0}, initial=scene.initial, t_span=(0, 1),
                   project=True)
    assert scene2.params["R"] == 2.0 and scene2.params["I1"] == 0.5


@settings(deadline=None)
@given(st.floats(-3.0, 3.0), st.floats(-3.0, 3.0), st.floats(-10.0, 10.0),
       st.floats(-2.0, 2.0))
def test_replace_initial_is_the_new_scene(disk_scene, psi, phi_t, x, psi_t):
    """``replace(initial=...)`` takes the scene over, its dependent velocities from the
    compiled kernels: the same states bit for bit, the dependent velocities to rounding,
    the same run bit for bit, frozen, with the kernels' plans handed on."""
    ini = dict(DISK0, psi=psi, phi_t=phi_t, x=x, psi_t=psi_t)
    moved = disk_scene.replace(initial=ini, t_span=(0.0, 0.5))
    new = Scene(disk_scene.system, "chetaev", params=disk_scene.params, initial=ini,
                t_span=(0.0, 0.5), cache=False)
    assert np.array_equal(moved.y0, new.y0) and moved.t_span == new.t_span
    assert moved.initial.keys() == new.initial.keys()
    for name in moved.dependent_velocities:
        assert abs(moved.initial[name] - new.initial[name]) <= 4e-16 * max(
            1.0, abs(new.initial[name]))
    assert np.array_equal(moved.run(rtol=1e-6, atol=1e-9).y, new.run(rtol=1e-6, atol=1e-9).y)
    assert moved.kernels is disk_scene.kernels
    assert moved._memo["plans"] is disk_scene._memo.get("plans", moved._memo["plans"])
    with pytest.raises(FrozenError):
        moved.initial = {}
    with pytest.raises(FrozenError):
        moved.t_span = (0.0, 1.0)


def test_replace_initial_near_a_singular_configuration(monkeypatch):
    """The kernels' floats serve only where every indicator is away from zero; nearer, and
    where a dependent velocity is given, the 30-digit evaluation decides (as a new Scene
    does): a singular configuration is refused, an inconsistent velocity too."""
    J = jn.JetSpace("x y")
    x, y = J.q
    xd, yd = J.qd
    s = System(J, (xd**2 + yd**2) / 2, [x * xd - yd], dependent=[x])    # x_t = y_t / x
    sc = Scene(s, "chetaev", initial=dict(x=1.0, y=0.0, y_t=1.0), cache=False).compile()
    exact = []
    original = Scene._dependent_velocity_values

    def counted(self, *args, **kw):
        exact.append(args[0]["x"])
        return original(self, *args, **kw)
    monkeypatch.setattr(Scene, "_dependent_velocity_values", counted)
    assert sc.replace(initial=dict(x=0.5, y=0.0, y_t=1.0)).initial["x_t"] == 2.0
    assert exact == []
    near = sc.replace(initial=dict(x=1e-9, y=0.0, y_t=1.0))
    assert exact == [1e-9]
    assert near.initial["x_t"] == Scene(s, "chetaev", initial=dict(x=1e-9, y=0.0, y_t=1.0)
                                        ).initial["x_t"]
    with pytest.raises(ConstraintError, match="no finite value for x_t"):
        sc.replace(initial=dict(x=0.0, y=0.0, y_t=1.0))
    with pytest.raises(ConstraintError, match="x_t = 3.0 but the constraints give"):
        sc.replace(initial=dict(x=0.5, y=0.0, y_t=1.0, x_t=3.0))
    with pytest.raises(JetnhError, match="missing initial values"):
        sc.replace(initial=None)
    with pytest.raises(JetnhError, match="initial must be a dict"):
        sc.replace(initial=[0.5, 0.0, 1.0])
