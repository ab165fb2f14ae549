"""Sweeps: every row is the single run of its point, bit for bit; the same DataFrame on a
real 2-worker Dask LocalCluster (processes, loopback), also when a worker is killed
mid-sweep; failing points keep their rows; the error paths; the map; the CLI."""

import csv
import logging
import os
import signal
import socket
import subprocess
import sys

import numpy as np
import pandas as pd
import pytest
import sympy as sp

import jetnh as jn
from jetnh.errors import JetnhError
from jetnh.models import appell_hamel, rolling_disk
from jetnh.numeric import Event, Scene
from jetnh.numeric.methods._common import FINISHED, NONFINITE, SINGULAR
from jetnh.sweep import plot_map, separation

DISK0 = dict(x=0.1, y=-0.2, phi=0.3, psi=0.4, phi_t=1.0, psi_t=0.7)
GRID = {"R": [0.5, 1.0, 2.0], "phi_t": [0.25, 0.5, 1.0, 1.5]}
DASK = dict(timeout=120)                  # a broken cluster fails the test, never hangs
# no dashboard; the scheduler's HTTP server (health routes) on a free loopback port
NO_DASHBOARD = dict(dashboard_address=None, scheduler_kwargs={"dashboard_address": "127.0.0.1:0"})


def assert_same(a, b):
    pd.testing.assert_frame_equal(a, b, check_exact=True)
    assert a.attrs == b.attrs


@pytest.fixture(scope="module")
def disk():
    """The rolling disk with R at run time and p_psi = I2 psi_t as a first integral;
    kernels out of the disk cache, so Dask workers install the shipped source."""
    s = rolling_disk()
    I2, psi_t = sp.Symbol("I2"), s.J.qd[3]
    return Scene(s, "chetaev", initial=DISK0, t_span=(0.0, 5.0), runtime_params=["R"],
                 integrals={"p_psi": I2 * psi_t}, cache=False).compile()


@pytest.fixture(scope="module")
def failing():
    """Appell-Hamel (singular where the horizontal speed vanishes: at t0 for zero speed,
    later for small speeds) and a blow-up exp(c x) whose NaN no indicator explains."""
    ah = Scene(appell_hamel(), "chetaev", initial=dict(x=0, y=0, z=0, x_t=0.6, y_t=0.8),
               t_span=(0.0, 0.5))
    J = jn.JetSpace("x y")
    x, _ = J.q
    xd, yd = J.qd
    c = sp.Symbol("c")
    s = jn.System(J, (xd**2 + yd**2) / 2 + sp.exp(c * x), [yd - xd], dependent=[J.q[1]])
    blow = Scene(s, "chetaev", params={"c": 0.0}, initial=dict(x=1.0, y=0.0, x_t=1.0),
                 t_span=(0.0, 1.0))
    return ah, blow


@pytest.fixture(scope="module")
def client():
    pytest.importorskip("distributed")
    from distributed import Client, LocalCluster

    with LocalCluster(n_workers=2, processes=True, threads_per_worker=1, host="127.0.0.1",
                      silence_logs=logging.CRITICAL, **NO_DASHBOARD) as cluster:
        with Client(cluster) as c:
            yield c


