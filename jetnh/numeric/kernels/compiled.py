"""The record of a loaded kernel module (``CompiledKernels``): its kernels callable from
Python (``calls``) and their C callbacks for the compiled loops."""

from __future__ import annotations

from pathlib import Path

from ..layout import Layout
from ..methods._common import FunctionAddress
from . import calls


class CompiledKernels:
    """A loaded kernel package: ``rhs``, ``aux``, ``sing``, ``aux_rows`` (callable from
    Python, ``calls``), their C callbacks (``rhs_fp``, ...: for the compiled loops), the
    layout, integrators.

    ``source`` is the text of ``kernels.py`` as it was checked and compiled (read it
    rather than the file in ``directory``, which may change or go)."""

    def __init__(self, key: str, directory: Path, layout: Layout, hit: bool, timings: dict,
                 persistent: bool, module, source: str):
        self.key = key
        self.directory = directory
        self.layout = layout
        self.hit = hit                     # found on disk (no derivation, no cse)
        self.timings = dict(timings)
        self.package = f"jetnh_kernels_{key}" + ("" if persistent else "_tmp")
        self.kernels = module
        self.source = source
        for name in ("rhs_c", "aux_c", "sing_c", "hol_c", "jac_c", "events", "events_c", "sing",
                     "step_residual", "momentum", "legendre", "nodal", "constraint_jac"):
            if hasattr(self.kernels, name):
                setattr(self, name, getattr(self.kernels, name))
        for name in ("rhs_c", "aux_c", "sing_c", "hol_c", "events_c"):
            if hasattr(self, name):      # rhs_fp, ...: cheap to pass to compiled loops
                setattr(self, name[:-2] + "_fp", FunctionAddress(getattr(self, name)))
        lay = layout
        n_y, n_p = lay.n_state, len(lay.runtime_params)
        sizes = {"rhs": lay.n_rhs, "aux": lay.n_aux, "sing": len(lay.indicators),
                 "hol": lay.holonomic * (1 + len(lay.coordinates)
                                         + (n_p if lay.sensitivity_columns else 0))}
        for name, n_out in sizes.items():     # rhs, aux, sing from Python
            if hasattr(self, f"{name}_fp") and not hasattr(self, name):
                setattr(self, name, calls.Kernel(getattr(self, f"{name}_fp"),
                                                 (n_out if name == "rhs" else n_y, n_p,
                                                  n_out)))
        #: the holonomic kernel for the compiled loops (``methods.projection``); a stand-in
        #: of the same type, never called, for systems without holonomic constraints
        self.hol_or_none = getattr(self, "hol_fp", getattr(self, "sing_fp", None))
        if hasattr(self, "aux_fp"):
            self.aux_rows = calls.Rows(self.aux_fp, (n_y, n_p, lay.n_aux))
        if hasattr(self, "jac_c"):           # the generated Jacobian (radau)
            self.jac_fp = calls.jacobian_address(self.jac_c)
            self.jac = calls.Kernel(self.jac_fp, (lay.n_rhs, n_p, lay.n_rhs),
                                    jacobian=True)

