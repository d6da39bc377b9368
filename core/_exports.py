"""Names of a sub-package loaded from the module that defines them, on first use.

A sub-package that took the place of a module (``regopack.run`` holds
:mod:`regopack.run.pipeline` and its neighbours) offers the names of that
module without importing it when the package is imported, so that importing
one of its lighter neighbours stays light and creates no import cycle.
"""

from __future__ import annotations

import importlib
import importlib.util
import sys
from collections.abc import Callable, Mapping, MutableMapping
from typing import Any

__all__ = ["lazy_exports", "load_export"]


def load_export(namespace: MutableMapping[str, Any], sources: Mapping[str, str], name: str) -> Any:
    """Return ``name`` from its module ``sources[name]`` and keep it in ``namespace``.

    Raises
    ------
    AttributeError
        When ``name`` is not in ``sources``.
    """
    if name not in sources:
        raise AttributeError(f"module {namespace['__name__']!r} has no attribute {name!r}")
    value = getattr(importlib.import_module(sources[name]), name)
    namespace[name] = value
    return value


def _public_of(namespace: Mapping[str, Any], module: str, name: str) -> bool:
    """Whether ``module`` offers the public ``name`` that no submodule of the package takes."""
    if name.startswith("_"):
        return False
    package = str(namespace["__name__"])
    if f"{package}.{name}" in sys.modules:
        return False
    if namespace.get("__path__") is not None and importlib.util.find_spec(f"{package}.{name}"):
        return False
    return hasattr(importlib.import_module(module), name)


def lazy_exports(
    namespace: MutableMapping[str, Any], sources: Mapping[str, str] | str
) -> tuple[Callable[[str], Any], Callable[[], list[str]]]:
    """Return a package's ``__getattr__`` and ``__dir__`` (PEP 562) for ``sources``.

    ``__getattr__`` loads a name of ``sources`` (or, given one module's name,
    of the package's ``__all__`` from that module) on first use
    (:func:`load_export`); ``__dir__`` lists the package's ``__all__``. A
    package that took the place of one module (``sources`` is its name) also
    offers that module's other public names, as the module did before it
    moved (``regopack.run.summary_rows``), unless a submodule of the package
    has the name.
    """
    table = dict.fromkeys(namespace["__all__"], sources) if isinstance(sources, str) else sources

    def getattr_(name: str) -> Any:
        if isinstance(sources, str) and name not in table and _public_of(namespace, sources, name):
            return load_export(namespace, {name: sources}, name)
        return load_export(namespace, table, name)

    def dir_() -> list[str]:
        return sorted(namespace["__all__"])

    return getattr_, dir_