# ---------------------------------------------------------------------- this machine
def test_rows_are_the_single_runs(disk):
    df = jn.sweep(disk, {sp.Symbol("R"): GRID["R"], disk.system.J.qd[2]: GRID["phi_t"]},
                  rtol=1e-10, atol=1e-12)
    assert list(df.columns[:2]) == df.attrs["grid"] == ["R", "phi_t(t0)"]
    assert len(df) == 12
    # the Cartesian product, the last key fastest
    assert np.array_equal(df["R"], np.repeat(GRID["R"], 4))
    assert np.array_equal(df["phi_t(t0)"], np.tile(GRID["phi_t"], 3))
    names = ["x", "y", "phi", "psi", "phi_t", "psi_t", "x_t", "y_t", "p_psi"]
    assert list(df.columns[2:11]) == names
    assert list(df.columns[11:]) == ["status", "success", "stop_reason", "t_final", "steps",
                                     "rejected", "rhs_evaluations", "residual_max",
                                     "energy_drift", "drift[p_psi]"]
    for r in (0, 5, 11):
        y0 = disk.y0.copy()
        y0[disk.state_names.index("phi_t")] = df["phi_t(t0)"][r]
        tr = disk.run(rtol=1e-10, atol=1e-12, y0=y0, params=np.array([df["R"][r]]),
                      save="final")
        assert [df[n][r] for n in names] == [tr.final[n] for n in names]    # to the bit
        d = tr.diagnostics
        assert (df["steps"][r], df["rhs_evaluations"][r]) == (d.steps, d.rhs_evaluations)
        assert df["stop_reason"][r] == d.stop_reason and df["t_final"][r] == 5.0
        # over the stored rows (t0 and the final one): |E(t_final) - E(t0)|
        e = tr.energy
        assert df["energy_drift"][r] == pytest.approx(abs(e[-1] - e[0]), rel=1e-9, abs=1e-15)
    # and the closed form x = x0 + R phidot/psidot (sin psi - sin psi0)
    x = 0.1 + df["R"] * df["phi_t(t0)"] / 0.7 * (np.sin(0.4 + 3.5) - np.sin(0.4))
    assert np.max(np.abs(df["x"] - x)) < 1e-8
    assert (df["status"] == FINISHED).all() and df["success"].all()
    assert (df["residual_max"] < 1e-12).all() and (df["drift[p_psi]"] < 1e-12).all()


def test_times_outputs_points_and_dataframe_grids(disk):
    prod = jn.sweep(disk, GRID, times=[1.0, 2.5], outputs=["x", sp.Symbol("psi")])
    assert list(prod.columns[:6]) == ["R", "phi_t(t0)", "x(t=1)", "x(t=2.5)", "psi(t=1)",
                                      "psi(t=2.5)"]
    y0 = disk.y0.copy()
    y0[disk.state_names.index("phi_t")] = 1.5
    tr = disk.run(t_eval=[1.0, 2.5], y0=y0, params=np.array([2.0]))
    assert list(prod.iloc[-1][["x(t=1)", "x(t=2.5)"]]) == list(tr["x"])
    # the same points as a list and as a DataFrame: the same rows
    rows = [{"R": r, "phi_t": p} for r in GRID["R"] for p in GRID["phi_t"]]
    for grid in (rows, pd.DataFrame(rows)):
        assert_same(jn.sweep(disk, grid, times=[1.0, 2.5], outputs=["x", "psi"]), prod)
    # a chunked run with progress reports gives the same bits
    seen = []
    chunked = jn.sweep(disk, GRID, times=[1.0, 2.5], outputs=["x", "psi"], chunk_size=5,
                       progress=lambda done, total: seen.append((done, total)))
    assert_same(chunked, prod)
    assert seen == [(5, 12), (10, 12), (12, 12)]


def test_event_columns(disk):
    psi = disk.system.J.q[3]
    ev = [Event(sp.sin(psi), name="sin psi")]
    df = jn.sweep(disk, {"psi_t": [0.3, 0.7]}, events=ev)
    assert list(df.columns[-2:]) == ["events[sin psi]", "first[sin psi]"]
    y0 = disk.y0.copy()
    y0[disk.state_names.index("psi_t")] = 0.7
    tr = disk.run(y0=y0, params=disk.p, events=ev, save="final")
    assert df["events[sin psi]"][1] == len(tr.t_events[0]) > 0
    assert df["first[sin psi]"][1] == tr.t_events[0][0]


def test_failing_points_keep_their_rows(failing):
    ah, blow = failing
    df = jn.sweep(ah, {"x_t": [0.0, 3.0], "y_t": [0.0, 1.0]})
    assert list(df["status"]) == [SINGULAR, SINGULAR, FINISHED, FINISHED]
    assert list(df["success"]) == [False, False, True, True]
    assert "the initial state (t = 0) is singular" in df["stop_reason"][0]
    assert "x_t**2 + y_t**2 fell to" in df["stop_reason"][1] and 0 < df["t_final"][1] < 0.5
    assert df["stop_reason"][2] == "reached the end of the interval"
    df = jn.sweep(blow, {"c": [0.0, 800.0]})
    assert list(df["status"]) == [FINISHED, NONFINITE]
    assert df["stop_reason"][1] == "the state or the right-hand side became NaN or infinite"
    assert np.isnan(df["x"][1]) and df["x"][0] == pytest.approx(2.0, rel=1e-12)


