"""Immutable objects (``System``, ``Equations``, ``Scene``, ``Trajectory``, ``Event``,
``Ensemble``): attributes are set in ``__init__`` only.  Their mappings (``system.forces``,
``scene.params``, ``scene.initial``) are ``FrozenDict``: read as dicts, written never;
every numpy array of a public attribute or computed value (``traj.t``, ``traj["x"]``,
``scene.y0``) is read-only (``readonly``); private ones (``_p``) feed compiled code,
which takes writable arrays, and are never handed out.

``Frozen.__init_subclass__`` wraps the subclass's ``__init__``: once it returns, setting
or deleting an attribute raises ``FrozenError``.  Values computed on first use (compiled
kernels and events, derived columns) go to the object's private ``_memo`` through
``memo`` (like ``functools.cached_property``, but the instance's ``__dict__`` is never
written after construction), or ``made`` where some objects hold the value already.
"""

from __future__ import annotations

import functools

import numpy as np

from .errors import FrozenError


def readonly(value):
    """``value`` with every numpy array in it (also inside lists, tuples and dicts)
    made read-only in place, so that what a frozen object hands out cannot change it."""
    if isinstance(value, np.ndarray):
        value.flags.writeable = False
    elif isinstance(value, (list, tuple)):
        for v in value:
            readonly(v)
    elif isinstance(value, dict):
        for v in value.values():
            readonly(v)
    return value


class Frozen:
    """Base of the immutable objects (module docstring).  ``_portable``: the memo entries
    that copies and pickles keep (plain data; compiled code stays behind)."""

    _portable: tuple[str, ...] = ()

    def __init_subclass__(cls, **kwargs):
        super().__init_subclass__(**kwargs)
        init = cls.__dict__.get("__init__")
        if init is None:
            return

        @functools.wraps(init)
        def frozen_init(self, *args, **kw):
            init(self, *args, **kw)
            if type(self).__init__ is frozen_init:    # the outermost __init__ freezes
                object.__setattr__(self, "_memo", {})

        cls.__init__ = frozen_init

    def __getstate__(self):
        memo = self.__dict__.get("_memo", {})
        return {**self.__dict__, "_memo": {k: memo[k] for k in self._portable if k in memo}}

    def _refuse(self, name):
        raise FrozenError(f"{type(self).__name__} is immutable: cannot change {name!r} after "
                          "construction; make a new one (Scene.replace, System.replace)")

    def _set(self, **values):
        """Set attributes in ``__init__``, in one go (as many assignments, without a call of
        ``__setattr__`` each: a trajectory is made on every run)."""
        if "_memo" in self.__dict__:
            self._refuse(next(iter(values)))
        self.__dict__.update(values)
        readonly({k: v for k, v in values.items() if not k.startswith("_")})

    def __setattr__(self, name, value):
        if "_memo" in self.__dict__:
            self._refuse(name)
        object.__setattr__(self, name, value if name.startswith("_") else readonly(value))

    def __delattr__(self, name):
        if "_memo" in self.__dict__:
            self._refuse(name)
        object.__delattr__(self, name)


class made:
    """A value made on first read and kept in the object's ``_memo`` (read-only where it
    is public).  Alone, a non-data descriptor: an attribute the object holds in its
    ``__dict__`` is read first (a ``Scene`` built by ``Scene(...)`` holds ``initial``; the
    copies ``Scene.replace`` makes do not, and make it when it is read)."""

    def __init__(self, fget):
        self.fget = fget
        self.name = fget.__name__
        self.__doc__ = fget.__doc__

    def __get__(self, obj, cls=None):
        if obj is None:
            return self
        store = obj._memo
        if self.name not in store:
            value = self.fget(obj)
            # what is handed out is read-only; private values feed compiled code
            store[self.name] = value if self.name.startswith("_") else readonly(value)
        return store[self.name]


class memo(made):
    """A property computed on first use and kept in the object's ``_memo`` (``made``, but
    a data descriptor: never held in ``__dict__``, and setting it raises ``FrozenError``)."""

    def __set__(self, obj, value):
        obj._refuse(self.name)


class FrozenDict(dict):
    """A dict that refuses writes (``FrozenError``); reads, copies (``dict(d)``), JSON and
    pickling work as for a dict."""

    __slots__ = ()

    def _refuse(self, *args, **kwargs):
        raise FrozenError("this mapping is read-only (fixed at construction, as a system's "
                          "forces and defaults and a scene's params and initial values); "
                          "make a new one: a new System, or Scene.replace(params=..., "
                          "initial=...)")

    __setitem__ = __delitem__ = __ior__ = _refuse
    clear = pop = popitem = setdefault = update = _refuse

    def __reduce__(self):
        return FrozenDict, (dict(self),)
