"""The command line: ``regopack run``, ``analyze``, ``export``, ``verify``, ``sweep``, ..."""

from __future__ import annotations

from typing import TYPE_CHECKING

from regopack._exports import lazy_exports

if TYPE_CHECKING:
    from regopack.cli.commands import build_parser as build_parser
    from regopack.cli.commands import main as main

__all__ = ["build_parser", "main"]

__getattr__, __dir__ = lazy_exports(globals(), "regopack.cli.commands")