def test_failed_point_methods_report_their_steps(failing):
    """A dla or scipy point that fails keeps the counts of the run up to its stop: dla's
    steps are those of the same steps run to just before the failing one."""
    _, blow = failing
    df = jn.sweep(blow, {"c": [0.0, 3.0]}, method="dla", n_steps=200)
    assert list(df["status"]) == [FINISHED, NONFINITE]
    steps, t_stop = int(df["steps"][1]), df["t_final"][1]
    assert 0 < steps < 200 and t_stop == pytest.approx(steps / 200, rel=1e-12)
    before = blow.replace(params={"c": 3.0}, t_span=(0.0, t_stop)).run(method="dla",
                                                                        n_steps=steps)
    assert before.success and before.diagnostics.steps == steps
    assert df["rhs_evaluations"][1] > before.diagnostics.rhs_evaluations
    df = jn.sweep(blow, {"c": [800.0]}, method="scipy-RK45")
    assert df["status"][0] == NONFINITE and np.isnan(df["steps"][0])   # scipy: not counted
    assert df["t_final"][0] == 0.0 and df["rhs_evaluations"][0] == 1


@pytest.mark.parametrize("grid, options, words", [
    ({"Q": [1.0]}, {}, "neither a parameter (R, I1, I2) nor a state"),
    ({}, {}, "the grid is empty"),
    ({"R": []}, {}, "are empty"),
    ([], {}, "no points"),
    ([{"R": 1.0}, {"R": 2.0, "phi_t": 1.0}], {}, "point 1 has keys"),
    ({"R": [1.0, np.nan]}, {}, "non-finite"),
    ({"R": ["big"]}, {}, "must be numbers"),
    ({"R": [True, 2.0]}, {}, "grid values of 'R' must be a number, got True"),
    ({"R": np.array([False, True])}, {}, "grid values of 'R' must be a number, got False"),
    ({"R": np.True_}, {}, "grid values of 'R' must be a number, got True"),
    ([{"R": 1.0}, {"R": True}], {}, "grid point 1 must be a number, got True"),
    (pd.DataFrame({"R": [1.0, 2.0], "phi_t": [True, False]}), {},
     "grid values of 'phi_t' must be a number, got True"),
    (pd.DataFrame({"R": ["1.0"]}), {}, "strings are never parsed"),
    (pd.DataFrame({"R": [1.0, np.inf]}), {}, "non-finite"),
    (pd.DataFrame({"R": []}), {}, "the grid has no points"),
    (pd.DataFrame(index=range(3)), {}, "the grid has no columns"),
    ({"R": [[1.0, 2.0]]}, {}, "1-d sequence"),
    ({sp.Symbol("R"): [1.0], "R": [2.0]}, {}, "gives R twice"),
    ({"x_t": [1.0]}, {}, "a dependent velocity"),
    ({3: [1.0]}, {}, "grid keys are parameter or state names"),
    ("R=1:2:3", {}, "a mapping name -> values"),
    ({"R": [1.0]}, {"t_eval": [1.0]}, "no option 't_eval'"),
    ({"R": [1.0]}, {"times": [9.0]}, "within t_span"),
    ({"R": [1.0]}, {"times": []}, "times is empty"),
    ({"R": [1.0]}, {"outputs": ["nope"]}, "outputs ['nope']"),
    ({"R": [1.0]}, {"chunk_size": 0}, "chunk_size must be a positive integer"),
    ({"R": [1.0]}, {"client": 42}, "scheduler address, not int"),
])
def test_bad_input_is_named(disk, grid, options, words):
    with pytest.raises(JetnhError) as err:
        jn.sweep(disk, grid, **options)
    assert words in str(err.value)


def test_unreachable_scheduler_fails_within_the_timeout(disk):
    with socket.socket() as s:                  # a loopback port nobody listens on
        s.bind(("127.0.0.1", 0))
        port = s.getsockname()[1]
    with pytest.raises(JetnhError, match="cannot reach a Dask scheduler at 'tcp://127.0.0.1:"):
        jn.sweep(disk, GRID, client=f"tcp://127.0.0.1:{port}", connect_timeout=1.0)


def test_scheduler_without_workers_fails_within_the_timeout(disk):
    from distributed import LocalCluster

    with LocalCluster(n_workers=0, processes=True, host="127.0.0.1", **NO_DASHBOARD) as empty:
        with pytest.raises(JetnhError, match="has no workers"):
            jn.sweep(disk, GRID, client=empty.scheduler_address, connect_timeout=0.5)


