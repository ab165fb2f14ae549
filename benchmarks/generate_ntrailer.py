"""CPU seconds from an N-trailer model to its kernels' source, without compiling:
the model (``models.get``), the ``Scene`` constructor, and ``codegen.generate`` (the
derivation, the energy and indicators, the printing).

    PYTHONPATH=. .venv/bin/python benchmarks/generate_ntrailer.py N PRINCIPLE

prints one JSON line; compare two checkouts with
``farm-bench -n 3 -- <this command> --vs '<the same command at another commit>'``.
"""

from __future__ import annotations

import hashlib
import json
import sys
import time


def main(argv=None) -> int:
    argv = sys.argv[1:] if argv is None else argv
    N, principle = int(argv[0]), argv[1]
    from jetnh import models
    from jetnh.numeric import Scene, codegen

    t0 = time.process_time()
    system = models.get("n_trailer", N=N)
    t1 = time.process_time()
    ini = dict(models.initial("n_trailer", N=N))
    ini.update({m: 0.0 for m in codegen.multiplier_names(system, principle)})
    sc = Scene(system, principle, initial=ini, t_span=(0.0, 1.0))
    t2 = time.process_time()
    ks = codegen.generate(sc.spec)
    t3 = time.process_time()
    body = ks.source.split("\n", 2)[2]          # the key line names the source hash
    print(json.dumps({"N": N, "principle": principle, "model_cpu": t1 - t0,
                      "scene_cpu": t2 - t1, "generate_cpu": t3 - t2,
                      "source_sha256": hashlib.sha256(body.encode()).hexdigest()}))
    return 0


if __name__ == "__main__":
    sys.exit(main())
