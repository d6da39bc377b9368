"""Draw the figures of the image export: the files it writes, and PoreSpy run on them.

Run from the repository root (needs the ``docs`` extra for matplotlib and the
``test`` extra for PoreSpy)::

    python docs/scripts/make_image_figure.py                   # packs the ``small`` scene first
    python docs/scripts/make_image_figure.py --packing runs/table1/packing.npz

Writes ``docs/images/export-image.png`` (the binary and minerals images as
written, and a close-up of the pixels under the exact outlines) and
``docs/images/porespy-local-thickness.png`` (PoreSpy's local thickness of the
pore space and the pore-size distribution it gives).
"""

from __future__ import annotations

import argparse
import json
import tempfile
from collections.abc import Sequence
from pathlib import Path
from typing import Any

import matplotlib

matplotlib.use("Agg")

import matplotlib.pyplot as plt
import numpy as np
from matplotlib.axes import Axes
from matplotlib.colors import ListedColormap
from matplotlib.patches import Patch
from PIL import Image

import regopack
from regopack.base.colours import mineral_colours
from regopack.exports.pipeline import export_packing
from regopack.packing.core import Packing
from regopack.plugins.analyzers.figure_style import WIDTH, style
from regopack.plugins.exporters.image_export import image_paths
from regopack.registry.manager import default_registry

HERE = Path(__file__).resolve().parent
IMAGES_DIR = HERE.parent / "images"
"""The documentation's pictures, ``docs/images``."""
IMAGES = IMAGES_DIR
DPI = 200

CLOSE_UP = 6.0
"""Side, in µm, of the close-up window around the smallest particle."""

WINDOW = 60.0
"""Side, in µm, of the window of the local-thickness map, at the domain's centre."""


def _pack_small() -> Packing:
    from regopack.run.pipeline import run_scene
    from regopack.scenes.model import load_scene, resolve_scene

    return run_scene(resolve_scene(load_scene("small"), default_registry())).packing


def _axes_in_um(ax: Axes) -> None:
    ax.set_xlabel("x (µm)")
    ax.set_ylabel("y (µm)")


def _show(ax: Axes, image: np.ndarray, extent: Sequence[float], **kwargs: Any) -> None:
    """Draw ``image`` (row 0 at the top) over ``extent`` = (left, right, bottom, top)."""
    ax.imshow(image, extent=tuple(extent), origin="upper", interpolation="nearest", **kwargs)
    _axes_in_um(ax)


def draw_files(packing: Packing, files: dict[str, Path], meta: dict[str, Any], out: Path) -> Path:
    """Binary image, minerals image and a close-up of the pixels under the outlines."""
    extent = meta["extent"]
    h = meta["pixel_size"]
    binary = np.asarray(Image.open(files["binary"]))
    minerals = np.asarray(Image.open(files["minerals"]))
    names = meta["mineral_names"]
    colours = ["#000000", *mineral_colours(names)]  # by name, as in the analysis figures
    cmap = ListedColormap([*colours, *["#808080"] * (256 - len(colours))])

    with style():
        fig, axes = plt.subplots(1, 3, figsize=(WIDTH, 2.85), layout="constrained", dpi=DPI)
        _show(axes[0], binary, extent, cmap="gray", vmin=0, vmax=255)
        axes[0].set_title(f"(a) {files['binary'].name} (binary)")
        _show(axes[1], minerals, extent, cmap=cmap, vmin=0, vmax=255)
        axes[1].set_title(f"(b) {files['minerals'].name}")

        # centred on the smallest particle, d_min across (10 pixels at the default size)
        idx = np.flatnonzero(packing.placed)
        half = CLOSE_UP / 2
        xmin, xmax, ymin, ymax = packing.domain.bounds()
        cx, cy = packing.centre[idx[np.argmin(packing.radius[idx])]]
        cx, cy = np.clip(cx, xmin + half, xmax - half), np.clip(cy, ymin + half, ymax - half)
        window = (cx - half, cx + half, cy - half, cy + half)
        _show(axes[2], minerals, extent, cmap=cmap, vmin=0, vmax=255)
        for poly in packing.polygons(idx):
            closed = np.vstack([poly, poly[:1]])
            axes[2].plot(closed[:, 0], closed[:, 1], color="white", lw=0.8)
        axes[2].set_xlim(window[0], window[1])
        axes[2].set_ylim(window[2], window[3])
        axes[2].set_title(f"(c) close-up: {h:.3g} µm pixels")
        for ax in axes[:2]:
            ax.add_patch(
                plt.Rectangle(
                    (window[0], window[2]), CLOSE_UP, CLOSE_UP, fill=False, color="red", lw=1.2
                )
            )
        handles = [Patch(facecolor=colours[0], label="pore")]
        handles += [Patch(facecolor=colours[k + 1], label=n) for k, n in enumerate(names)]
        fig.legend(handles=handles, loc="outside lower center", ncol=len(handles))
        fig.savefig(out, dpi=DPI)
        plt.close(fig)
    return out


