"""The transversality conditions of a free end (``connect.problem.Momenta``): one
evaluation of the values and their derivatives by the state, prepared once as a
straight line of float operations, against the walk over the shared graph it replaced
(``Momenta.walk``, ``dag.evaluate_numpy``); and a free-end connect with either.

    .venv/bin/python benchmarks/connect_momenta.py [--quick] [--out PATH]

(default output: benchmarks/results/connect_momenta.json).  In one process, the calls
interleaved (``_common.best_of``; a call's figure is the best mean of a batch of
calls): the rolling disk (vakonomic; end x, y, phi: psi free), the rolling coin
(vakonomic; end x, y: three free coordinates), and ``jn.connect`` on the disk's free
end (warm) with the prepared call and with the walk.
"""

from __future__ import annotations

import sys

import numpy as np

from _common import best_of, parser, write

DISK0 = {"x": 0.0, "y": 0.0, "phi": 0.0, "psi": 0.0}
DISK_END = {"x": 0.5, "y": 0.3, "phi": 0.2}


def momenta(model, principle, free):
    from jetnh.models import get, initial
    from jetnh.numeric.connect.problem import Momenta, Unknowns, _scene

    system = get(model)
    shape = Unknowns.of(system, principle)
    start = {c: float(v) for c, v in initial(model).items() if c in shape.coords}
    scene = _scene(system, principle, None,
                   {**start, **{u: 0.1 for u in shape.unknowns}, **shape.fixed}, (0.0, 1.0))
    return scene, Momenta(scene, free)


def call_case(model, principle, free, reps, batch):
    scene, m = momenta(model, principle, free)
    y = np.linspace(0.1, 0.8, len(scene.state_names))

    def timed(f):
        def go():
            for _ in range(batch):
                f(0.5, y)
            return f(0.5, y)
        return go

    (t_line, a), (t_walk, b) = best_of([timed(m), timed(m.walk)], reps)
    return {"free": list(m.free), "prepared_us": t_line / (batch + 1) * 1e6,
            "walk_us": t_walk / (batch + 1) * 1e6, "walk_over_prepared": t_walk / t_line,
            "max_difference": float(max(np.abs(a[0] - b[0]).max(), np.abs(a[1] - b[1]).max()))}


def connect_case(reps):
    import jetnh as jn
    from jetnh.models import get
    from jetnh.numeric.connect.problem import Momenta

    disk = get("rolling_disk")
    prepared = Momenta.__call__

    def one(walk):
        def go():
            if walk:
                Momenta.__call__ = Momenta.walk
            try:
                return jn.connect(disk, "vakonomic", DISK0, DISK_END, (0.0, 1.0))
            finally:
                Momenta.__call__ = prepared
        return go

    one(False)(), one(True)()
    (t_line, c), (t_walk, d) = best_of([one(False), one(True)], reps)
    return {"prepared_s": t_line, "walk_s": t_walk, "walk_over_prepared": t_walk / t_line,
            "iterations": c.iterations, "residual": c.residual,
            "initial_difference": max(abs(c.initial[k] - d.initial[k]) for k in c.initial)}


def main():
    ap = parser(__doc__, "connect_momenta")
    args = ap.parse_args()
    reps, batch = (5, 200) if args.quick else (20, 1000)
    data = {"disk": call_case("rolling_disk", "vakonomic", ["psi"], reps, batch),
            "coin": call_case("rolling_coin", "vakonomic", ["phi", "psi", "theta"], reps,
                              batch),
            "connect": connect_case(3 if args.quick else 15)}
    for name in ("disk", "coin"):
        r = data[name]
        print(f"{name} ({', '.join(r['free'])} free): prepared {r['prepared_us']:.2f} us, "
              f"walk {r['walk_us']:.2f} us ({r['walk_over_prepared']:.1f}x)")
    r = data["connect"]
    print(f"connect (disk, psi free): prepared {r['prepared_s'] * 1e3:.2f} ms, walk "
          f"{r['walk_s'] * 1e3:.2f} ms ({r['walk_over_prepared']:.2f}x)")
    write("connect_momenta", data, args.out, args.quick)


if __name__ == "__main__":
    sys.exit(main())
