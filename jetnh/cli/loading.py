"""A model named on the command line: a catalogue name (with options) or a model file."""

from __future__ import annotations

import os
import re
from dataclasses import dataclass, field
from pathlib import Path

from ..errors import ModelFileError
from .usage import UsageError


@dataclass
class Loaded:
    """A model from the catalogue or a file, with its defaults for simulation."""

    system: object
    label: str
    initial: dict = field(default_factory=dict)
    principle: str | None = None
    convention: str | None = None
    integrals: dict = field(default_factory=dict)
    simulation: dict = field(default_factory=dict)


_SPEC = re.compile(r"^([A-Za-z_][A-Za-z0-9_]*)(?::(.*))?$")


def _catalogue_options(text: str, model: str) -> dict:
    opts = {}
    for item in filter(None, (s.strip() for s in text.split(","))):
        k, sep, v = item.partition("=")
        if not sep:
            raise UsageError(f"model options are KEY=VALUE, got {item!r} in {model!r} "
                             "(e.g. n_trailer:N=4)")
        try:
            opts[k.strip()] = int(v)
        except ValueError:
            raise UsageError(f"model option {k.strip()} must be an integer, got {v!r}") from None
    return opts


def load_model(spec: str) -> Loaded:
    """A catalogue name (``name`` or ``name:K=V,...``) or a path to a model file."""
    from .. import models
    from ..modelfile import load

    path = Path(spec)
    match = _SPEC.match(spec)
    looks_like_file = spec.endswith(".toml") or os.sep in spec or "/" in spec
    in_catalogue = bool(match) and match.group(1) in models.CATALOGUE
    if looks_like_file or (not in_catalogue and path.exists()):
        m = load(path)
        return Loaded(m.system, m.name or path.stem, dict(m.initial), m.principle,
                      m.convention, dict(m.integrals), dict(m.simulation))
    if not in_catalogue:
        raise ModelFileError(
            f"no model named {spec!r} in the catalogue, and no model file of that name; "
            f"the catalogue has {', '.join(models.CATALOGUE)} (see `jetnh models`)")
    name, rest = match.group(1), match.group(2)
    opts = _catalogue_options(rest or "", spec)
    info = models.info(name)
    system = info.system(**opts)
    return Loaded(system, spec, info.initial(**opts), None, None, {},
                  {"t_end": info.t_end})


def with_split(loaded: Loaded, split: str | None) -> Loaded:
    if split:
        names = [s.strip() for s in split.split(",") if s.strip()]
        loaded.system = loaded.system.with_split(names)
    return loaded
