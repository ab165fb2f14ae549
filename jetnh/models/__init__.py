"""A catalogue of constrained systems, each a function returning a ``System``.

Every model carries its parameters' default values (``system.defaults``) and a docstring
with its source, its closed-form solutions and its first integrals.
"""

from .paper import appell_hamel, rolling_disk

CATALOGUE = {
    "rolling_disk": rolling_disk,
    "appell_hamel": appell_hamel,
}


def get(name: str):
    """The catalogue model ``name`` (a System with defaults)."""
    from ..errors import ModelFileError

    try:
        return CATALOGUE[name]()
    except KeyError:
        raise ModelFileError(
            f"no model named {name!r} in the catalogue; known: {', '.join(sorted(CATALOGUE))}"
        ) from None


__all__ = ["CATALOGUE", "get", "rolling_disk", "appell_hamel"]
