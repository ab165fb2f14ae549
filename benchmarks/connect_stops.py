"""Shooting runs that cannot change split, stopped at the split's edge: Suslov's
equations (the paper's convention) for a sleigh in centre-of-mass coordinates with
dependent=[Y], whose split is singular at cos(th) = 0 (``tests/test_connect_stops.py``).

    .venv/bin/python benchmarks/connect_stops.py [--quick] [--out PATH]

(default output: benchmarks/results/connect_stops.json).  In one process, the calls
interleaved (``_common.best_of``), each figure the best of its repetitions, "crawl" =
the runs as they were (``Shooter.watch_edge = False``: the run goes on toward the
singular set until the loop finds it crawling), "edge" = as now (the plan watches the
split's edge as a terminal event, ``shooting.edge_event``):

- ``shot``: one shooting run with sensitivities (rtol 1e-11, connect's default) from
  the start with X_t = 0.8, th_t = 0.5: seconds and where it stopped;
- ``connect``: ``jn.connect`` (warm) to X = 1, th = 2.5 at T = 3, beyond the singular
  set: seconds to its ``ConnectError``, and its runs.
"""

from __future__ import annotations

import sys

import numpy as np

from _common import best_of, parser, write

PARAMS = {"m": 2.0, "I": 0.7, "a": 0.4}
START = {"X": 0.1, "Y": -0.2, "th": 0.3}
END = {"X": 1.0, "th": 2.5}


def sleigh():
    import sympy as sp

    import jetnh as jn

    J = jn.JetSpace("X Y th")
    _, _, th = J.q
    Xt, Yt, tht = J.qd
    m, inertia, a = sp.symbols("m I a", positive=True)
    L = m / 2 * (Xt**2 + Yt**2) + inertia / 2 * tht**2
    return jn.System(J, L, [-sp.sin(th) * Xt + sp.cos(th) * Yt - a * tht],
                     dependent=[J.q[1]])


def shooter(system, watch_edge):
    from jetnh.numeric.connect.problem import Unknowns, _scene
    from jetnh.numeric.connect.solve import Search

    shape = Unknowns.of(system, "suslov")
    scene = _scene(system, "suslov", PARAMS,
                   {**START, **{u: 0.0 for u in shape.unknowns}, **shape.fixed}, (0.0, 3.0))
    sh = Search(scene, START, END, shape.unknowns, shape.fixed, 1e-11, 1e-12, "dop853",
                1e-9)
    sh.watch_edge = watch_edge
    return sh


def shot_case(system, reps):
    u = np.array([0.8, 0.5])
    shooters = {"crawl": shooter(system, False), "edge": shooter(system, True)}

    def one(sh):
        def go():
            sh.stops.clear()
            assert sh.run(u) is None
            kind = "crawl" if "crawl" in sh.last_stops else next(iter(sh.last_stops))
            return float(sh.last_stops[kind][0]), str(kind)
        return go

    timed = best_of([one(sh) for sh in shooters.values()], reps)
    out = {name: {"seconds": s, "stopped_at_t": r[0], "stop": r[1]}
           for name, (s, r) in zip(shooters, timed)}
    out["crawl_over_edge"] = out["crawl"]["seconds"] / out["edge"]["seconds"]
    return out


def connect_case(system, reps):
    import jetnh as jn
    from jetnh.errors import ConnectError
    from jetnh.numeric.connect.shooting import Shooter

    def one(watch):
        def go():
            Shooter.watch_edge = watch
            try:
                jn.connect(system, "suslov", START, END, (0.0, 3.0), params=PARAMS,
                           timeout=300)
            except ConnectError as e:
                return str(e)
            finally:
                Shooter.watch_edge = True
            raise AssertionError("the end beyond cos(th) = 0 was reached")
        return go

    one(False)(), one(True)()           # warm: scenes, kernels, plans
    timed = best_of([one(False), one(True)], reps)
    out = {name: {"seconds": s, "message": msg[:400]}
           for name, (s, msg) in zip(("crawl", "edge"), timed)}
    out["crawl_over_edge"] = out["crawl"]["seconds"] / out["edge"]["seconds"]
    return out


def main():
    ap = parser(__doc__, "connect_stops")
    args = ap.parse_args()
    system = sleigh()
    data = {"shot": shot_case(system, 3 if args.quick else 10),
            "connect": connect_case(system, 1 if args.quick else 3)}
    for name, r in data.items():
        print(f"{name}: crawl {r['crawl']['seconds'] * 1e3:.1f} ms, edge "
              f"{r['edge']['seconds'] * 1e3:.2f} ms ({r['crawl_over_edge']:.0f}x)")
    write("connect_stops", data, args.out, args.quick)


if __name__ == "__main__":
    sys.exit(main())
