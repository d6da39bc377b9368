"""The ``stl`` exporter: the placed polyhedra as one binary STL mesh.

Binary STL holds one list of triangles and nothing else (no solids, no
names), so the whole packing is one mesh: the triangles of particle after
particle, in draw order, each face split into a fan from its first vertex,
counter-clockwise seen from outside (the outward normal by the right-hand
rule, which is also the normal written with each triangle). Coordinates are
single precision, as the format stores them.

STL has no unit field, and most tools that read it (slicers, CAD, many mesh
viewers) take its numbers for millimetres. By default the coordinates are
written in the scene's ``length_unit`` (micrometres unless the scene names
another), and the unit is named in the 80-byte header (``unit um``). The
option ``unit`` converts them instead: ``unit = "mm"`` writes millimetres,
so that a 40 µm grain opens as 0.04 mm and not as 40 mm.
"""

from __future__ import annotations

from collections.abc import Mapping
from pathlib import Path
from typing import Any

import numpy as np
from pydantic import BaseModel, ConfigDict, Field, field_validator

from regopack.base.errors import ConfigError
from regopack.base.units import check_length_unit, conversion, length_unit
from regopack.geometry.domain import Box
from regopack.packing.core import Packing
from regopack.plugins.exporters.export_common import scene_label
from regopack.plugins.exporters.solid_export_common import fan_triangles, placed_solids, write_bytes
from regopack.registry.interfaces import Analyzer, Exporter

__all__ = ["STL_RECORD", "StlConfig", "StlExporter", "stl_triangles"]

STL_RECORD = np.dtype([("normal", "<f4", (3,)), ("vertices", "<f4", (3, 3)), ("attribute", "<u2")])
"""One triangle of a binary STL file (50 bytes)."""


class StlConfig(BaseModel):
    """Parameters of the ``stl`` exporter."""

    model_config = ConfigDict(extra="forbid", strict=True)

    unit: str | None = Field(
        None,
        description=(
            "Length unit of the coordinates written: 'm', 'cm', 'mm', 'µm' (or 'um') or 'nm', "
            "converted from the scene's length_unit; default: the scene's own unit, unconverted. "
            "Tools that assume millimetres need 'mm'."
        ),
    )

    @field_validator("unit", mode="before")
    @classmethod
    def _check_unit(cls, value: Any) -> Any:
        if value is None:
            return None
        try:
            return check_length_unit(value)
        except ConfigError as err:
            raise ValueError(str(err).partition(": ")[2]) from err


def stl_triangles(packing: Packing[Box]) -> tuple[np.ndarray, np.ndarray]:
    """Outward triangles of the placed polyhedra, in draw order.

    Returns
    -------
    triangles, owner
        ``(t, 3, 3)`` vertices of every triangle in the packing's frame, and
        the draw index of the particle of each.
    """
    tris, owner = [], []
    for s in placed_solids(packing, "stl"):
        fan = fan_triangles(s.loops)
        tris.append(s.world[fan])
        owner.append(np.full(fan.shape[0], s.index, dtype=np.int64))
    if not tris:
        return np.zeros((0, 3, 3)), np.zeros(0, dtype=np.int64)
    return np.concatenate(tris), np.concatenate(owner)


class StlExporter(Exporter[Packing[Box]]):
    """Binary STL (``.stl``): every placed polyhedron's faces as outward triangles, one mesh."""

    suffix = ".stl"

    def __init__(self, config: StlConfig | None = None) -> None:
        self.config = config or StlConfig()

    def export(
        self, packing: Packing[Box], path: Path, *, analyses: Mapping[str, Analyzer] | None = None
    ) -> Path:
        """Write the mesh; return ``path``."""
        path = Path(path)
        tris, _ = stl_triangles(packing)
        own = length_unit(packing)
        unit = self.config.unit or own
        if unit != own:
            tris = tris * conversion(own, unit)
        normal = np.cross(tris[:, 1] - tris[:, 0], tris[:, 2] - tris[:, 0])
        length = np.linalg.norm(normal, axis=1, keepdims=True)
        normal = np.divide(normal, length, out=np.zeros_like(normal), where=length > 0)
        records = np.zeros(tris.shape[0], dtype=STL_RECORD)
        records["normal"] = normal
        records["vertices"] = tris
        text = (
            f"regopack {packing.version} 3D packing, unit {unit.replace('µ', 'u')}, "
            f"scene {scene_label(packing)}, seed {packing.seed}, "
            f"{packing.n_placed} particles"
        )
        header = text.encode("ascii", "replace")[:80].ljust(80, b" ")
        count = np.array([tris.shape[0]], dtype="<u4").tobytes()
        write_bytes(path, header + count + records.tobytes())
        return path
