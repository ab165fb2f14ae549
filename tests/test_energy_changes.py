"""Why the energy is not conserved by design (``jetnh.mechanics.energy``), said in the
diagnostics: each named reason against the drift of tight runs (a second route: where no
reason is named the equations conserve E, so a tight run's drift is at the tolerance's
level; where one is, the motion changes E by far more), and the reasons at the scene's
parameter values."""

import numpy as np
import pytest
import sympy as sp

import jetnh as jn
from jetnh import models
from jetnh.mechanics.energy import changes
from jetnh.numeric.codegen import multiplier_names

J = jn.JetSpace("x y z")
(x, y, z), (xt, yt, zt) = J.q, J.qd
t, c = J.t, sp.Symbol("c")
L = (xt**2 + yt**2 + zt**2) / 2 - y**2 / 2
START = dict(x=0.0, y=0.1, z=0.0, x_t=1.0, y_t=0.0)
TIGHT = dict(rtol=1e-12, atol=1e-13)
REACTIONS = "the constraint reactions work (a constraint not homogeneous in the velocities)"


def drift(system, principle, params, extra=None):
    ini = dict(START, **(extra or {}))
    sc = jn.Scene(system, principle, params=params, initial=ini, t_span=(0.0, 5.0))
    d = sc.run(**TIGHT).diagnostics
    return d, d.energy_drift_relative


def test_affine_constraint_reactions_work_under_chetaev_only():
    """z_t = y x_t + c: the Chetaev reaction's power is -lambda c; with c = 0 the
    constraint is homogeneous and E is conserved; the vakonomic E (of L + lambda f)
    is conserved for any c."""
    S = jn.System(J, L, [zt - y * xt - c])
    d, rel = drift(S, "chetaev", {"c": 0.7})
    assert d.energy_changes == (REACTIONS,) and rel > 1e-2
    assert "not conserved: " + REACTIONS in str(d)
    d, rel = drift(S, "chetaev", {"c": 0.0})
    assert d.energy_changes == () and rel < 1e-9 and "not conserved" not in str(d)
    d, rel = drift(S, "vakonomic", {"c": 0.7}, {"lambda_z": 0.1})
    assert d.energy_changes == () and rel < 1e-9


def test_explicit_time():
    """t in L changes E under every principle; t in a constraint changes the vakonomic
    E (lambda df/dt) and, through the reactions, the Chetaev one."""
    S = jn.System(J, L + t * y, [zt - y * xt])
    for principle, extra in (("chetaev", None), ("vakonomic", {"lambda_z": 0.1})):
        d, rel = drift(S, principle, {}, extra)
        assert d.energy_changes == ("L depends on t",) and rel > 1e-2
    S = jn.System(J, L, [zt - y * xt - sp.sin(t)])
    assert changes(S, "vakonomic", {}) == ("the constraints depend on t",)
    assert changes(S, "chetaev", {}) == (REACTIONS,)


def test_a_t_that_cancels_is_no_reason():
    """sin(t)^2 + cos(t)^2 in L (a Kane import writes such terms) does not depend on t."""
    S = jn.System(J, L + y * (sp.sin(t)**2 + sp.cos(t)**2), [zt - y * xt])
    assert changes(S, "chetaev", {}) == ()


def test_forces_and_their_value():
    S = jn.System(J, L, [zt - y * xt], forces={x: -c * xt})
    assert changes(S, "chetaev", {"c": 0.3}) == ("the generalized forces work (traj.power)",)
    assert changes(S, "chetaev", {"c": 0.0}) == ()


@pytest.mark.parametrize("name, principle", [
    ("chaplygin_sleigh", "chetaev"), ("rolling_disk", "chetaev"),
    ("rolling_disk", "vakonomic"), ("rheonomic_knife_edge", "chetaev"),
    ("rheonomic_knife_edge", "vakonomic"), ("damped_knife_edge", "chetaev")])
def test_catalogue_models_drift_as_named(name, principle):
    """Where no reason is named, a tight run's relative drift is at rounding level; the
    rheonomic knife edge and the damped one name theirs and drift."""
    system = models.get(name)
    ini = dict(models.initial(name),
               **{m: 0.05 for m in multiplier_names(system, principle)})
    sc = jn.Scene(system, principle, initial=ini, t_span=(0.0, 1.0))
    d = sc.run(**TIGHT).diagnostics
    if d.energy_changes:
        assert name in ("rheonomic_knife_edge", "damped_knife_edge")
        assert d.energy_drift_relative > 1e-6
    else:
        assert name not in ("rheonomic_knife_edge", "damped_knife_edge")
        assert d.energy_drift_relative < 1e-9
