"""The ``vtk`` exporter: VTK XML files for ParaView, of packings of both dimensions.

A 2D packing is PolyData (``.vtp``) with one polygon per placed particle; a
3D packing is an unstructured grid (``.vtu``) with one ``VTK_POLYHEDRON``
cell (type 42) per placed particle, with its faces, in draw order. The grid
uses the polyhedron layout of VTK XML files version 1.0 (``faces`` and
``faceoffsets`` beside ``connectivity``, ``offsets`` and ``types``), which
every VTK since 6 and ParaView since 4 read, the newest included.
"""

from __future__ import annotations

from collections.abc import Iterable, Mapping
from pathlib import Path
from typing import ClassVar
from xml.sax.saxutils import escape

import numpy as np
from pydantic import BaseModel, ConfigDict

from regopack._compat import renamed_names
from regopack.base.errors import ExportError
from regopack.base.units import length_unit
from regopack.geometry.domain import Box
from regopack.packing.core import Packing
from regopack.plugins.exporters.export_common import (
    Analyses,
    AnyPacking,
    IntArray,
    _num,
    _write_text,
)
from regopack.plugins.exporters.solid_export_common import mass_properties, placed_solids
from regopack.registry.interfaces import Analyzer, Exporter

__all__ = ["VTK_POLYHEDRON", "VtkConfig", "VtkExporter"]

VTK_POLYHEDRON = 42
"""VTK's cell type of a polyhedron given by its faces."""


class VtkConfig(BaseModel):
    """Parameters of the VTK exporter (it has none)."""

    model_config = ConfigDict(extra="forbid", strict=True)


def _coordination(packing: Packing, analyses: Mapping[str, Analyzer] | None) -> IntArray | None:
    """Per-particle coordination number from a computed ``coordination`` analyzer."""
    if not analyses or "coordination" not in analyses:
        return None
    z = getattr(analyses["coordination"], "per_particle", None)
    if z is None:
        return None
    z = np.asarray(z)
    if z.shape != (packing.n_particles,):
        raise ExportError(
            f"coordination results have {z.shape[0] if z.ndim else 0} values for "
            f"{packing.n_particles} particles"
        )
    return z.astype(np.int64)


def _data_array(name: str, vtk_type: str, values: Iterable[str], components: int = 1) -> str:
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


def _ints(values: Iterable[int]) -> Iterable[str]:
    return (str(v) for v in values)


def _cell_data(packing: AnyPacking, idx: IntArray, measures: list[str]) -> list[str]:
    """Return the cell arrays ``index``, ``mineral``, ``measures`` and ``insertion_index``."""
    return [
        _data_array("index", "Int64", _ints(idx.tolist())),
        _data_array("mineral", "Int32", _ints(packing.mineral[idx].tolist())),
        *measures,
        _data_array("insertion_index", "Int64", _ints(packing.insertion_index[idx].tolist())),
    ]


def _document(
    packing: AnyPacking,
    grid: str,
    field: list[str],
    piece: str,
    points: list[str],
    cells: tuple[str, list[str]],
    cell_data: list[str],
) -> str:
    """Return the XML file: a comment, then one ``grid`` piece of points, cells and cell data."""
    names = ", ".join(f"{k} = {name}" for k, name in enumerate(packing.mineral_names))
    solid = "3D " if packing.dimension == 3 else ""
    tag, cell_arrays = cells
    lines = [
        '<?xml version="1.0"?>',
        f"<!-- regopack {packing.version} {solid}packing: scene "
        f"{escape(str(packing.scene.get('name', '?')))}, seed {packing.seed}; "
        f"lengths in {length_unit(packing)}; minerals: {escape(names)} -->",
        f'<VTKFile type="{grid}" version="1.0" byte_order="LittleEndian" header_type="UInt64">',
        f"<{grid}>",
        "<FieldData>",
        *field,
        "</FieldData>",
        piece,
        "<Points>",
        _data_array("Points", "Float64", points, components=3),
        "</Points>",
        f"<{tag}>",
        *cell_arrays,
        f"</{tag}>",
        '<CellData Scalars="mineral">',
        *cell_data,
        "</CellData>",
        "</Piece>",
        f"</{grid}>",
        "</VTKFile>",
    ]
    return "\n".join(lines) + "\n"


