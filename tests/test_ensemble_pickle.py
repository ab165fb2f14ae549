"""An Ensemble survives pickling (results sent through multiprocessing or dask): every
field and named column equal, every array read-only and the ensemble immutable after
unpickling, its aux rows evaluated in a fresh process from its scene's kernels."""

import os
import pickle
import subprocess
import sys
import textwrap

import numpy as np
import pytest

import jetnh as jn
from jetnh.errors import FrozenError
from jetnh.models import knife_edge
from jetnh.numeric import Event
from jetnh.numeric.methods._common import EVENT, NONFINITE, SINGULAR
from jetnh.mechanics.system import System

TE = np.linspace(0.0, 3.0, 7)


@pytest.fixture(scope="module")
def knife():
    return jn.Scene(knife_edge(), "chetaev", initial=dict(x=0, y=0, phi=0, x_t=0.5, phi_t=3.0),
                    t_span=(0.0, 3.0))


@pytest.fixture(scope="module")
def runs(knife):
    x = knife.system.J.q[0]
    ini = {"phi_t": [3.0, 2.0, 1.0]}
    J = jn.JetSpace("x")
    (q,), (qd,) = J.q, J.qd
    blow = jn.Scene(System(J, qd**2 / 2 + q**4 / 4, []), "chetaev",
                    initial=dict(x=1.0, x_t=0.1), t_span=(0.0, 5.0))
    return {
        "switching": knife.ensemble(ini, t_eval=TE),
        "final": knife.ensemble(ini, save="final", parallel="serial"),
        "singular": knife.ensemble(ini, t_eval=TE, split="fixed", parallel="prange"),
        "one": knife.ensemble({"phi_t": [3.0]}, split="fixed"),
        "one, t_eval": knife.ensemble({"phi_t": [2.0]}, t_eval=TE[:3], split="fixed"),
        "event": knife.ensemble(ini, t_eval=TE, split="fixed",
                                events=[Event(x - 0.05, terminal=True)]),
        "sensitivities": knife.ensemble(ini, t_eval=TE[:2], sensitivities=True,
                                        split="fixed"),
        "nonfinite": blow.ensemble({"x": [0.0, 1.0], "x_t": [0.0, 3.0]}, method="rk4",
                                   n_steps=50, on_error="record"),
    }


FIELDS = ("t", "y", "status", "steps", "rejected", "nfev", "rows", "t_final", "y_final",
          "event_counts", "event_first", "initial", "params", "success", "names",
          "state_names", "event_names", "param_names", "method", "save", "parallel",
          "workers", "wall_time", "switching", "switches", "sensitivity_columns", "aux",
          "aux_initial", "residual_max", "energy_drift", "holonomic_residual_max",
          "stop_reasons")


def _same(a, b):
    """Equal values, NaN equal to NaN, through dicts, lists and tuples."""
    if isinstance(a, dict):
        return isinstance(b, dict) and a.keys() == b.keys() and all(_same(a[k], b[k])
                                                                  for k in a)
    if isinstance(a, (list, tuple)):
        return len(a) == len(b) and all(_same(x, y) for x, y in zip(a, b))
    if isinstance(a, np.ndarray) or isinstance(b, np.ndarray):
        a, b = np.asarray(a), np.asarray(b)
        return a.dtype == b.dtype and np.array_equal(a, b, equal_nan=True)
    if isinstance(a, float) and isinstance(b, float):
        return a == b or (a != a and b != b)
    return a == b


def test_every_field_survives_pickling_read_only(runs):
    statuses = {k: set(e.status.tolist()) for k, e in runs.items()}
    assert SINGULAR in statuses["singular"] and SINGULAR in statuses["one"]
    assert EVENT in statuses["event"] and NONFINITE in statuses["nonfinite"]
    assert runs["switching"]._pieces and runs["switching"].switches
    for kind, ens in runs.items():
        back = pickle.loads(pickle.dumps(ens))
        for name in FIELDS:
            assert _same(getattr(ens, name), getattr(back, name)), (kind, name)
        for name in ens.names:
            assert _same(ens[name], back[name]), (kind, name)
        assert _same(ens.diagnostics(), back.diagnostics()), kind
        assert _same(ens.final_values(), back.final_values()), kind
        assert back.layout == ens.layout and back.scene.state_names == ens.scene.state_names
        if kind == "sensitivities":
            assert _same(back.sensitivities, ens.sensitivities)
            assert _same(back.sensitivity("x", "phi_t"), ens.sensitivity("x", "phi_t"))
        arrays = [back.t, back.y, back.status, back.t_final, back.y_final, back.initial,
                  back.params, back.event_counts, back.event_first, back.aux,
                  back.aux_initial, *(back[n] for n in back.names),
                  *back.final_values().values()]
        assert not any(a.flags.writeable for a in arrays), kind
        with pytest.raises(FrozenError):
            back.method = "x"
        with pytest.raises(FrozenError):
            back.status = 3
        # a pickle of the unpickled ensemble: the same again
        again = pickle.loads(pickle.dumps(back))
        assert _same(again.y, ens.y) and _same(again.aux, ens.aux), kind


def test_an_unpickled_ensemble_is_evaluated_in_a_fresh_process(knife, tmp_path):
    """The aux rows of unpickled ensembles (never evaluated before pickling: of three
    runs, of one) in a new process: their scene's kernels loaded again from the cache,
    bit for bit."""
    ens = [knife.ensemble(initial, t_eval=TE, split="fixed")
           for initial in ({"phi_t": [3.0, 2.0, 1.0]}, {"phi_t": [2.0]})]
    (tmp_path / "ens.pkl").write_bytes(pickle.dumps(ens))
    child = textwrap.dedent(f"""
        import pickle, numpy as np
        ens = pickle.loads(open({str(tmp_path / 'ens.pkl')!r}, 'rb').read())
        np.save({str(tmp_path / 'aux.npy')!r}, np.concatenate([e.aux for e in ens]))
        np.save({str(tmp_path / 'x_t.npy')!r}, np.concatenate([e["x_t"] for e in ens]))
    """)
    subprocess.run([sys.executable, "-c", child], check=True, env=dict(os.environ),
                   timeout=600)
    assert np.array_equal(np.load(tmp_path / "aux.npy"),
                          np.concatenate([e.aux for e in ens]), equal_nan=True)
    assert np.array_equal(np.load(tmp_path / "x_t.npy"),
                          np.concatenate([e["x_t"] for e in ens]), equal_nan=True)
