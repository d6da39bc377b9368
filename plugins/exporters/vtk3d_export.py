"""The ``vtk3d`` exporter: a VTK XML unstructured grid (``.vtu``) of polyhedron cells.

One ``VTK_POLYHEDRON`` cell (type 42) per placed particle, with its faces, in
draw order. The file uses the polyhedron layout of VTK XML files version 1.0
(``faces`` and ``faceoffsets`` beside ``connectivity``, ``offsets`` and
``types``), which every VTK since 6 and ParaView since 4 read, the newest
included.
"""

from __future__ import annotations

from collections.abc import Iterable, Mapping
from pathlib import Path
from xml.sax.saxutils import escape

import numpy as np
from pydantic import BaseModel, ConfigDict

from regopack.base.units import length_unit
from regopack.geometry.domain import Box
from regopack.packing.core import Packing
from regopack.plugins.exporters.export_common import _num, _write_text
from regopack.plugins.exporters.solid_export_common import mass_properties, placed_solids
from regopack.registry.interfaces import Analyzer, SolidExporter

__all__ = ["VTK_POLYHEDRON", "Vtk3dConfig", "Vtk3dExporter"]

VTK_POLYHEDRON = 42
"""VTK's cell type of a polyhedron given by its faces."""


class Vtk3dConfig(BaseModel):
    """Parameters of the ``vtk3d`` exporter (it has none)."""

    model_config = ConfigDict(extra="forbid", strict=True)


def _array(name: str, vtk_type: str, values: Iterable[str], components: int = 1) -> str:
    comps = f' NumberOfComponents="{components}"' if components != 1 else ""
    body = " ".join(values)
    return (
        f'<DataArray type="{vtk_type}" Name="{name}"{comps} format="ascii">\n{body}\n</DataArray>'
    )


def _strings(name: str, values: Iterable[str]) -> str:
    """Write a VTK string array (ASCII: the UTF-8 bytes of each string, each ended by 0)."""
    codes = [str(b) for v in values for b in (*v.encode("utf-8"), 0)]
    count = sum(1 for c in codes if c == "0")
    return (
        f'<Array type="String" Name="{name}" NumberOfTuples="{count}" format="ascii">\n'
        f"{' '.join(codes)}\n</Array>"
    )


class Vtk3dExporter(SolidExporter):
    """VTK XML unstructured grid (``.vtu``, ASCII) with one polyhedron cell per placed particle.

    Points are each particle's own vertices in the packing's frame (none is
    shared between particles), in the scene's length unit, which the
    field-data string array ``length_unit`` and the comment at the top name.
    Cell data: ``index`` (draw index), ``mineral``
    (index into the field-data string array ``mineral_names``, also listed in
    a comment), ``equivalent_diameter``, ``volume`` (exact, of the polyhedron)
    and ``insertion_index``.
    """

    suffix = ".vtu"

    def __init__(self, config: Vtk3dConfig | None = None) -> None:
        self.config = config or Vtk3dConfig()

    def export(
        self, packing: Packing[Box], path: Path, *, analyses: Mapping[str, Analyzer] | None = None
    ) -> Path:
        """Write the unstructured grid; return ``path``."""
        path = Path(path)
        solids = placed_solids(packing, "vtk3d")
        idx = np.array([s.index for s in solids], dtype=np.int64)
        points = np.concatenate([s.world for s in solids]) if solids else np.zeros((0, 3))
        counts = np.array([s.local.shape[0] for s in solids], dtype=np.int64)
        starts = np.concatenate([[0], np.cumsum(counts)]).astype(np.int64)
        faces: list[int] = []
        face_ends: list[int] = []
        for s, start in zip(solids, starts[:-1].tolist(), strict=True):
            faces.append(len(s.loops))
            for loop in s.loops:
                faces.append(len(loop))
                faces.extend((loop + start).tolist())
            face_ends.append(len(faces))
        volume = [mass_properties(s.local, s.loops)[0] for s in solids]
        names = ", ".join(f"{k} = {name}" for k, name in enumerate(packing.mineral_names))
        unit = length_unit(packing)
        cell = [
            _array("index", "Int64", (str(j) for j in idx.tolist())),
            _array("mineral", "Int32", (str(m) for m in packing.mineral[idx].tolist())),
            _array(
                "equivalent_diameter",
                "Float64",
                (_num(2.0 * r) for r in packing.radius[idx].tolist()),
            ),
            _array("volume", "Float64", (_num(v) for v in volume)),
            _array(
                "insertion_index", "Int64", (str(i) for i in packing.insertion_index[idx].tolist())
            ),
        ]
        xyz = (f"{_num(x)} {_num(y)} {_num(z)}" for x, y, z in points.tolist())
        n = len(solids)
        lines = [
            '<?xml version="1.0"?>',
            f"<!-- regopack {packing.version} 3D packing: scene "
            f"{escape(str(packing.scene.get('name', '?')))}, seed {packing.seed}; "
            f"lengths in {unit}; minerals: {escape(names)} -->",
            '<VTKFile type="UnstructuredGrid" version="1.0" byte_order="LittleEndian" '
            'header_type="UInt64">',
            "<UnstructuredGrid>",
            "<FieldData>",
            _strings("mineral_names", packing.mineral_names),
            _strings("length_unit", [unit]),
            "</FieldData>",
            f'<Piece NumberOfPoints="{points.shape[0]}" NumberOfCells="{n}">',
            "<Points>",
            _array("Points", "Float64", xyz, components=3),
            "</Points>",
            "<Cells>",
            _array("connectivity", "Int64", (str(i) for i in range(points.shape[0]))),
            _array("offsets", "Int64", (str(o) for o in starts[1:].tolist())),
            _array("types", "UInt8", (str(VTK_POLYHEDRON) for _ in range(n))),
            _array("faces", "Int64", (str(f) for f in faces)),
            _array("faceoffsets", "Int64", (str(e) for e in face_ends)),
            "</Cells>",
            '<CellData Scalars="mineral">',
            *cell,
            "</CellData>",
            "</Piece>",
            "</UnstructuredGrid>",
            "</VTKFile>",
        ]
        _write_text(path, "\n".join(lines) + "\n")
        return path