def _polydata(packing: Packing, analyses: Mapping[str, Analyzer] | None) -> str:
    """PolyData of the placed polygons (z = 0)."""
    z = _coordination(packing, analyses)
    idx = np.flatnonzero(packing.placed).astype(np.int64)
    polygons = packing.polygons(idx)
    points = np.concatenate(polygons) if polygons else np.empty((0, 2))
    offsets = np.cumsum(np.array([len(p) for p in polygons], dtype=np.int64))
    measures = [
        _data_array("radius", "Float64", (_num(r) for r in packing.radius[idx].tolist())),
        _data_array("orientation", "Float64", (_num(r) for r in packing.orientation[idx].tolist())),
    ]
    cell = _cell_data(packing, idx, measures)
    if z is not None:
        cell.append(_data_array("Z", "Int32", _ints(z[idx].tolist())))
    return _document(
        packing,
        "PolyData",
        [_strings("length_unit", [length_unit(packing)])],
        f'<Piece NumberOfPoints="{points.shape[0]}" NumberOfVerts="0" NumberOfLines="0" '
        f'NumberOfStrips="0" NumberOfPolys="{len(idx)}">',
        [f"{_num(x)} {_num(y)} 0.0" for x, y in points.tolist()],
        (
            "Polys",
            [
                _data_array("connectivity", "Int64", _ints(range(points.shape[0]))),
                _data_array("offsets", "Int64", _ints(offsets.tolist())),
            ],
        ),
        cell,
    )


def _unstructured_grid(packing: Packing[Box]) -> str:
    """Unstructured grid of the placed polyhedra, one polyhedron cell each."""
    solids = placed_solids(packing, "vtk")
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
    diameter = (_num(2.0 * r) for r in packing.radius[idx].tolist())
    measures = [
        _data_array("equivalent_diameter", "Float64", diameter),
        _data_array("volume", "Float64", (_num(v) for v in volume)),
    ]
    n = len(solids)
    return _document(
        packing,
        "UnstructuredGrid",
        [
            _strings("mineral_names", packing.mineral_names),
            _strings("length_unit", [length_unit(packing)]),
        ],
        f'<Piece NumberOfPoints="{points.shape[0]}" NumberOfCells="{n}">',
        [f"{_num(x)} {_num(y)} {_num(z)}" for x, y, z in points.tolist()],
        (
            "Cells",
            [
                _data_array("connectivity", "Int64", _ints(range(points.shape[0]))),
                _data_array("offsets", "Int64", _ints(starts[1:].tolist())),
                _data_array("types", "UInt8", (str(VTK_POLYHEDRON) for _ in range(n))),
                _data_array("faces", "Int64", _ints(faces)),
                _data_array("faceoffsets", "Int64", _ints(face_ends)),
            ],
        ),
        _cell_data(packing, idx, measures),
    )


class VtkExporter(Exporter[AnyPacking]):
    """VTK XML (ASCII): PolyData (``.vtp``) of a 2D packing, a grid (``.vtu``) of a 3D one.

    Points are in the scene's length unit, which the field-data string array
    ``length_unit`` and the comment at the top name. Cell data: ``index``
    (the particle's draw index), ``mineral`` (index into the mineral names,
    listed in a comment and, in 3D, in the field-data string array
    ``mineral_names``) and ``insertion_index``.

    - 2D: one polygon per placed particle, its absolute outline vertices at
      z = 0; cell data ``radius``, ``orientation`` and, when a computed
      ``coordination`` analyzer is passed in ``analyses``, ``Z``.
    - 3D: one polyhedron cell per placed particle, its own vertices in the
      packing's frame (none shared between particles); cell data
      ``equivalent_diameter`` and ``volume`` (exact, of the polyhedron).
      Spheres are refused.
    """

    suffix = ".vtp"
    suffixes: ClassVar[Mapping[int, str]] = {3: ".vtu"}

    def __init__(self, config: VtkConfig | None = None) -> None:
        self.config = config or VtkConfig()

    def export(self, packing: AnyPacking, path: Path, *, analyses: Analyses = None) -> Path:
        """Write the file; return ``path``."""
        path = Path(path)
        if packing.dimension == 3:
            text = _unstructured_grid(packing)
        else:
            text = _polydata(packing, analyses)
        _write_text(path, text)
        return path


__getattr__ = renamed_names(
    __name__,
    {
        "Vtk3dConfig": "VtkConfig",
        "Vtk3dExporter": "VtkExporter",
    },
)
"""The names of the 3D exporter this module's exporter took over, for one release."""
