"""Built-in exporters: VTK, LAMMPS (2D, 3D), CSV, JSON, SVG (2D), STL, slice, LIGGGHTS, YADE (3D).

Each format lives in its own module: :mod:`.vtk_export`, :mod:`.lammps_export`,
:mod:`.liggghts_export`, :mod:`.yade_export`, :mod:`.csv_export`, :mod:`.json_export`,
:mod:`.svg_export`, :mod:`.stl_export` and :mod:`.slice_export` (what they share is in
:mod:`.export_common`, and for 3D packings in :mod:`.solid_export_common`);
``gsd`` and ``image`` register themselves. This module registers them and
gathers their public names, so ``from regopack.plugins.exporters import
read_csv`` keeps working. Every exporter writes one main file (and, for CSV,
two companion files named after its stem); CSV and JSON keep every array of
the packing exactly and are read back by :func:`read_csv` and :func:`read_json`.
An exporter of both dimensions names its suffix per dimension (``vtk``:
``.vtp`` polygons, ``.vtu`` polyhedra); the 3D exporters' old names
``vtk3d`` and ``lammps3d`` (and ``gsd3d``) select them for one release, with a
deprecation warning.
"""

from __future__ import annotations

from collections.abc import Iterable

from regopack._compat import renamed_names
from regopack.plugins.exporters.csv_export import (
    CSV_FORMAT,
    CsvConfig,
    CsvExporter,
    companion_paths,
    read_csv,
)
from regopack.plugins.exporters.csv_export import PARTICLE_COLUMNS as PARTICLE_COLUMNS
from regopack.plugins.exporters.csv_export import VERTEX_COLUMNS as VERTEX_COLUMNS
from regopack.plugins.exporters.export_common import EXPORT_FORMAT_VERSION as EXPORT_FORMAT_VERSION
from regopack.plugins.exporters.export_common import both_dimensions
from regopack.plugins.exporters.json_export import JSON_FORMAT, JsonConfig, JsonExporter, read_json
from regopack.plugins.exporters.lammps_export import LammpsConfig, LammpsExporter
from regopack.plugins.exporters.liggghts_export import LiggghtsConfig, LiggghtsExporter
from regopack.plugins.exporters.rounded_bodies import polygon_moments as polygon_moments
from regopack.plugins.exporters.slice_export import SliceConfig, SliceExporter
from regopack.plugins.exporters.stl_export import StlConfig, StlExporter
from regopack.plugins.exporters.svg_export import SvgConfig, SvgExporter
from regopack.plugins.exporters.vtk_export import VtkConfig, VtkExporter
from regopack.plugins.exporters.yade_export import YadeConfig, YadeExporter
from regopack.registry.hookspecs import hookimpl
from regopack.registry.plugin_types import ExporterSpec

__all__ = [
    "CSV_FORMAT",
    "JSON_FORMAT",
    "CsvConfig",
    "CsvExporter",
    "JsonConfig",
    "JsonExporter",
    "LammpsConfig",
    "LammpsExporter",
    "LiggghtsConfig",
    "LiggghtsExporter",
    "SliceConfig",
    "SliceExporter",
    "StlConfig",
    "StlExporter",
    "SvgConfig",
    "SvgExporter",
    "VtkConfig",
    "VtkExporter",
    "YadeConfig",
    "YadeExporter",
    "companion_paths",
    "read_csv",
    "read_json",
]


@hookimpl
def regopack_exporters() -> Iterable[ExporterSpec]:
    """Register the built-in exporters."""
    return [
        ExporterSpec(
            "csv", CsvConfig, CsvExporter, "Particle and vertex tables (exact round trip)."
        ),
        ExporterSpec("json", JsonConfig, JsonExporter, "One JSON document (exact round trip)."),
        ExporterSpec("svg", SvgConfig, SvgExporter, "Picture of the particles, by mineral."),
        both_dimensions(
            "vtk",
            VtkConfig,
            VtkExporter,
            "VTK XML for ParaView: PolyData (.vtp) of polygons, an unstructured grid (.vtu) "
            "of polyhedron cells.",
        ),
        both_dimensions(
            "lammps",
            LammpsConfig,
            LammpsExporter,
            "LAMMPS data file (body rounded/polygon or rounded/polyhedron) and an input script "
            "that runs it.",
        ),
        ExporterSpec(
            "liggghts",
            LiggghtsConfig,
            LiggghtsExporter,
            "3D packings of spheres: LIGGGHTS data file (atom_style granular) and an input "
            "script that runs it.",
            dimensions=(3,),
        ),
        ExporterSpec(
            "yade",
            YadeConfig,
            YadeExporter,
            "3D: a YADE script that builds every polyhedron and sphere as a body (with walls or "
            "a periodic cell), and its bodies file.",
            dimensions=(3,),
        ),
        ExporterSpec(
            "stl",
            StlConfig,
            StlExporter,
            "3D: binary STL mesh of every placed polyhedron (outward triangles).",
            dimensions=(3,),
        ),
        ExporterSpec(
            "slice",
            SliceConfig,
            SliceExporter,
            "3D: a planar section as a 2D packing file (convex polygons) and its picture.",
            dimensions=(3,),
        ),
    ]


__getattr__ = renamed_names(
    __name__,
    {
        "Vtk3dConfig": "VtkConfig",
        "Vtk3dExporter": "VtkExporter",
        "Gsd3dConfig": "regopack.plugins.exporters.gsd_export:GsdConfig",
        "Gsd3dExporter": "regopack.plugins.exporters.gsd_export:GsdExporter",
        "Lammps3dConfig": "LammpsConfig",
        "Lammps3dExporter": "LammpsExporter",
    },
)
"""The names of the 3D exporter this module's exporter took over, for one release."""
