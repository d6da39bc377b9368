"""Names of a sub-package loaded from the module that defines them, on first use.

A sub-package that took the place of a module (``regopack.run`` holds
:mod:`regopack.run.pipeline` and its neighbours) offers the names of that
module without importing it when the package is imported, so that importing
one of its lighter neighbours stays light and creates no import cycle.
"""

from __future__ import annotations

import importlib
from collections.abc import Mapping, MutableMapping
from typing import Any

__all__ = ["load_export"]


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
