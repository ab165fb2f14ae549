"""Sweeps: this machine against a 2-worker Dask LocalCluster, and what more workers would give.

Points per second of ``jetnh.sweep`` on this machine (client=None: the ensemble's thread
pool on every core) and on Dask LocalClusters of 1 and 2 worker processes on loopback,
for the same grids, each DataFrame checked equal to the local one to the last bit; the
serial cost of a point in one process (the worker's own function, no Dask); the Dask
cost per task and per point; and, from these measured costs, the time per point with
more workers.  Also the map of the final-time separation between the vakonomic and the
Chetaev rolling disk over the initial multipliers, run on the cluster (zero on the
branch lambda = -p of the paper's (32)).

    .venv/bin/python benchmarks/sweep_dask.py [--quick] [--out PATH]

Writes benchmarks/results/sweep_dask.json and sweep_dask.png.  Best of several
repetitions, interleaved; the machine is shared (its load average is in the JSON), so
only figures measured in the same run are compared.
"""

import logging
import os
import pickle
import sys
import time
from importlib.metadata import version
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parent))
from _common import best, best_of, parser, write  # noqa: E402

import jetnh as jn  # noqa: E402
from jetnh.models import rolling_disk  # noqa: E402
from jetnh.numeric.ensemble import resolve  # noqa: E402
from jetnh.sweep import CompiledScene, _run_chunk, plot_map  # noqa: E402

DISK0 = dict(x=0.1, y=-0.2, phi=0.3, psi=0.4, phi_t=1.0, psi_t=0.7)


def workloads(quick):
    """(name, scene, grid, options): a cheap point and a costly one (rolling disk)."""
    s = rolling_disk()
    side = (20, 20) if quick else (40, 50)
    grid = {"R": np.linspace(0.5, 2.0, side[0]), "phi_t": np.linspace(0.2, 1.5, side[1])}
    t_heavy = 20.0 if quick else 50.0
    light = jn.Scene(s, "chetaev", initial=DISK0, t_span=(0.0, 5.0))
    heavy = jn.Scene(s, "vakonomic", initial=dict(DISK0, lambda_x=0.1, lambda_y=-0.2),
                     t_span=(0.0, t_heavy))
    return [("light: chetaev disk, t in [0, 5], rtol 1e-9", light, grid, {}),
            (f"heavy: vakonomic disk, t in [0, {t_heavy:g}], rtol 1e-12", heavy, grid,
             dict(rtol=1e-12, atol=1e-14))]


def serial_cost(scene, grid, options, reps):
    """Seconds per point of the worker's own function (``_run_chunk``, serial) in one
    process: the compute a Dask worker does, with no Dask around it; and the size in
    bytes of what goes once to each worker (the scene and its kernels' source)."""
    names = list(grid)
    values = np.array(np.meshgrid(*grid.values(), indexing="ij")).reshape(len(names), -1).T
    params = {k: values[:, j] for j, k in enumerate(names) if k in scene.params}
    states = {k: values[:, j] for j, k in enumerate(names) if k not in scene.params}
    sc, Y0, P = resolve(scene, states, params)
    run = dict(options, t_eval=None, save="final")
    t, _ = best(lambda: _run_chunk(sc, Y0, P, run, sc.kernels.layout.states, "serial"), reps)
    return t / len(Y0), len(pickle.dumps(CompiledScene(sc)))


def cluster(n_workers):
    from distributed import Client, LocalCluster

    logging.getLogger("distributed").setLevel(logging.ERROR)
    tic = time.perf_counter()
    lc = LocalCluster(n_workers=n_workers, processes=True, threads_per_worker=1,
                      host="127.0.0.1", dashboard_address=None, silence_logs=logging.ERROR,
                      scheduler_kwargs={"dashboard_address": "127.0.0.1:0"})  # a free port
    return lc, Client(lc), time.perf_counter() - tic


def _noop(i):
    return i


def noop_task_cost(client, reps):
    """Seconds per task of 200 no-op tasks: Dask's own floor on this machine."""
    from distributed import wait

    def run():
        futures = [client.submit(_noop, i, pure=False) for i in range(200)]
        wait(futures)
        client.gather(futures)
    return best(run, reps)[0] / 200