def test_separation_and_map(disk, tmp_path):
    a = jn.sweep(disk, GRID)
    b = jn.sweep(disk.replace(t_span=(0.0, 4.0)), GRID)
    gap = separation(a, b, ["x", sp.Symbol("y")])
    assert np.array_equal(gap, np.sqrt((a["x"] - b["x"]) ** 2 + (a["y"] - b["y"]) ** 2))
    with pytest.raises(JetnhError, match="same grid"):
        separation(a, jn.sweep(disk, {"R": GRID["R"], "phi_t": [1, 2, 3, 4]}), ["x"])
    a.loc[4, "success"] = False                 # a failed point is drawn grey
    fig = plot_map(a, "R", "phi_t(t0)", gap, path=tmp_path / "map.png", log=True)
    drawn = fig.axes[0].collections[0].get_array()
    want = gap.to_numpy().reshape(3, 4).T.copy()     # rows: phi_t, columns: R
    assert drawn.mask[0, 1] and not drawn.mask.sum() - 1
    want[0, 1] = drawn[0, 1] = 0.0
    assert np.array_equal(np.asarray(drawn), want)
    with open(tmp_path / "map.png", "rb") as fh:
        assert fh.read(8) == b"\x89PNG\r\n\x1a\n"
    with pytest.raises(JetnhError, match="several rows share a point"):
        plot_map(pd.concat([a, a], ignore_index=True), "R", "phi_t(t0)", "x")


@pytest.mark.parametrize("method, options", [
    ("dla", dict(n_steps=200)),
    ("scipy-DOP853", dict(rtol=1e-10, atol=1e-12)),
])
def test_point_methods_are_the_single_runs(disk, method, options):
    """dla and scipy have no compiled ensemble: their rows are Scene.run at each point,
    with the columns of the ensemble methods; and they agree with dop853."""
    df = jn.sweep(disk, GRID, method=method, **options)
    ref = jn.sweep(disk, GRID, rtol=1e-10, atol=1e-12)
    assert list(df.columns) == list(ref.columns) and df.attrs == ref.attrs
    names = ["x", "y", "phi", "psi", "phi_t", "psi_t", "x_t", "y_t", "p_psi"]
    for r in (0, 7, 11):
        y0 = disk.y0.copy()
        y0[disk.state_names.index("phi_t")] = df["phi_t(t0)"][r]
        tr = disk.run(method=method, y0=y0, params=np.array([df["R"][r]]), save="final",
                      **options)
        assert [df[n][r] for n in names] == [tr.final[n] for n in names]    # to the bit
        d = tr.diagnostics
        # over the output row (the final one), against the start, whatever rows it stored
        assert df["residual_max"][r] == np.max(np.abs(tr.residual[-1]))
        assert df["drift[p_psi]"][r] == abs(tr["p_psi"][-1] - tr["p_psi"][0])
        assert df["energy_drift"][r] == abs(tr.energy[-1] - tr.energy[0])
        assert df["stop_reason"][r] == d.stop_reason
        if d.steps is None:     # scipy does not count its steps: unknown, not 0
            assert np.isnan(df["steps"][r]) and np.isnan(df["rejected"][r])
        else:
            assert (df["steps"][r], df["rejected"][r]) == (d.steps, d.rejected)
    assert df["steps"].dtype == (np.float64 if method.startswith("scipy") else np.int64)
    assert df["success"].all()
    # second order (dla, 200 steps) or 1e-10 (scipy) against dop853
    tol = 1e-3 if method == "dla" else 1e-7
    assert np.max(np.abs(df[["x", "y"]].to_numpy() - ref[["x", "y"]].to_numpy())) < tol


