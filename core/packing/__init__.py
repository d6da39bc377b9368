"""Packings: the placed particles and their domain, their files, their pictures and measures."""

from __future__ import annotations

from typing import TYPE_CHECKING

from regopack._exports import lazy_exports

if TYPE_CHECKING:
    from regopack.packing.core import FILE_MAGIC as FILE_MAGIC
    from regopack.packing.core import FORMAT_VERSION as FORMAT_VERSION
    from regopack.packing.core import Packing as Packing
    from regopack.packing.core import load as load
    from regopack.packing.core import save as save
    from regopack.packing.core import write_json_atomic as write_json_atomic

__all__ = ["FILE_MAGIC", "FORMAT_VERSION", "Packing", "load", "save", "write_json_atomic"]

__getattr__, __dir__ = lazy_exports(globals(), "regopack.packing.core")