def per_task_fit(client, scene, grid, n, reps):
    """Wall time of one sweep against its number of tasks (2 to 200 chunks): the slope is
    the cost of a task on the critical path, the intercept the fixed cost of a sweep."""
    rows = []
    for tasks in (2, 8, 40, 200):
        size = -(-n // tasks)
        t, _ = best(lambda: jn.sweep(scene, grid, client=client, chunk_size=size), reps)
        rows.append(dict(chunk_size=size, tasks=-(-n // size), wall_s=t))
    slope, intercept = np.polyfit([r["tasks"] for r in rows], [r["wall_s"] for r in rows], 1)
    return dict(rows=rows, per_task_s=slope, fixed_s=intercept,
                noop_task_s=noop_task_cost(client, reps))


def scaling(row, fit):
    """Time per point with W workers from the measured costs: T(W)/n = c/W + (T0 + k tau)/n,
    c the serial cost of a point, tau the cost of a task at 2 workers (all of it taken as
    serial -- scheduler and client -- so it does not shrink with W), T0 the fixed cost and
    k the number of tasks: 4W with the default chunking, n/250 with chunks of 250 points
    (then Dask adds tau/250 per point whatever W)."""
    tau, t0 = fit["per_task_s"], max(fit["fixed_s"], 0.0)       # a fit may go below 0
    n, c = row["points"], row["serial_s_per_point"]
    workers = (1, 2, 4, 8, 16, 32, 64, 128)
    return dict(
        workload=row["workload"], tau_s=tau, fixed_s=t0,
        measured_s_per_point={1: row["dask_1_worker_s"] / n, 2: row["dask_2_workers_s"] / n},
        default_chunks_s_per_point={w: c / w + (t0 + 4 * w * tau) / n for w in workers},
        chunks_of_250_s_per_point={w: c / w + (t0 + n / 250 * tau) / n for w in workers},
        break_even_workers=dict(default_chunks=float(np.sqrt(n * c / (4 * tau))),
                                chunks_of_250=250 * c / tau))


def separation_map(client, path, quick):
    """Final (x, y) of the vakonomic disk over (lambda_x, lambda_y)(t0) against the
    Chetaev run, swept on the cluster and drawn by ``plot_map``."""
    s = rolling_disk()
    ref = jn.Scene(s, "chetaev", initial=DISK0, t_span=(0.0, 10.0)).run(
        rtol=1e-12, atol=1e-14, save="final").final
    vak = jn.Scene(s, "vakonomic", initial=dict(DISK0, lambda_x=0.0, lambda_y=0.0),
                   t_span=(0.0, 10.0))
    branch = (-np.cos(0.4), -np.sin(0.4))          # lambda = -p at t0 (R = 1, phi_t = 1)
    k = 21 if quick else 41
    grid = {"lambda_x": np.linspace(branch[0] - 1, branch[0] + 1, k),
            "lambda_y": np.linspace(branch[1] - 1, branch[1] + 1, k)}
    df = jn.sweep(vak, grid, client=client, rtol=1e-12, atol=1e-14)
    gap = np.hypot(df["x"] - ref["x"], df["y"] - ref["y"]).rename(
        "|(x, y) - Chetaev| at t = 10")
    fig = plot_map(df, "lambda_x(t0)", "lambda_y(t0)", gap, log=True,
                   title="rolling disk: vakonomic vs Chetaev (+: lambda = -p)")
    fig.axes[0].plot(*branch, "r+", ms=14)
    fig.savefig(path, dpi=120)
    at = int(np.argmin(gap))
    return dict(points=len(df), failed=int((~df["success"]).sum()),
                min_separation=float(gap[at]), branch=list(branch),
                at=[float(df["lambda_x(t0)"][at]), float(df["lambda_y(t0)"][at])],
                max_separation=float(gap.max()))


def main(argv=None):
    args = parser(__doc__, "sweep_dask").parse_args(argv)
    reps = 2 if args.quick else 4
    load0 = os.getloadavg()
    work = workloads(args.quick)
    for _, scene, grid, opts in work:              # compile, and warm the integrators
        jn.sweep(scene, {k: v[:2] for k, v in grid.items()}, **opts)
    c1, client1, _ = cluster(1)
    c2, client2, start = cluster(2)
    rows = []
    try:
        light, grid_l = work[0][1], work[0][2]
        tic = time.perf_counter()                  # cold workers: imports, kernels loaded
        jn.sweep(light, grid_l, client=client2)
        cold = time.perf_counter() - tic
        jn.sweep(light, grid_l, client=client1)
        for name, scene, grid, opts in work:
            n = int(np.prod([len(v) for v in grid.values()]))
            cost, shipped = serial_cost(scene, grid, opts, reps)
            (t_loc, local), (t_1, d1), (t_2, d2) = best_of([
                lambda: jn.sweep(scene, grid, **opts),
                lambda: jn.sweep(scene, grid, client=client1, **opts),
                lambda: jn.sweep(scene, grid, client=client2, **opts)], reps)
            rows.append(dict(
                workload=name, points=n, serial_s_per_point=cost, local_s=t_loc,
                dask_1_worker_s=t_1, dask_2_workers_s=t_2,
                local_points_per_s=n / t_loc, dask_1_worker_points_per_s=n / t_1,
                dask_2_workers_points_per_s=n / t_2, dask_2_workers_vs_local=t_loc / t_2,
                dask_1_worker_vs_local=t_loc / t_1,
                dask_overhead_s_per_point=(2 * t_2 - n * cost) / n,
                bitwise_equal=d1.equals(local) and d2.equals(local),   # exact, NaN = NaN
                shipped_once_per_worker_bytes=shipped))
            print({k: v for k, v in rows[-1].items() if "per_s" in k or k == "bitwise_equal"})
        n_l = rows[0]["points"]
        fits = {w: per_task_fit(c, light, grid_l, n_l, reps)
                for w, c in ((1, client1), (2, client2))}
        print({w: (f["per_task_s"], f["noop_task_s"], f["fixed_s"]) for w, f in fits.items()})
        png = args.out.with_suffix(".png")
        figure = separation_map(client2, png, args.quick)
    finally:
        for client, lc in ((client1, c1), (client2, c2)):
            client.close()
            lc.close()
    scale = scaling(rows[1], fits[2])
    heavy, light_row = rows[1], rows[0]
    write("sweep_dask", dict(
        title="Sweeps: this machine against a 2-worker Dask LocalCluster",
        summary=[
            f"Load average {load0[0]:.1f} at the start on {os.cpu_count()} cores"
            + (": the local run and the cluster shared the cores with other work, so both "
               "ran slower than on a free machine." if load0[0] > os.cpu_count() else "."),
            f"Every Dask DataFrame equals the local one to the last bit: "
            f"{all(r['bitwise_equal'] for r in rows)}.",
            f"Costly points ({heavy['serial_s_per_point'] * 1e3:.2f} ms each): local "
            f"{heavy['local_points_per_s']:.0f} points/s, 2 Dask workers "
            f"{heavy['dask_2_workers_points_per_s']:.0f} points/s "
            f"(x{heavy['dask_2_workers_vs_local']:.2f} of local), 1 worker "
            f"{heavy['dask_1_worker_points_per_s']:.0f}.",
            f"Cheap points ({light_row['serial_s_per_point'] * 1e6:.0f} us each): local "
            f"{light_row['local_points_per_s']:.0f} points/s, 2 Dask workers "
            f"{light_row['dask_2_workers_points_per_s']:.0f} "
            f"(x{light_row['dask_2_workers_vs_local']:.2f}): Dask's cost per task dominates.",
            f"Dask costs {fits[2]['per_task_s'] * 1e3:.1f} ms per task at 2 workers (a no-op "
            f"task {fits[2]['noop_task_s'] * 1e3:.1f} ms) and {scale['fixed_s'] * 1e3:.0f} ms "
            f"per sweep; per point of the costly grid (default chunks, 2 workers) "
            f"{heavy['dask_overhead_s_per_point'] * 1e6:.0f} us of worker time beyond the "
            f"compute.",
            f"Scaling (from these costs): with chunks of 250 points Dask adds "
            f"{fits[2]['per_task_s'] / 250 * 1e6:.0f} us per point whatever the number of "
            f"workers W, while the compute per point is c/W: for the costly points the two "
            f"meet (50% efficiency) at about {scale['break_even_workers']['chunks_of_250']:.0f}"
            f" workers; larger chunks move that further.",
            f"The vakonomic-Chetaev separation map: minimum {figure['min_separation']:.1e} at "
            f"lambda = {figure['at'][0]:.4f}, {figure['at'][1]:.4f} (the branch lambda = -p: "
            f"{figure['branch'][0]:.4f}, {figure['branch'][1]:.4f}).",
        ],
        columns=["workload", "points", "serial_s_per_point", "local_points_per_s",
                 "dask_1_worker_points_per_s", "dask_2_workers_points_per_s",
                 "dask_2_workers_vs_local", "dask_overhead_s_per_point", "bitwise_equal"],
        rows=rows,
        tables=[
            {"title": "Wall time of a sweep of the cheap grid against its number of tasks",
             "columns": ["workers", "chunk size", "tasks", "wall s"],
             "rows": [[w, r["chunk_size"], r["tasks"], r["wall_s"]]
                      for w, f in fits.items() for r in f["rows"]],
             "note": "; ".join(f"{w} worker(s): {f['per_task_s'] * 1e3:.2f} ms per task, "
                               f"fixed {f['fixed_s'] * 1e3:.0f} ms" for w, f in fits.items())},
            {"title": "Predicted seconds per point of the costly grid with W workers",
             "columns": ["W", "default chunks (4 per worker)", "chunks of 250"],
             "rows": [[w, scale["default_chunks_s_per_point"][w],
                       scale["chunks_of_250_s_per_point"][w]]
                      for w in scale["default_chunks_s_per_point"]],
             "note": "measured: " + ", ".join(f"W = {w}: {v:.3g} s"
                                              for w, v in scale["measured_s_per_point"].items())
                     + ". " + " ".join(scaling.__doc__.split())},
        ],
        figures=[png.name],
        cluster=dict(kind="LocalCluster, processes, 1 thread per worker, 127.0.0.1",
                     start_2_workers_s=start, first_sweep_cold_workers_s=cold),
        per_task=fits, scaling=scale, separation_map=figure, loadavg_start=list(load0),
        versions={p: version(p) for p in ("pandas", "dask", "distributed", "pyarrow")},
    ), args.out, args.quick)


if __name__ == "__main__":
    main()