def test_energy_drift_has_one_definition_on_every_route():
    """energy_drift over the output rows against E(t0) whether the point ran as a compiled
    ensemble (dop853) or as Scene.run (scipy-DOP853, which stores every step): an
    end-point difference without times, the largest over the times with them (t0 not
    among them), each against the rows of single runs."""
    J = jn.JetSpace("x y z")
    x, y, _ = J.q
    xd, yd, zd = J.qd
    L = (xd**2 + yd**2 + zd**2) / 2 - (x**2 + y**2) / 2
    sc = Scene(jn.System(J, L, [zd - y * xd], dependent=[J.q[2]]), "chetaev",
               initial=dict(x=0.3, y=0.8, z=0.0, x_t=0.5, y_t=-0.2), t_span=(0.0, 20.0))
    opts, times = dict(rtol=1e-4, atol=1e-6), [1.0, 2.5, 20.0]
    steps = sc.run(method="scipy-DOP853", **opts)
    e0 = steps.energy[0]
    for method in ("dop853", "scipy-DOP853"):
        end = sc.run(method=method, save="final", **opts).energy[-1]
        at = sc.run(method=method, t_eval=times, **opts).energy
        df = jn.sweep(sc, {"x_t": [0.5]}, method=method, **opts)
        assert df["energy_drift"][0] == abs(end - e0)
        df = jn.sweep(sc, {"x_t": [0.5]}, method=method, times=times, **opts)
        assert df["energy_drift"][0] == np.max(np.abs(at - e0))
    # (the largest over scipy's steps is another figure: the single run's own)
    assert steps.diagnostics.energy_drift > abs(steps.energy[-1] - e0)


def test_point_methods_times_and_their_limits(disk):
    times = [1.0, 2.5]
    df = jn.sweep(disk, {"R": [0.5, 2.0]}, method="scipy-RK45", times=times, outputs=["x"])
    tr = disk.run(method="scipy-RK45", t_eval=times, params=np.array([2.0]))
    assert list(df.iloc[1][["x(t=1)", "x(t=2.5)"]]) == list(tr["x"])
    with pytest.raises(JetnhError, match="times needs dense output, which dla"):
        jn.sweep(disk, {"R": [1.0]}, method="dla", n_steps=10, times=[1.0])
    with pytest.raises(JetnhError, match="projection: an option of the dla method"):
        jn.sweep(disk, {"R": [1.0]}, projection=True)
    with pytest.raises(JetnhError, match="newton_tol and max_newton are options of radau"):
        jn.sweep(disk, {"R": [1.0]}, newton_tol=1e-12)


def test_point_methods_keep_failing_rows(failing):
    _, blow = failing
    for method, options in (("scipy-RK45", {}), ("dla", {"n_steps": 100})):
        df = jn.sweep(blow, {"c": [0.0, 800.0]}, method=method, **options)
        assert list(df["status"]) == [FINISHED, NONFINITE], method
        assert list(df["success"]) == [True, False] and np.isnan(df["x"][1])
        assert df["x"][0] == pytest.approx(2.0, rel=1e-12)
        assert method in df["stop_reason"][1]


def test_dvi_sweeps_the_vakonomic_disk():
    """dvi (second order, variational) against dop853 on a vakonomic grid."""
    scene = Scene(rolling_disk(), "vakonomic", initial=dict(DISK0, lambda_x=0.1, lambda_y=0.0),
                  t_span=(0.0, 2.0))
    grid = {"R": [0.5, 1.0], "psi_t": [0.2, 0.7]}
    dvi = jn.sweep(scene, grid, method="dvi", n_steps=800)
    ref = jn.sweep(scene, grid, rtol=1e-11, atol=1e-12)
    assert dvi["success"].all() and (dvi["steps"] == 800).all()
    assert np.max(np.abs(dvi[["x", "y"]].to_numpy() - ref[["x", "y"]].to_numpy())) < 1e-4


def test_progress_true_is_a_tqdm_bar(disk, capsys):
    df = jn.sweep(disk, GRID, progress=True)
    err = capsys.readouterr().err
    assert len(df) == 12 and "sweep" in err and "12/12" in err
    with pytest.raises(JetnhError, match="progress is None, True or a callable"):
        jn.sweep(disk, GRID, progress="yes")


def test_import_is_light_and_jetnh_sweep_is_the_callable_module():
    code = ("import sys, jetnh\n"
            "heavy = [m for m in ('pandas', 'distributed', 'numba', 'matplotlib') "
            "if m in sys.modules]\n"
            "import jetnh.sweep\n"
            "from jetnh.sweep import plot_map\n"
            "print(heavy, callable(jetnh.sweep), jetnh.sweep is sys.modules['jetnh.sweep'])")
    r = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True,
                       timeout=120)
    assert r.stdout.strip() == "[] True True", r.stderr


# ---------------------------------------------------------------------- Dask
def kernels_on_worker(key):
    from jetnh.numeric.kernels import loader

    kern = loader._LOADED[(key, False)]
    return kern.hit, sorted(kern.timings)


