"""A catalogue of constrained systems, each a function returning a ``System``.

Every model carries its parameters' default values (``system.defaults``) and a docstring
with its source, its closed-form solutions and its first integrals (each checked in
``tests/test_models.py``).  ``model(name)`` is the ``Model`` (``jetnh.modelfile.Model``,
the record model files give too): the System with a default initial state and time span
(what ``jetnh simulate NAME`` uses); ``info(name)`` is the catalogue entry that builds
it.  Scalable families take options, e.g. ``get("n_trailer", N=4)`` or, on the command
line, ``n_trailer:N=4``.

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
        raise ModelFileError(
            f"no model named {name!r} in the catalogue; known: {', '.join(sorted(CATALOGUE))}"
        ) from None


def get(name: str, **options):
    """The catalogue model ``name`` (a System with defaults); options such as N=4."""
    return _entry(name).system(**options)


def model(name: str, **options) -> Model:
    """The catalogue model ``name`` with its defaults (a ``Model``); options such as N=4."""
    return _entry(name).model(**options)


def info(name: str) -> ModelInfo:
    """The catalogue entry: factory, options, default initial state and time span."""
    return _entry(name)


def initial(name: str, **options) -> dict:
    """The default initial state of a catalogue model (names -> floats; others are 0)."""
    return _entry(name).initial(**options)


__all__ = ["CATALOGUE", "INFO", "ModelInfo", "get", "model", "info", "initial", *_ORDER,
           "n_trailer_turning"]
