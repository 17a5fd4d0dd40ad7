"""The contact-law registry: one file per law, each registered under the simulator's own name.

``law_class(key)`` and ``make(key, params)`` find a law by its key
(``liggghts:hertz``, ``yade:Law2_ScGeom_MindlinPhys_Mindlin``, ...);
``supported()`` lists every key. Every module of this package is imported
below, and each law class registers itself with :func:`register`, so adding
a law is adding one file (``docs/design.md``, "How to add a contact law").
An unknown key is one :class:`~demsplit.errors.UnsupportedModelError` that
lists what is supported.
"""

from __future__ import annotations

import pkgutil
from collections.abc import Mapping
from importlib import import_module
from typing import Any, TypeVar

from ...errors import UnsupportedModelError
from .base import ContactLaw, ContactRows, LawEnergy

_REGISTRY: dict[str, type[ContactLaw]] = {}

DEFAULT = "liggghts:hertz"
"""The law of a scene that names none (LIGGGHTS' granular default, Hertz with a tangential history)."""

L = TypeVar("L", bound=type[ContactLaw])


def register(cls: L) -> L:
    """Class decorator: add a law to the registry under ``cls.key`` (once)."""
    if cls.key in _REGISTRY and _REGISTRY[cls.key] is not cls:
        raise ValueError(
            f"two contact laws are registered as {cls.key!r}: {_REGISTRY[cls.key].__module__} and {cls.__module__}"
        )
    _REGISTRY[cls.key] = cls
    return cls


def supported() -> tuple[str, ...]:
    """Every registered key, sorted."""
    return tuple(sorted(_REGISTRY))


def law_class(key: str) -> type[ContactLaw]:
    """The law registered as ``key``; an unknown key lists the supported ones."""
    try:
        return _REGISTRY[key]
    except KeyError:
        raise UnsupportedModelError(
            f"contact law {key!r} is not supported; demsplit has {', '.join(supported())}.",
            fix="run the simulation with one of these laws, or add the law (docs/design.md, "
            "'How to add a contact law').",
        ) from None


def simulator_words(simulator: str) -> dict[str, str]:
    """The ``simulator``'s own name of every law registered for it -> the law's key: a law is registered as
    ``simulator:name`` with the simulator's spelling of its name (``liggghts:hooke/hysteresis``,
    ``yade:Law2_ScGeom_MindlinPhys_Mindlin``), so the readers' word maps need no table of their own."""
    prefix = f"{simulator}:"
    return {key[len(prefix) :]: key for key in supported() if key.startswith(prefix)}


def make(key: str, params: Mapping[str, Any] | None = None) -> ContactLaw:
    """An instance of the law ``key`` with ``params`` (defaults filled in, checked)."""
    return law_class(key)(params)


for _module in pkgutil.iter_modules(__path__):
    if _module.name != "base":
        import_module(f"{__name__}.{_module.name}")

__all__ = [
    "DEFAULT",
    "ContactLaw",
    "ContactRows",
    "LawEnergy",
    "law_class",
    "make",
    "register",
    "simulator_words",
    "supported",
]
