"""Old names kept for one release as deprecated aliases of what replaced them.

A module that moved stays importable under its old name: :data:`MOVED_MODULES`
maps the old name to the new one, and the finder that :func:`install` puts at
the front of :data:`sys.meta_path` hands out the new module object itself, so
that an attribute set through the old name (a monkeypatch, say) reaches the
real module. Importing the old name warns once, with a
:class:`DeprecationWarning` naming the new place; a submodule of a moved
package moves with it. :func:`warn_moved` says the same of a single name.
"""

from __future__ import annotations

import importlib
import importlib.abc
import importlib.util
import sys
import warnings
from collections.abc import Mapping, Sequence
from importlib.machinery import ModuleSpec
from types import ModuleType

__all__ = ["MOVED_MODULES", "AliasFinder", "install", "warn_moved"]

MOVED_MODULES: dict[str, str] = {
    "regopack.domain3d": "regopack.domain",
}
"""New module of each old module name (kept until the release after the move)."""


def warn_moved(old: str, new: str, stacklevel: int = 2) -> None:
    """Warn that ``old`` is deprecated and that ``new`` replaces it.

    ``stacklevel`` is that of :func:`warnings.warn` counted from the caller:
    the default blames the code that called the caller (the import system's
    own frames are skipped).
    """
    warnings.warn(
        f"{old} is deprecated and will be removed in the next release; use {new}",
        DeprecationWarning,
        stacklevel=stacklevel + 1,
    )


class _AliasLoader(importlib.abc.Loader):
    """Loads an old module name as the module object of the new name."""

    def __init__(self, target: str) -> None:
        self.target = target
        self.spec: ModuleSpec | None = None

    def create_module(self, spec: ModuleSpec) -> ModuleType:
        """Import the new module and return it, warning that the old name is deprecated."""
        module = importlib.import_module(self.target)
        self.spec = module.__spec__
        warn_moved(spec.name, self.target)
        return module

    def exec_module(self, module: ModuleType) -> None:
        """Run nothing: give the module back the spec that the import system replaced."""
        module.__spec__ = self.spec


class AliasFinder(importlib.abc.MetaPathFinder):
    """Finds the old names of moved modules (and their submodules).

    Parameters
    ----------
    moved
        New module name by old module name.
    """

    def __init__(self, moved: Mapping[str, str]) -> None:
        self.moved = moved

    def target(self, name: str) -> str | None:
        """Return the new name of the module ``name``, or ``None`` if it did not move."""
        for old, new in self.moved.items():
            if name == old or name.startswith(old + "."):
                return new + name[len(old) :]
        return None

    def find_spec(
        self, fullname: str, path: Sequence[str] | None, target: ModuleType | None = None
    ) -> ModuleSpec | None:
        """Return a spec that loads the new module for an old name, else ``None``."""
        new = self.target(fullname)
        if new is None:
            return None
        return importlib.util.spec_from_loader(fullname, _AliasLoader(new))


FINDER = AliasFinder(MOVED_MODULES)
"""The finder of regopack's moved modules."""


def install() -> None:
    """Put :data:`FINDER` at the front of :data:`sys.meta_path` (once)."""
    if FINDER not in sys.meta_path:
        sys.meta_path.insert(0, FINDER)