def test_dask_equals_local_to_the_bit(disk, failing, client):
    for kw in ({}, dict(times=[0.5, 5.0], chunk_size=1)):
        local = jn.sweep(disk, GRID, **kw)
        assert_same(jn.sweep(disk, GRID, client=client, **kw, **DASK), local)
    # the workers installed the shipped kernel source: nothing derived there
    got = client.run(kernels_on_worker, disk.key)
    assert list(got.values()) == [(False, ["write"])] * 2
    # a scheduler address: the sweep connects and closes its own client
    ah, blow = failing
    grid = {"x_t": [0.0, 3.0], "y_t": [0.0, 1.0]}
    assert_same(jn.sweep(ah, grid, client=client.scheduler.address, **DASK),
                jn.sweep(ah, grid))
    assert_same(jn.sweep(blow, {"c": [0.0, 800.0]}, client=client, **DASK),
                jn.sweep(blow, {"c": [0.0, 800.0]}))


def test_killed_worker_loses_no_rows(disk, client):
    slow = disk.replace(t_span=(0.0, 100.0))   # ~1 ms a point: chunks of 20 take a while
    grid = {"R": np.linspace(0.5, 2.0, 16), "phi_t": np.linspace(0.2, 1.5, 20)}
    opts = dict(rtol=1e-12, atol=1e-14, chunk_size=20)
    local = jn.sweep(slow, grid, **opts)
    killed = {}

    def kill_a_busy_worker(done, total):
        busy = [w for w, keys in client.processing().items() if keys]
        if killed or not busy:          # (none busy between two chunks: the next report)
            return
        pid = client.run(os.getpid, workers=busy[:1])[busy[0]]
        os.kill(pid, signal.SIGKILL)
        killed.update(pid=pid, done=done, total=total)

    df = jn.sweep(slow, grid, client=client, progress=kill_a_busy_worker, **opts, **DASK)
    assert killed["done"] < killed["total"] == 320       # killed mid-sweep, while busy
    assert killed["pid"] not in client.run(os.getpid).values()
    assert_same(df, local)


def test_dask_timeout_is_an_error(disk, client):
    slow = disk.replace(t_span=(0.0, 100.0))
    with pytest.raises(JetnhError, match=r"did not finish within timeout=0.01 s \(\d+ of 320"):
        jn.sweep(slow, {"R": np.linspace(0.5, 2.0, 16), "phi_t": np.linspace(0.2, 1.5, 20)},
                 client=client, rtol=1e-12, atol=1e-14, chunk_size=20, timeout=0.01)


# ---------------------------------------------------------------------- command line
def cli(capsys, *args):
    from jetnh.cli import main

    try:
        code = main(list(args))
    except SystemExit as exc:
        code = exc.code
    out, err = capsys.readouterr()
    return code, out, err


def test_cli_sweep_files_map_and_scheduler(disk, client, capsys, tmp_path):
    args = ["sweep", "rolling_disk", "--grid", "R=0.5:2:4", "--grid", "phi_t=0.5,1,1.5",
            "--init", "psi_t=0.5", "--t-end", "5"]
    code, _, err = cli(capsys, *args, "--out", str(tmp_path / "a.csv"), "--plot",
                       str(tmp_path / "a.png"), "--value", "x")
    assert code == 0, err
    assert "jetnh: sweeping on this machine: 12/12 points" in err
    assert "12 points, 12 succeeded" in err
    scene = Scene(rolling_disk(), "chetaev", initial=dict(DISK0, psi_t=0.5), t_span=(0, 5))
    api = jn.sweep(scene, {"R": np.linspace(0.5, 2.0, 4), "phi_t": [0.5, 1.0, 1.5]})
    with open(tmp_path / "a.csv", newline="") as fh:       # float(): the exact numbers
        rows = list(csv.DictReader(fh))
    assert list(rows[0]) == list(api.columns)
    for c in ("R", "phi_t(t0)", "x", "y", "residual_max", "steps"):
        assert np.array_equal([float(r[c]) for r in rows], api[c])
    assert [r["stop_reason"] for r in rows] == list(api["stop_reason"])
    with open(tmp_path / "a.png", "rb") as fh:
        assert fh.read(4) == b"\x89PNG"
    code, _, err = cli(capsys, *args, "--scheduler", client.scheduler.address, "--timeout",
                       "120", "--out", str(tmp_path / "a.parquet"))
    assert code == 0, err
    assert f"sweeping on the Dask cluster at {client.scheduler.address}: 12/12" in err
    assert_same(pd.read_parquet(tmp_path / "a.parquet"), api)     # attrs (the grid) too


