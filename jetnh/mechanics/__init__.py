"""The mechanics layer: constrained systems (``system``), the principles and their
variations, the derived equations and accelerations, their equivalence, first integrals
and symmetries, symbolic proofs, and the bridge to sympy.physics.mechanics
(``sympy_bridge``; ``jetnh.mechanics.from_mechanics`` and ``to_mechanics`` are kept
importable from here)."""

_BRIDGE = ("from_mechanics", "to_mechanics")


def __getattr__(name):
    """The bridge imports sympy.physics.mechanics: load it on first use."""
    if name in _BRIDGE:
        from . import sympy_bridge

        return getattr(sympy_bridge, name)
    raise AttributeError(f"module 'jetnh.mechanics' has no attribute {name!r}")
