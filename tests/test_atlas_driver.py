"""A switching run in one compiled call (``numeric.chart_driver``) against the same run
made piece by piece in Python (``atlas.follow``): the same rows, aux rows, dense output,
switches and counts, bit for bit."""

from __future__ import annotations

import numpy as np
import pytest

import jetnh as jn
from jetnh.models import chaplygin_sleigh, knife_edge
from jetnh.numeric import atlas


@pytest.fixture(scope="module")
def scenes():
    from jetnh.numeric import chart_driver

    for method, parts in [("dop853", (True, False, False, False)),
                          ("dop853", (True, False, False, True)),
                          ("dop853", (True, False, True, False)),
                          ("rk4", (True, False, False, True))]:
        chart_driver.compiled(method, parts)        # (as ``jetnh cache warm`` does)
    sleigh = jn.Scene(chaplygin_sleigh(), "vakonomic",
                      initial=dict(x=0, y=0, theta=0, x_t=0.2, theta_t=1.0, lambda_y=0.1),
                      t_span=(0.0, 2.0))
    knife = jn.Scene(knife_edge(), "chetaev",
                     initial=dict(x=0, y=0, phi=0, x_t=0.5, phi_t=3.0), t_span=(0.0, 2.0))
    return {"sleigh": sleigh, "knife": knife}


def _by_follow(scene, kw, monkeypatch):
    with monkeypatch.context() as m:
        m.setattr(atlas, "_driven", lambda *a: None)
        return scene.run(**kw)


RUNS = [dict(method="dop853", save="final", rtol=1e-8, atol=1e-11),
        dict(method="dop853", rtol=1e-11, atol=1e-13),
        dict(method="rk4", n_steps=60),
        dict(method="dop853", rtol=1e-9, t_eval=np.linspace(0.0, 2.0, 9))]


@pytest.mark.parametrize("name", ["sleigh", "knife"])
@pytest.mark.parametrize("kw", RUNS, ids=lambda kw: f"{kw['method']}-{kw.get('save', '')}"
                         f"{'-t_eval' if 't_eval' in kw else ''}{kw.get('rtol', '')}")
def test_driver_equals_follow(scenes, name, kw, monkeypatch):
    scene = scenes[name]
    want = _by_follow(scene, kw, monkeypatch)
    assert want.switches                       # (a run that changes chart)
    scene.run(**kw)                            # (the plan noted as reaching the edge)
    got = scene.run(**kw)
    assert isinstance(got._segments, atlas._Recorded)
    assert got.switches == want.switches and got.status == want.status == 0
    assert np.array_equal(got.t, want.t) and np.array_equal(got.y, want.y)
    assert np.array_equal(got.aux, want.aux)
    assert got._counts[0] == want._counts[0]          # (steps, rejected, evaluations)
    if kw.get("save") != "final" and "t_eval" not in kw:
        tau = np.linspace(0.0, 2.0, 41)
        assert np.array_equal(got.at(tau), want.at(tau))
    pieces, wanted = got._segments.pieces, want._segments.pieces
    assert [(lo, hi, c.split, a) for lo, hi, c, _, a, _ in pieces] == \
        [(lo, hi, c.split, a) for lo, hi, c, _, a, _ in wanted]


@pytest.mark.parametrize("name", ["sleigh", "knife"])
def test_at_inside_a_cut_last_step(scenes, name, monkeypatch):
    """``at()`` inside the last step of a piece cut at the edge re-runs that piece with
    the step control it ran with (its step bound near the singular set too): the driver's
    record and follow's give the same states, where a loose tolerance makes the steps
    long enough for the bound to matter."""
    kw = dict(method="dop853", rtol=1e-4, atol=1e-7)
    scene = {"sleigh": lambda: jn.Scene(
                 chaplygin_sleigh(), "vakonomic", t_span=(0.0, 4.0), initial=dict(
                     x=0, y=0, theta=0, x_t=0.2, theta_t=7.0, lambda_y=0.1)),
             "knife": lambda: scenes["knife"].replace(t_span=(0.0, 4.0))}[name]()
    want = _by_follow(scene, kw, monkeypatch)
    scene.run(**kw)
    got = scene.run(**kw)
    assert isinstance(got._segments, atlas._Recorded)
    tau = [np.linspace(seg.t[-2], seg.t[-1], 7)[1:-1]
           for lo, hi, c, seg, a, rr in got._segments.pieces
           if seg._dense["partial_last"] and len(seg.t) > 1 and hi < len(got.t)]
    assert tau
    tau = np.concatenate(tau)
    assert np.array_equal(got.at(tau), want.at(tau))


def test_a_run_that_never_reaches_the_edge(scenes):
    """After a run that switched, a run of the same plan that ends before the edge is
    the driver's one piece, equal to the loop's own run."""
    scene = scenes["knife"]
    kw = dict(method="dop853", rtol=1e-8, atol=1e-11)
    scene.run(**kw)
    short = scene.run(t_span=(0.0, 0.3), **kw)
    again = scene.run(t_span=(0.0, 0.3), **kw)
    assert not short.switches and not again.switches
    assert np.array_equal(short.y, again.y) and np.array_equal(short.t, again.t)


def test_budget_counts_every_piece(scenes, monkeypatch):
    scene = scenes["sleigh"]
    kw = dict(method="dop853", rtol=1e-8, atol=1e-11, max_steps=12)
    want = _by_follow(scene, kw, monkeypatch)
    got = scene.run(**kw)
    got = scene.run(**kw)
    assert got.status == want.status and np.array_equal(got.y, want.y)


def test_the_record_holds_its_pieces(scenes):
    """The driver's record: the summary it returns (counts over the pieces, the switch
    times) is that of its rows ``I`` and ``F``, and ``B`` holds ``F``, ``TS``, ``YS`` one
    after the other (``chart_driver.unpacked``), the rows' first time and the run's
    last state among them."""
    from jetnh.numeric import chart_driver as cd

    scene = scenes["sleigh"]
    kw = dict(method="dop853", save="final", rtol=1e-8, atol=1e-11)
    scene.run(**kw)
    tr = scene.run(**kw)
    n_p, n_sw, n_rows, I, B = tr._segments._made[-1]
    n = len(scene.state_names)
    F, TS, YS = cd.unpacked((n_p, n_sw, n_rows, I, B), n)
    assert n_p >= 2 and n_sw == len(tr.switches) >= 1
    assert tr._counts[0] == tuple(I[:n_p, cd.C_STEPS:cd.C_NFEV + 1].sum(axis=0).tolist())
    assert [s["t"] for s in tr.switches] == F[:n_sw, cd.SW_T].tolist()
    assert I[:n_p, cd.C_ROWS].sum() == n_rows == TS.shape[0] == YS.shape[0]
    assert B.shape[0] == F.size + TS.size + YS.size and F.shape == (max(n_p, n_sw),
                                                                    cd.N_F + 3 * n)
    assert TS[0] == scene.t_span[0] and TS[-1] == tr.t[-1] == scene.t_span[1]
    assert np.array_equal(F[n_p - 1, cd.N_F + n:cd.N_F + 2 * n], YS[-1])