def local_radius(phases: np.ndarray, walled: bool) -> np.ndarray:
    """PoreSpy's local thickness (radius in pixels) of the pore space ``phases == 1``.

    A walled domain gets a frame of solid pixels first, so that its walls bound
    the pores as the particles do (PoreSpy takes the image border as open).
    """
    import porespy as ps

    pores = phases == 1
    if not walled:
        return np.asarray(ps.filters.local_thickness(pores, method="dt"))
    framed = np.pad(pores, 1, constant_values=False)
    return np.asarray(ps.filters.local_thickness(framed, method="dt"))[1:-1, 1:-1]


def draw_porespy(phases: np.ndarray, meta: dict[str, Any], out: Path) -> Path:
    """PoreSpy's local thickness of the pore space and its pore-size distribution."""
    import porespy as ps

    h = meta["pixel_size"]
    porosity = ps.metrics.porosity(phases)  # 1 pore, 0 solid, 2 (outside) ignored
    pores = phases == 1
    radius = local_radius(phases, meta["domain"]["kind"] != "periodic") * h  # µm
    edges = np.arange(0.5, radius.max() / h + 1.0) * h  # PoreSpy's radii: whole pixels
    psd = ps.metrics.pore_size_distribution(radius, log=False, bins=edges)

    left, right, bottom, top = meta["extent"]
    cx, cy, half = (left + right) / 2, (bottom + top) / 2, min(WINDOW, right - left) / 2
    with style():
        fig, (ax, hist) = plt.subplots(
            1, 2, figsize=(WIDTH, 3.0), layout="constrained", dpi=DPI, width_ratios=(1, 1.2)
        )
        shown = np.ma.masked_where(~pores, radius)
        cmap = plt.get_cmap("viridis").with_extremes(bad="#d9d9d9")
        _show(ax, shown, meta["extent"], cmap=cmap, vmin=0, vmax=float(radius.max()))
        ax.set_xlim(cx - half, cx + half)
        ax.set_ylim(cy - half, cy + half)
        bar = fig.colorbar(ax.images[0], ax=ax, shrink=0.9)
        bar.set_label("local pore radius (µm)")
        ax.set_title(f"(a) local thickness (solid grey), {2 * half:g} µm window")

        hist.bar(psd.bin_centers, psd.satn, width=psd.bin_widths, color="#0072B2", alpha=0.85)
        hist.set_xlabel("local pore radius r (µm)")
        hist.set_ylabel("share of the pore area")
        hist.set_xlim(0, float(edges[-1]))
        cdf = hist.twinx()
        cdf.plot(psd.bin_centers, 1 - psd.cdf + psd.satn, color="#D55E00")
        cdf.set_ylim(0, 1.02)
        cdf.set_ylabel("cumulative share (radius ≤ r)", color="#D55E00")
        cdf.tick_params(axis="y", colors="#D55E00")
        hist.set_title(f"(b) pore sizes: porosity {porosity:.3f}, {h:.3g} µm pixels")
        fig.savefig(out, dpi=DPI)
        plt.close(fig)
    return out


def main(argv: Sequence[str] | None = None) -> int:
    """Export a packing to images and draw the two figures; returns the exit status."""
    parser = argparse.ArgumentParser(
        description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter
    )
    parser.add_argument("--packing", type=Path, help="packing file (default: pack the small scene)")
    parser.add_argument("--pixel-size", type=float, default=0.0, help="0: d_min / 10")
    parser.add_argument("--out-dir", type=Path, default=IMAGES)
    args = parser.parse_args(argv)
    packing = regopack.load(args.packing) if args.packing else _pack_small()
    args.out_dir.mkdir(parents=True, exist_ok=True)
    with tempfile.TemporaryDirectory() as tmp:
        main_file = export_packing(
            packing,
            "image",
            Path(tmp) / "packing.png",
            registry=default_registry(),
            params={"pixel_size": args.pixel_size},
        )
        files = image_paths(main_file)
        meta = json.loads(files["meta"].read_text(encoding="utf-8"))
        phases = np.load(files["phases"], allow_pickle=False)
        for path in (
            draw_files(packing, files, meta, args.out_dir / "export-image.png"),
            draw_porespy(phases, meta, args.out_dir / "porespy-local-thickness.png"),
        ):
            print(f"wrote {path}")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
