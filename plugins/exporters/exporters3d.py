"""Built-in exporters of 3D packings, registered as one plugin.

Each format lives in its own module: :mod:`.vtk3d_export` (``vtk3d``),
:mod:`.stl_export` (``stl``), :mod:`.gsd3d_export` (``gsd3d``),
:mod:`.lammps3d_export` (``lammps3d``) and :mod:`.slice_export` (``slice``);
what they share is in :mod:`.solid_export_common`. Their specs declare
``dimensions = (3,)``, so a 2D packing given to one of them, or a 3D packing
given to a 2D exporter, is refused in one line.
"""

from __future__ import annotations

from collections.abc import Iterable

from regopack.plugins.exporters.gsd3d_export import Gsd3dConfig, Gsd3dExporter
from regopack.plugins.exporters.lammps3d_export import Lammps3dConfig, Lammps3dExporter
from regopack.plugins.exporters.slice_export import SliceConfig, SliceExporter
from regopack.plugins.exporters.stl_export import StlConfig, StlExporter
from regopack.plugins.exporters.vtk3d_export import Vtk3dConfig, Vtk3dExporter
from regopack.registry.hookspecs import hookimpl
from regopack.registry.plugin_types import ExporterSpec

__all__ = ["regopack_exporters"]


@hookimpl
def regopack_exporters() -> Iterable[ExporterSpec]:
    """Register the built-in 3D exporters."""
    return [
        ExporterSpec(
            "vtk3d",
            Vtk3dConfig,
            Vtk3dExporter,
            "3D: VTK XML unstructured grid (.vtu) of polyhedron cells for ParaView.",
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
            "gsd3d",
            Gsd3dConfig,
            Gsd3dExporter,
            "3D: GSD frame for HOOMD-blue, freud and OVITO (a polyhedron type per particle).",
            dimensions=(3,),
        ),
        ExporterSpec(
            "lammps3d",
            Lammps3dConfig,
            Lammps3dExporter,
            "3D: LAMMPS data file (body rounded/polyhedron) and an input script that runs it.",
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
