"""The ``vtk`` exporter: VTK XML PolyData (``.vtp``) for ParaView."""

from __future__ import annotations

from collections.abc import Iterable, Mapping
from pathlib import Path
from xml.sax.saxutils import escape

import numpy as np
from pydantic import BaseModel, ConfigDict

from regopack.base.errors import ExportError
from regopack.base.units import length_unit
from regopack.packing.core import Packing
from regopack.plugins.exporters.export_common import IntArray, _num, _write_text
from regopack.plugins.exporters.vtk3d_export import _strings
from regopack.registry.interfaces import Analyzer, Exporter

__all__ = ["VtkConfig", "VtkExporter"]


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


class VtkExporter(Exporter):
    """VTK XML PolyData (``.vtp``, ASCII) with one polygon per placed particle.

    Points are the absolute outline vertices (z = 0), in the scene's length
    unit, which the field data array ``length_unit`` (a string) and the
    comment at the top name. Cell data: ``index``
    (the particle's draw index), ``mineral`` (index into the mineral names,
    listed in a comment), ``radius``, ``orientation``, ``insertion_index`` and,
    when a computed ``coordination`` analyzer is passed in ``analyses``, ``Z``.
    """

    suffix = ".vtp"

    def __init__(self, config: VtkConfig | None = None) -> None:
        self.config = config or VtkConfig()

    def export(
        self, packing: Packing, path: Path, *, analyses: Mapping[str, Analyzer] | None = None
    ) -> Path:
        """Write the PolyData file; return ``path``."""
        path = Path(path)
        z = _coordination(packing, analyses)
        idx = np.flatnonzero(packing.placed).astype(np.int64)
        polygons = packing.polygons(idx)
        points = np.concatenate(polygons) if polygons else np.empty((0, 2))
        counts = np.array([len(p) for p in polygons], dtype=np.int64)
        offsets = np.cumsum(counts)
        names = ", ".join(f"{k} = {name}" for k, name in enumerate(packing.mineral_names))
        unit = length_unit(packing)
        cell = [
            _data_array("index", "Int64", (str(j) for j in idx.tolist())),
            _data_array("mineral", "Int32", (str(m) for m in packing.mineral[idx].tolist())),
            _data_array("radius", "Float64", (_num(r) for r in packing.radius[idx].tolist())),
            _data_array(
                "orientation", "Float64", (_num(r) for r in packing.orientation[idx].tolist())
            ),
            _data_array(
                "insertion_index", "Int64", (str(i) for i in packing.insertion_index[idx].tolist())
            ),
        ]
        if z is not None:
            cell.append(_data_array("Z", "Int32", (str(v) for v in z[idx].tolist())))
        xyz = (f"{_num(x)} {_num(y)} 0.0" for x, y in points.tolist())
        lines = [
            '<?xml version="1.0"?>',
            f"<!-- regopack {packing.version} packing: scene "
            f"{escape(str(packing.scene.get('name', '?')))}, seed {packing.seed}; "
            f"lengths in {unit}; minerals: {escape(names)} -->",
            '<VTKFile type="PolyData" version="1.0" byte_order="LittleEndian" '
            'header_type="UInt64">',
            "<PolyData>",
            "<FieldData>",
            _strings("length_unit", [unit]),
            "</FieldData>",
            f'<Piece NumberOfPoints="{points.shape[0]}" NumberOfVerts="0" NumberOfLines="0" '
            f'NumberOfStrips="0" NumberOfPolys="{len(idx)}">',
            "<Points>",
            _data_array("Points", "Float64", xyz, components=3),
            "</Points>",
            "<Polys>",
            _data_array("connectivity", "Int64", (str(i) for i in range(points.shape[0]))),
            _data_array("offsets", "Int64", (str(o) for o in offsets.tolist())),
            "</Polys>",
            '<CellData Scalars="mineral">',
            *cell,
            "</CellData>",
            "</Piece>",
            "</PolyData>",
            "</VTKFile>",
        ]
        _write_text(path, "\n".join(lines) + "\n")
        return path