def test_cli_point_methods(capsys):
    """--method takes every method of Scene.run; --steps sets the fixed-step ones."""
    base = ["sweep", "rolling_disk", "--grid", "R=0.5,1", "--t-end", "1", "--outputs", "x"]
    scene = Scene(rolling_disk(), "chetaev", initial=DISK0, t_span=(0, 1))
    code, out, err = cli(capsys, *base, "--method", "dla", "--steps", "50")
    assert code == 0, err
    api = jn.sweep(scene, {"R": [0.5, 1.0]}, outputs=["x"], method="dla", n_steps=50)
    assert [float(r.split(",")[1]) for r in out.splitlines()[1:]] == list(api["x"])
    vk = ["--init", "lambda_x=0.1", "-p", "vakonomic"]
    code, out, err = cli(capsys, *base, *vk, "--method", "dvi", "--steps", "50")
    assert code == 0 and out.count("\n") == 3, err
    code, _, err = cli(capsys, *base, "--method", "scipy-Radau")
    assert code == 0, err


@pytest.mark.parametrize("args, code, words", [
    (("--grid", "R=0.5:2"), 2, "neither A:B:N"),
    (("--grid", "R=0.5:2:x"), 2, "neither A:B:N"),
    (("--grid", "R=1,two"), 2, "neither A:B:N"),
    (("--grid", "R"), 2, "--grid takes NAME=A:B:N"),
    (("--grid", "R=1", "--grid", "R=2"), 2, "gives R twice"),
    (("--grid", "R=1", "--plot", "m.png"), 2, "exactly two --grid and a --value"),
    (("--grid", "Q=1"), 1, "neither a parameter"),
    (("--grid", "R=1", "--out", "table.xlsx"), 1, "give a .csv or .parquet path"),
    (("--grid", "R=1", "--scheduler", "tcp://127.0.0.1:9", "--connect-timeout", "0.5"), 1,
     "cannot reach a Dask scheduler"),
    (("--grid", "R=1", "--method", "dla", "--times", "0.5"), 2, "--times needs dense output"),
    (("--grid", "R=1", "--method", "dvi", "--steps", "0", "-p", "vakonomic"), 1,
     "--steps must be a positive integer"),
    (("--grid", "R=1", "--method", "euler"), 1, "unknown method 'euler'"),
])
def test_cli_errors(capsys, args, code, words):
    got, _, err = cli(capsys, "sweep", "rolling_disk", "--t-end", "1", *args)
    assert got == code and words in err and "Traceback" not in err, err


def test_without_dask_local_sweeps_run_and_cluster_ones_name_the_extra(disk, capsys,
                                                                      monkeypatch):
    """dask is the 'cluster' extra: a local sweep never imports it; a client or
    --scheduler without it is a JetnhError naming pip install 'jetnh[cluster]'."""
    for mod in ("dask", "distributed"):
        monkeypatch.setitem(sys.modules, mod, None)       # import dask -> ImportError
    df = jn.sweep(disk, {"R": [0.5, 1.0]})
    assert list(df["R"]) == [0.5, 1.0] and df["success"].all()
    with pytest.raises(JetnhError, match=r"pip install 'jetnh\[cluster\]'"):
        jn.sweep(disk, {"R": [0.5, 1.0]}, client="tcp://127.0.0.1:9")
    got, _, err = cli(capsys, "sweep", "rolling_disk", "--t-end", "1", "--grid", "R=1",
                      "--scheduler", "tcp://127.0.0.1:9")
    assert got == 1 and "pip install 'jetnh[cluster]'" in err and "Traceback" not in err


def test_cli_parquet_needs_pyarrow(capsys, monkeypatch, tmp_path):
    monkeypatch.setitem(sys.modules, "pyarrow", None)
    got, _, err = cli(capsys, "sweep", "rolling_disk", "--t-end", "1", "--grid", "R=1",
                      "--out", str(tmp_path / "a.parquet"))
    assert got == 1 and "pip install 'jetnh[parquet]'" in err
