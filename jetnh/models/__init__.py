"""A catalogue of constrained systems, each a function returning a ``System``.

Every model carries its parameters' default values (``system.defaults``) and a docstring
with its source, its closed-form solutions and its first integrals (each checked in
``tests/test_models.py``).  ``model(name)`` is the ``Model`` (``jetnh.modelfile.Model``,
the record model files give too): the System with a default initial state and time span
(what ``jetnh simulate NAME`` uses); ``info(name)`` is the catalogue entry that builds
it.  Scalable families take options, e.g. ``get("n_trailer", N=4)`` or, as on the command
line and in ``Model.name``, ``get("n_trailer:N=4")``.

=======================  ==============================================================
rolling_disk             vertical rolling disk (the paper's Example 1)
appell_hamel             Appell-Hamel system, nonlinear constraint (Example 2)
knife_edge               knife edge on an inclined plane
chaplygin_sleigh         Chaplygin sleigh
nonholonomic_particle    zdot = y xdot (Heisenberg-type distribution)
heisenberg               zdot = x ydot - y xdot (Heisenberg system, sub-Riemannian)
isokinetic_particle      constant speed, xdot^2 + ydot^2 = v^2 (nonlinear)
rheonomic_knife_edge     prescribed heading w t on a moving belt (time-dependent)
bead_on_parabola         ydot = 2 a x xdot (integrable, differential form)
radial_line              y xdot - x ydot = 0 (integrable, differential form)
rolling_ball             ball rolling on a plane, Euler angles
ball_on_turntable        ball rolling on a rotating table, Euler angles
suslov_rigid_body        Suslov's problem, Euler angles
rolling_coin             disk rolling on a plane, free to lean (upright critical spin)
n_trailer                car with N trailers (option N, default 2)
particle_chain           N coupled nonholonomic particles (option N, default 3)
damped_knife_edge        knife edge with viscous friction (Rayleigh dissipation)
damped_chaplygin_sleigh  Chaplygin sleigh with viscous friction (Rayleigh dissipation)
=======================  ==============================================================
"""

from ..modelfile.model import Model
from ._registry import INFO, ModelInfo, register
from .dissipative import damped_chaplygin_sleigh, damped_knife_edge
from .families import n_trailer, n_trailer_turning, particle_chain
from .paper import appell_hamel, rolling_disk
from .planar import (bead_on_parabola, chaplygin_sleigh, heisenberg, isokinetic_particle,
                     knife_edge, nonholonomic_particle, radial_line, rheonomic_knife_edge)
from .rigid import ball_on_turntable, rolling_ball, rolling_coin, suslov_rigid_body

register("rolling_disk", rolling_disk,
         dict(x=0.1, y=-0.2, phi=0.3, psi=0.4, phi_t=1.0, psi_t=0.7), t_end=10.0,
         tags=("affine", "nonholonomic", "Chaplygin", "paper"))
register("appell_hamel", appell_hamel, dict(x=0.0, y=0.0, z=0.0, x_t=3.0, y_t=1.0),
         t_end=0.5, tags=("nonlinear", "nonholonomic", "paper"))

_ORDER = ("rolling_disk", "appell_hamel", "knife_edge", "chaplygin_sleigh",
          "nonholonomic_particle", "heisenberg", "isokinetic_particle", "rheonomic_knife_edge",
          "bead_on_parabola", "radial_line", "rolling_ball", "ball_on_turntable",
          "suslov_rigid_body", "rolling_coin", "n_trailer", "particle_chain", "damped_knife_edge",
          "damped_chaplygin_sleigh")
assert set(_ORDER) == set(INFO), "every registered model must be listed"

CATALOGUE = {name: INFO[name].factory for name in _ORDER}


def _entry(name: str) -> ModelInfo:
    from ..errors import ModelFileError

    try:
        return INFO[name]
    except (KeyError, TypeError):
        base = name.partition(":")[0] if isinstance(name, str) else None
        hint = ""
        if base in INFO and INFO[base].options:
            key = next(iter(INFO[base].options))
            hint = (f"; options are keyword arguments, get({base!r}, {key}=4), or "
                    f"KEY=VALUE after the name, '{base}:{key}=4'")
        raise ModelFileError(
            f"no model named {name!r} in the catalogue{hint}; known: "
            f"{', '.join(sorted(CATALOGUE))}") from None


def _split(name, options: dict) -> tuple:
    """``name:K=V,...`` (the spelling of the command line and of ``Model.name``) as the
    catalogue name and its options (integers, read by int()), joined to ``options``."""
    from ..errors import ModelFileError

    if not (isinstance(name, str) and ":" in name):
        return name, options
    base, _, text = name.partition(":")
    entry = _entry(base)
    key = next(iter(entry.options), "N")
    opts = {}
    for item in filter(None, (s.strip() for s in text.split(","))):
        k, sep, v = (t.strip() for t in item.partition("="))
        if not sep:
            raise ModelFileError(
                f"model options are KEY=VALUE, got {item!r} in {name!r}: write "
                f"'{base}:{key}={item}' or get({base!r}, {key}={item})")
        if k in opts or k in options:
            raise ModelFileError(f"model option {k} is given twice for {name!r}; give it once")
        try:
            opts[k] = int(v)
        except ValueError:
            raise ModelFileError(
                f"model option {k} must be an integer, got {v!r} in {name!r}") from None
    return base, {**opts, **options}


def get(name: str, **options):
    """The catalogue model ``name`` (a System with defaults); options such as N=4, as
    keywords or after the name (``"n_trailer:N=4"``)."""
    name, options = _split(name, options)
    return _entry(name).system(**options)


def model(name: str, **options) -> Model:
    """The catalogue model ``name`` with its defaults (a ``Model``); options such as N=4,
    as keywords or after the name (``"n_trailer:N=4"``, what ``Model.name`` holds)."""
    name, options = _split(name, options)
    return _entry(name).model(**options)


def info(name: str) -> ModelInfo:
    """The catalogue entry: factory, options, default initial state and time span (options
    after the name are checked, then left to the entry's ``model``/``system``)."""
    name, options = _split(name, {})
    return _entry(name)


def initial(name: str, **options) -> dict:
    """The default initial state of a catalogue model (names -> floats; others are 0)."""
    name, options = _split(name, options)
    return _entry(name).initial(**options)


__all__ = ["CATALOGUE", "INFO", "ModelInfo", "get", "model", "info", "initial", *_ORDER,
           "n_trailer_turning"]
