"""Draw the README picture: a Table-1 packing coloured by mineral, with a zoomed view.

Run from the repository root (needs the ``docs`` extra, i.e. matplotlib)::

    python docs/scripts/make_table1_figure.py                       # packs the default scene first
    python docs/scripts/make_table1_figure.py --packing runs/table1-seed1/packing.npz

The picture is written to ``docs/images/table1.png`` unless ``--out`` says otherwise.
"""

from __future__ import annotations

import argparse
import io
from collections.abc import Sequence
from pathlib import Path

import matplotlib

matplotlib.use("Agg")

import matplotlib.pyplot as plt
import numpy as np
from matplotlib.axes import Axes
from matplotlib.collections import PolyCollection
from matplotlib.patches import ConnectionPatch, Patch, Rectangle
from PIL import Image

import regopack
from regopack.base.colours import mineral_colours
from regopack.packing.core import Packing

HERE = Path(__file__).resolve().parent
IMAGES_DIR = HERE.parent / "images"
"""The documentation's pictures, ``docs/images``."""
DEFAULT_OUT = IMAGES_DIR / "table1.png"
ZOOM = (0.0, 100.0, 0.0, 100.0)
"""Window of the zoomed view, ``(xmin, xmax, ymin, ymax)`` in micrometres."""


def run_default_scene(seed: int | None) -> Packing:
    """Pack the default scene (the paper's Table 1) in memory and return the packing."""
    from regopack.registry.manager import default_registry
    from regopack.run.pipeline import run_scene
    from regopack.scenes.model import load_scene, resolve_scene

    scene = resolve_scene(load_scene(None, seed=seed), default_registry())
    return run_scene(scene).packing


def _collection(
    packing: Packing, idx: np.ndarray, colours: np.ndarray, lw: float
) -> PolyCollection:
    """One polygon per particle ``idx``, filled with its mineral colour."""
    return PolyCollection(
        packing.polygons(idx),
        facecolors=colours[packing.mineral[idx]],
        edgecolors="#202020",
        linewidths=lw,
        antialiased=True,
    )


def _frame(ax: Axes, bounds: Sequence[float]) -> None:
    """Equal aspect, limits ``bounds`` and axis labels in micrometres."""
    xmin, xmax, ymin, ymax = bounds
    ax.set_xlim(xmin, xmax)
    ax.set_ylim(ymin, ymax)
    ax.set_aspect("equal")
    ax.set_xlabel("x (µm)")
    ax.set_ylabel("y (µm)")


def draw(packing: Packing, out: Path, *, width_px: int = 1600, dpi: int = 200) -> Path:
    """Draw ``packing`` with a zoomed view of :data:`ZOOM` and save it as PNG.

    Parameters
    ----------
    packing
        The packing to draw (placed particles only).
    out
        File to write.
    width_px, dpi
        Width of the picture in pixels and its resolution.

    Returns
    -------
    Path
        The file written.
    """
    names = packing.mineral_names
    colours = np.array(mineral_colours(names))  # by name, as in the analysis figures
    placed = np.flatnonzero(packing.placed)
    dom = packing.domain

    width_in = width_px / dpi
    fig = plt.figure(figsize=(width_in, width_in * 0.53), dpi=dpi)
    ax = fig.add_axes((0.07, 0.18, 0.42, 0.76))
    zoom_ax = fig.add_axes((0.56, 0.18, 0.42, 0.76))

    ax.add_collection(_collection(packing, placed, colours, 0.0))
    _frame(ax, (dom.xmin, dom.xmax, dom.ymin, dom.ymax))
    scene = packing.scene.get("name", "packing")
    ax.set_title(
        f"{scene}, seed {packing.seed}: {packing.n_placed:,} particles in "
        f"{dom.width:g} × {dom.height:g} µm",
        fontsize=10,
    )

    x0, x1, y0, y1 = ZOOM
    centre = packing.centre[placed]
    reach = packing.circumradius[placed]
    near = (
        (centre[:, 0] + reach > x0)
        & (centre[:, 0] - reach < x1)
        & (centre[:, 1] + reach > y0)
        & (centre[:, 1] - reach < y1)
    )
    zoom_ax.add_collection(_collection(packing, placed[near], colours, 0.4))
    _frame(zoom_ax, ZOOM)
    zoom_ax.set_title(f"zoom: [{x0:g}, {x1:g}] × [{y0:g}, {y1:g}] µm", fontsize=10)
    ax.add_patch(
        Rectangle((x0, y0), x1 - x0, y1 - y0, fill=False, edgecolor="black", linewidth=1.2)
    )
    for y_data, y_axes in ((y1, 1.0), (y0, 0.0)):  # right corners of the box to the zoom
        fig.add_artist(
            ConnectionPatch(
                xyA=(x1, y_data),
                coordsA=ax.transData,
                xyB=(0.0, y_axes),
                coordsB=zoom_ax.transAxes,
                color="black",
                linewidth=0.8,
            )
        )

    for a in (ax, zoom_ax):
        a.tick_params(labelsize=8)
        a.xaxis.label.set_size(9)
        a.yaxis.label.set_size(9)

    handles = [
        Patch(facecolor=colours[k], edgecolor="#202020", linewidth=0.4, label=name)
        for k, name in enumerate(names)
    ]
    fig.legend(
        handles=handles,
        loc="lower center",
        ncol=len(names),
        frameon=False,
        fontsize=9,
        handlelength=1.2,
        columnspacing=1.5,
    )

    buffer = io.BytesIO()
    fig.savefig(buffer, format="png", dpi=dpi)
    plt.close(fig)
    out.parent.mkdir(parents=True, exist_ok=True)
    # a palette PNG keeps the file small; 256 colours are plenty for flat fills
    with Image.open(buffer) as image:
        image.convert("RGB").quantize(colors=256).save(out, optimize=True)
    return out


def main(argv: Sequence[str] | None = None) -> int:
    """Command line of this script; returns the exit status."""
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--packing", type=Path, help="draw this packing instead of packing anew")
    parser.add_argument("--seed", type=int, help="seed of the default scene (default: its own)")
    parser.add_argument("--out", type=Path, default=DEFAULT_OUT, help="PNG file to write")
    args = parser.parse_args(argv)
    packing = regopack.load(args.packing) if args.packing else run_default_scene(args.seed)
    path = draw(packing, args.out)
    print(f"wrote {path} ({path.stat().st_size / 1e6:.2f} MB)")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
