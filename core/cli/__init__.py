"""The command line: ``regopack run``, ``analyze``, ``export``, ``verify``, ``sweep``, ..."""

from __future__ import annotations

from typing import TYPE_CHECKING, Any

from regopack._exports import load_export

if TYPE_CHECKING:
    from regopack.cli.commands import build_parser as build_parser
    from regopack.cli.commands import main as main

__all__ = ["build_parser", "main"]

_SOURCES = dict.fromkeys(__all__, "regopack.cli.commands")


def __getattr__(name: str) -> Any:
    """Load the names of :mod:`regopack.cli.commands` on first use (PEP 562)."""
    return load_export(globals(), _SOURCES, name)


def __dir__() -> list[str]:
    return sorted(__all__)
