"""Bit-for-bit regression of the compiled methods: every output row, event, status and
count of the cases below must agree exactly with ``tests/data/rk_reference.npz``.

History: first recorded with the per-method loops that preceded the shared loop
(``integrators.loop``) and the shared Newton solver of dla and dvi
(``integrators.newton``), which reproduced it exactly; re-recorded when the kernels came
to be emitted from the shared graph (codegen version 9: the same expressions evaluated in
another order, so trajectories moved by rounding).  Regenerate (only for an intended
change of results) with ``python tests/test_numeric_reference.py``."""

from pathlib import Path

import numpy as np
import pytest

from jetnh.models import appell_hamel, chaplygin_sleigh, nonholonomic_particle
from jetnh.numeric import Event, Scene

DATA = Path(__file__).parent / "data" / "rk_reference.npz"


def _scenes():
    part = Scene(nonholonomic_particle(), "chetaev",
                 initial=dict(x=0.1, y=-0.5, z=0.2, x_t=1.0, y_t=0.3), t_span=(0.0, 6.0))
    sleigh = Scene(chaplygin_sleigh(), "chetaev", initial=dict(x=0.0, y=0.0, theta=0.0, theta_t=2.0, x_t=0.3),
                   t_span=(0.0, 8.0))
    ah = Scene(appell_hamel(), "chetaev", initial=dict(x=0, y=0, z=0, x_t=0.6, y_t=0.8),
               t_span=(0.0, 1.0))
    return part, sleigh, ah


def _cases():
    part, sleigh, ah = _scenes()
    vak = Scene(nonholonomic_particle(), "vakonomic", initial=dict(
        x=0.1, y=-0.5, z=0.2, x_t=1.0, y_t=0.3, lambda_z=0.2), t_span=(0.0, 2.0))
    te = np.linspace(0.0, 6.0, 37)
    x, y = part.system.J.q[:2]
    yield "part-dop853-steps", part, dict(method="dop853", rtol=1e-9, atol=1e-12)
    yield "part-dopri5-steps", part, dict(method="dopri5", rtol=1e-7, atol=1e-10)
    yield "part-dop853-teval", part, dict(method="dop853", rtol=1e-6, atol=1e-9, t_eval=te)
    yield "part-dopri5-teval", part, dict(method="dopri5", rtol=1e-6, atol=1e-9, t_eval=te)
    yield "part-rk4", part, dict(method="rk4", n_steps=60)
    yield "part-rk4-final", part, dict(method="rk4", n_steps=33, save="final")
    for m in ("dop853", "dopri5"):
        yield f"part-{m}-events", part, dict(
            method=m, rtol=1e-8, atol=1e-11,
            events=[y - 0.25, Event(x - 2.0, terminal=True, direction=1)])
    yield "part-rk4-events", part, dict(method="rk4", n_steps=80, events=[y - 0.25])
    for m in ("dop853", "dopri5"):
        yield f"sleigh-{m}", sleigh, dict(method=m, rtol=1e-10, atol=1e-12, split="fixed")
        yield f"ah-{m}-singular", ah, dict(method=m, rtol=1e-10, atol=1e-12)
    yield "ah-rk4-singular", ah, dict(method="rk4", n_steps=200)
    yield "sleigh-dla", sleigh, dict(method="dla", h=0.02)
    yield "sleigh-dla-projection", sleigh, dict(method="dla", h=0.05, projection=True)
    yield "part-dvi", vak, dict(method="dvi", n_steps=50)
    yield "part-dop853-first", part, dict(method="dop853", first_step=0.01, max_step=0.3,
                                          rtol=1e-7, atol=1e-9, save="final")


def _record(traj):
    d = traj.diagnostics
    out = {"t": traj.t, "y": traj.y,
           "counts": np.array([traj.status, d.steps, d.rejected, d.rhs_evaluations])}
    for k, (te, ye) in enumerate(zip(traj.t_events or (), traj.y_events or ())):
        out[f"te{k}"] = np.asarray(te)
        out[f"ye{k}"] = np.asarray(ye)
    return out


def _all():
    res = {}
    for name, scene, kw in _cases():
        for k, v in _record(scene.run(**kw)).items():
            res[f"{name}/{k}"] = v
    return res


@pytest.fixture(scope="module")
def recorded():
    with np.load(DATA) as f:
        return dict(f)


@pytest.mark.parametrize("name", [c[0] for c in _cases()])
def test_bit_for_bit(recorded, name):
    case = next(c for c in _cases() if c[0] == name)
    got = _record(case[1].run(**case[2]))
    want = {k.split("/", 1)[1]: v for k, v in recorded.items() if k.startswith(name + "/")}
    assert sorted(got) == sorted(want)
    for k in want:
        np.testing.assert_array_equal(got[k], want[k], err_msg=f"{name}: {k}")


if __name__ == "__main__":
    np.savez_compressed(DATA, **_all())
