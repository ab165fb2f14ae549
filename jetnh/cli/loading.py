"""A model named on the command line (a catalogue name with options, or a model file) and
the settings a command runs it with, resolved once: each the option given, else the
model's default, else jetnh's (``defaults()``)."""

from __future__ import annotations

import os
import re
from dataclasses import dataclass, fields
from pathlib import Path

from ..errors import ModelFileError
from ..modelfile import Model
from .declared import declared
from .usage import UsageError

#: jetnh's defaults of the settings a model does not give, but the tolerances
_OWN = {"principle": "chetaev", "convention": "paper", "t_start": 0.0, "method": "dop853",
        "points": 201}


def defaults() -> dict:
    """jetnh's defaults of the settings a model does not give; the tolerances are
    ``StepControl``'s (imported here, when a command needs them: the numerics take
    seconds to import, which a command that runs nothing should not pay)."""
    from ..numeric.options import StepControl

    return {**_OWN, "rtol": StepControl.rtol, "atol": StepControl.atol}


def help_default(name: str):
    """``defaults()[name]`` (or ``StepControl``'s ``max_steps``) as the help shows it,
    without importing the numerics (read from ``StepControl``'s source: ``declared``)."""
    return _OWN[name] if name in _OWN else declared("options", "StepControl", name)


_SPEC = re.compile(r"^([A-Za-z_][A-Za-z0-9_]*)(?::(.*))?$")


def _catalogue_options(text: str, model: str) -> dict:
    opts = {}
    for item in filter(None, (s.strip() for s in text.split(","))):
        k, sep, v = item.partition("=")
        if not sep:
            raise UsageError(f"model options are KEY=VALUE, got {item!r} in {model!r} "
                             "(e.g. n_trailer:N=4)")
        if k.strip() in opts:
            raise UsageError(f"model option {k.strip()} is given twice in {model!r}; give "
                             "each option once")
        try:
            opts[k.strip()] = int(v)
        except ValueError:
            raise UsageError(f"model option {k.strip()} must be an integer, got {v!r}") from None
    return opts


def load_model(spec: str) -> Model:
    """A catalogue name (``name`` or ``name:K=V,...``) or a path to a model file."""
    from .. import models
    from ..modelfile import load

    path = Path(spec)
    match = _SPEC.match(spec)
    looks_like_file = spec.endswith(".toml") or os.sep in spec or "/" in spec
    in_catalogue = bool(match) and match.group(1) in models.CATALOGUE
    if looks_like_file or (not in_catalogue and path.exists()):
        return load(path)
    if not in_catalogue:
        raise ModelFileError(
            f"no model named {spec!r} in the catalogue, and no model file of that name; "
            f"the catalogue has {', '.join(models.CATALOGUE)} (see `jetnh models`)")
    return models.model(match.group(1), **_catalogue_options(match.group(2) or "", spec))


def with_split(model: Model, split: str | None) -> Model:
    """``model`` with the dependent coordinates of ``--split Q1,Q2`` (if given)."""
    if split:
        return model.with_split([s.strip() for s in split.split(",") if s.strip()])
    return model


@dataclass(frozen=True)
class Settings:
    """What a command runs a model with; ``t_end`` None: neither --t-end nor the model
    gives one (``t_span`` then asks for it)."""

    principle: str
    convention: str
    t_start: float
    t_end: float | None
    method: str
    rtol: float
    atol: float
    points: int

    @property
    def t_span(self) -> tuple[float, float]:
        if self.t_end is None:
            raise UsageError("give --t-end (the model file has no [simulation] t_end)")
        return self.t_start, float(self.t_end)


def settings(args, model: Model) -> Settings:
    """The settings of a command: each option of ``args`` given (a command without the
    option gives none), else ``model``'s default, else ``defaults()``."""
    given = {"principle": model.principle, "convention": model.convention,
             **model.simulation}
    fallback = defaults()

    def pick(name):
        value = getattr(args, name, None)
        if value is not None:
            return value
        return given[name] if given.get(name) is not None else fallback.get(name)
    values = {f.name: pick(f.name) for f in fields(Settings)}
    return Settings(**{**values, "t_start": float(values["t_start"])})
