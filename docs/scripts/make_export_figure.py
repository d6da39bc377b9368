"""Render a packing's VTK export with VTK itself, as a viewer such as ParaView shows it.

Run from the repository root (needs the ``test`` extra, which installs ``vtk``)::

    python docs/scripts/make_export_figure.py                 # packs the ``small`` scene first
    python docs/scripts/make_export_figure.py --packing runs/small-seed1/packing.npz

Writes ``docs/images/export-vtk.png``: the ``.vtp`` file read back by VTK's XML
reader and drawn off screen, cells coloured by their ``mineral`` cell data.
"""

from __future__ import annotations

import argparse
import tempfile
from pathlib import Path

import vtk

import regopack
from regopack.base.colours import mineral_colours
from regopack.exports.pipeline import export_packing

HERE = Path(__file__).resolve().parent
IMAGES_DIR = HERE.parent / "images"
"""The documentation's pictures, ``docs/images``."""


def _rgb(hex_colour: str) -> tuple[float, float, float]:
    h = hex_colour.lstrip("#")
    return (int(h[0:2], 16) / 255, int(h[2:4], 16) / 255, int(h[4:6], 16) / 255)


def render(vtp: Path, out: Path, names: list[str], size: int = 900) -> None:
    """Draw the cells of ``vtp`` coloured by mineral into the PNG ``out``."""
    reader = vtk.vtkXMLPolyDataReader()
    reader.SetFileName(str(vtp))
    reader.Update()
    table = vtk.vtkLookupTable()
    n_minerals = len(names)
    table.SetNumberOfTableValues(n_minerals)
    for k, colour in enumerate(mineral_colours(names)):  # by name, as in the analysis figures
        table.SetTableValue(k, *_rgb(colour), 1.0)
    table.Build()
    mapper = vtk.vtkPolyDataMapper()
    mapper.SetInputConnection(reader.GetOutputPort())
    mapper.SetScalarModeToUseCellFieldData()
    mapper.SelectColorArray("mineral")
    mapper.SetLookupTable(table)
    mapper.SetScalarRange(0, n_minerals - 1)
    mapper.SetColorModeToMapScalars()
    actor = vtk.vtkActor()
    actor.SetMapper(mapper)
    actor.GetProperty().SetEdgeVisibility(True)
    actor.GetProperty().SetEdgeColor(0.15, 0.15, 0.15)
    actor.GetProperty().SetLineWidth(0.5)
    renderer = vtk.vtkRenderer()
    renderer.AddActor(actor)
    renderer.SetBackground(1.0, 1.0, 1.0)
    window = vtk.vtkRenderWindow()
    window.SetOffScreenRendering(True)
    window.AddRenderer(renderer)
    window.SetSize(size, size)
    renderer.ResetCamera()
    renderer.GetActiveCamera().Zoom(1.35)
    window.Render()
    grab = vtk.vtkWindowToImageFilter()
    grab.SetInput(window)
    grab.Update()
    writer = vtk.vtkPNGWriter()
    writer.SetFileName(str(out))
    writer.SetInputConnection(grab.GetOutputPort())
    writer.Write()


def main() -> None:
    """Pack (or load) a packing, export it to VTK and render the export."""
    parser = argparse.ArgumentParser(
        description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter
    )
    parser.add_argument("--packing", type=Path, help="packing file (default: pack the small scene)")
    parser.add_argument("--out", type=Path, default=IMAGES_DIR / "export-vtk.png")
    args = parser.parse_args()
    from regopack.registry.manager import default_registry

    with tempfile.TemporaryDirectory() as tmp:
        if args.packing is None:
            from regopack.run.pipeline import run_scene
            from regopack.scenes.model import load_scene, resolve_scene

            resolved = resolve_scene(load_scene("small"), default_registry())
            packing = run_scene(resolved, None).packing
        else:
            packing = regopack.load(args.packing)
        vtp = export_packing(packing, "vtk", Path(tmp) / "packing.vtp", registry=default_registry())
        args.out.parent.mkdir(parents=True, exist_ok=True)
        render(vtp, args.out, list(packing.mineral_names))
    print(f"wrote {args.out}")


if __name__ == "__main__":
    main()
