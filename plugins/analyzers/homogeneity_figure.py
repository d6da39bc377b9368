"""Figures of the homogeneity analyzer: rings and tiles (2D), layers and shells (3D)."""

from __future__ import annotations

from typing import Any

import matplotlib
import matplotlib.colors as mcolors
import numpy as np
from matplotlib.axes import Axes
from matplotlib.cm import ScalarMappable
from matplotlib.figure import Figure
from matplotlib.patches import Polygon as PolygonPatch
from matplotlib.patches import Rectangle
from numpy.typing import NDArray

from regopack.base.units import length_scale, length_unit
from regopack.plugins.analyzers.figure_style import WIDTH, axis_unit, length_ticks, note
from regopack.plugins.analyzers.homogeneity import SECTORS, Homogeneity

__all__ = ["draw_homogeneity", "draw_layers_and_shells"]

PANELS: tuple[tuple[str, str, str, str, int], ...] = (
    ("density", "number_density", "number density ({unit})", "number density", -2),
    ("phi", "phi", "area fraction φ", "area fraction φ", 0),
    ("mean_d", "mean_d", "mean equivalent diameter ({unit})", "mean diameter", 1),
)
"""Result prefix, column, axis label (``{unit}``: the axis unit), short name and the power
of length of each quantity."""


POINTS = "#0072B2"
FIT = "#D55E00"
POINT_STYLE: dict[str, Any] = {
    "fmt": "o",
    "color": POINTS,
    "ecolor": POINTS,
    "elinewidth": 0.6,
    "capsize": 1.5,
    "markersize": 3,
}
"""Markers and error bars of the regions' values."""
MAX_LABELLED_TILES = 36
"""Tile maps with more tiles than this carry no value labels."""


def _profile(
    ax: Axes, h: Homogeneity, prefix: str, column: str, label: str, scale: float, unit: str
) -> None:
    rings = h.rings
    r = np.asarray(rings["r_mean"])
    y = scale * np.asarray(rings[column])
    err = scale * np.asarray(rings[f"{column}_err"])
    if len(r) == 0:
        note(ax, "no rings (empty window)")
        return
    lo, hi = np.asarray(rings["r_inner"]), np.asarray(rings["r_outer"])
    ax.errorbar(
        r,
        y,
        yerr=err,
        xerr=[r - lo, hi - r],
        **POINT_STYLE,
        label=f"rings: value ± 1 standard error (of φ: from its {SECTORS} sectors), ring extent",
    )
    overall = scale * h.overall[column]
    ax.axhline(overall, color="#777777", linestyle=":", linewidth=0.8, label="whole window")
    fit = h.trends[prefix]
    if np.isfinite(fit.slope):
        xs = np.array([0.0, float(hi[-1])])
        ax.plot(
            xs,
            scale * (fit.intercept + fit.slope * xs),
            color=FIT,
            linewidth=1.0,
            label="weighted least-squares trend",
        )
        per = float(h.results()["slope_length"])
        ax.set_title(
            f"trend {scale * fit.slope * per:+.3g} ± "
            f"{scale * fit.slope_err * per:.2g} per {per:g} {unit}",
            fontsize=7,
        )
    ax.set_xlim(0.0, float(hi[-1]))
    ax.set_xlabel(f"distance from the centre ({unit})")
    ax.set_ylabel(label)


def _height_profile(
    ax: Axes,
    layers: Any,
    lo: str,
    hi: str,
    column: str,
    scale: float,
    overall: float,
    fit: tuple[float | None, float | None, float],
    unit: str,
) -> None:
    """One quantity over the layers, bottom to top, with errors, the window's value and its trend.

    ``fit`` is the trend's slope and error per length and that length (from
    the analyzer's ``layer_<q>_slope_per_100``, ``_slope_err`` and
    ``slope_length``), written in the title.
    """
    z0, z1 = np.asarray(layers[lo], dtype=float), np.asarray(layers[hi], dtype=float)
    if z0.size == 0:
        note(ax, "no layers (empty window)")
        return
    z = 0.5 * (z0 + z1)
    y = scale * np.asarray(layers[column], dtype=float)
    spread = scale * np.asarray(layers[f"{column}_err"], dtype=float)
    # densities, fractions and diameters are not negative: the bar stops at zero
    low = np.where(np.isfinite(y), np.minimum(spread, np.maximum(y, 0.0)), spread)
    ax.errorbar(
        z,
        y,
        yerr=np.vstack([low, spread]),
        xerr=[z - z0, z1 - z],
        **POINT_STYLE,
        label="layers: value ± 1 standard error, layer extent",
    )
    if np.isfinite(overall):
        ax.axhline(scale * overall, color="#777777", linestyle=":", linewidth=0.8)
    slope, err, per = fit
    if slope is not None and err is not None:
        text = f"trend {scale * slope:+.3g} ± {scale * err:.2g} per {per:g} {unit}"
        ax.set_title(text, fontsize=7)


def _outline(ax: Axes, xy: NDArray[np.float64], **kwargs: Any) -> None:
    ax.add_patch(PolygonPatch(xy, closed=True, fill=False, **kwargs))


def _tile_map(
    ax: Axes,
    fig: Figure,
    h: Homogeneity,
    column: str,
    scale: float,
    unit: str,
    scale_of_lengths: float = 1.0,
) -> None:
    tiles = h.tiles_table
    values = scale * np.asarray(tiles[column], dtype=np.float64)
    overall = scale * h.overall[column]
    with np.errstate(divide="ignore", invalid="ignore"):
        dev = 100.0 * (values / overall - 1.0)
    finite = dev[np.isfinite(dev)]
    top = max(float(np.max(np.abs(finite))) if finite.size else 1.0, 1.0)
    norm = mcolors.Normalize(vmin=-top, vmax=top)
    cmap = matplotlib.colormaps["RdBu_r"]
    labelled = len(values) <= MAX_LABELLED_TILES
    clip = PolygonPatch(h.window.outline(), closed=True, fill=False, edgecolor="none")
    ax.add_patch(clip)
    for t, value in enumerate(values):
        x0, x1 = float(tiles["x_min"][t]), float(tiles["x_max"][t])
        y0, y1 = float(tiles["y_min"][t]), float(tiles["y_max"][t])
        face = cmap(norm(dev[t])) if np.isfinite(dev[t]) else "#dddddd"
        cell = Rectangle(
            (x0, y0), x1 - x0, y1 - y0, facecolor=face, edgecolor="white", linewidth=0.6
        )
        ax.add_patch(cell)
        cell.set_clip_path(clip)  # a tile shows only its part inside the window
        if labelled and np.isfinite(value):
            dark = np.isfinite(dev[t]) and abs(norm(dev[t]) - 0.5) > 0.35
            ax.text(
                0.5 * (x0 + x1),
                0.5 * (y0 + y1),
                f"{value:.3g}",
                ha="center",
                va="center",
                fontsize=6,
                color="white" if dark else "black",
            )
    _outline(ax, h.window.outline(), edgecolor="black", linewidth=0.8)
    b = h.window.bounds()
    pad = 0.03 * max(float(b[1] - b[0]), float(b[3] - b[2]))
    ax.set_xlim(float(b[0]) - pad, float(b[1]) + pad)
    ax.set_ylim(float(b[2]) - pad, float(b[3]) + pad)
    ax.set_aspect("equal")
    text = length_ticks(ax, unit, scale_of_lengths)
    ax.set_xlabel(f"x ({text})")
    ax.set_ylabel(f"y ({text})")
    bar = fig.colorbar(
        ScalarMappable(norm=norm, cmap=cmap), ax=ax, location="bottom", shrink=0.8, aspect=25
    )
    bar.set_label("tile / window value − 1 (%)")


def draw_homogeneity(packing: Any, h: Homogeneity) -> Figure:
    """Ring profiles of number density, φ and mean diameter with their trends; tile maps.

    A 3D packing gets :func:`draw_layers_and_shells`.
    """
    if packing.domain.dimension == 3:
        return draw_layers_and_shells(h, length_unit(packing))
    res = h.results()
    unit = length_unit(packing)
    shown = [axis_unit(power, unit, length_scale(packing)) for *_, power in PANELS]
    fig = Figure(figsize=(WIDTH, 7.8))
    axes = fig.subplots(3, 3, height_ratios=(1.0, 1.25, 1.0))
    for ax, (prefix, column, label, *_), (text, scale) in zip(axes[0], PANELS, shown, strict=True):
        _profile(ax, h, prefix, column, label.format(unit=text), scale, unit)
    nx, ny = res["tiles"]
    for ax, (_, column, _, short, _), (_, scale) in zip(axes[1], PANELS, shown, strict=True):
        if len(h.tiles_table.get("tile", [])) == 0:
            note(ax, "no tiles (empty window)")
            continue
        _tile_map(ax, fig, h, column, scale, unit, length_scale(packing))
        ax.set_title(f"{short}, {nx} × {ny} tiles")
    for ax, (prefix, column, label, *_), (text, scale) in zip(axes[2], PANELS, shown, strict=True):
        _height_profile(
            ax,
            h.layers,
            "y_min",
            "y_max",
            column,
            scale,
            h.overall[column],
            (
                res[f"layer_{prefix}_slope_per_100"],
                res[f"layer_{prefix}_slope_err"],
                res["slope_length"],
            ),
            unit,
        )
        ax.set_xlabel(f"height y of the layer ({unit})")
        ax.set_ylabel(label.format(unit=text))
    handles, labels = axes[0, 0].get_legend_handles_labels()
    if handles:
        order = [labels.index(t) for t in labels if t.startswith("rings")]
        order += [k for k in range(len(labels)) if k not in order]
        handles, labels = [handles[k] for k in order], [labels[k] for k in order]
        fig.legend(handles, labels, loc="outside lower center", ncol=len(handles))
    fig.suptitle(
        f"{res['n_interior']:,} particles in the interior window "
        f"(margin {res['interior_margin']:g} {unit}): rings of {res['ring_width']:.3g} {unit} "
        f"about the centre, tiles, {res['layers']} layers",
        fontsize=8,
    )
    return fig


SHELL_ERRORS = {"density": "number_density_err", "mean_diameter": "mean_d_err"}
"""The shells' columns drawn with their sampling errors, and the errors' columns."""


def draw_layers_and_shells(homogeneity: Homogeneity, unit: str = "µm") -> Figure:
    """Draw number density, φ and mean diameter over the layers (top) and shells (bottom).

    Each region is drawn at its middle (the layer's height, the shell's mean
    half width); the layers with their sampling errors, a dotted line at the
    whole window's value and the trend with height in the title; the shells
    with a dashed line at the mean over them; lengths are
    labelled in ``unit``.
    """
    fig = Figure(figsize=(WIDTH, 4.4))
    axes = fig.subplots(2, 3)
    rows = (
        (homogeneity.layers, "z_lo", "z_hi", f"height z of the layer ({unit})"),
        (homogeneity.shells, "half_lo", "half_hi", f"half width of the shell ({unit})"),
    )
    columns = (
        ("density", f"number density (1/{unit}³)"),
        ("phi", "volume fraction φ"),
        ("mean_diameter", f"mean diameter ({unit})"),
    )
    res = homogeneity.results()
    for col, (prefix, column) in enumerate(
        (("density", "number_density"), ("phi", "phi"), ("mean_d", "mean_d"))
    ):
        ax = axes[0, col]
        overall = res.get(column)
        _height_profile(
            ax,
            homogeneity.layers,
            "z_lo",
            "z_hi",
            column,
            1.0,
            float("nan") if overall is None else float(overall),
            (
                res[f"layer_{prefix}_slope_per_100"],
                res[f"layer_{prefix}_slope_err"],
                res["slope_length"],
            ),
            unit,
        )
        ax.set_xlabel(rows[0][3])
        ax.set_ylabel(columns[col][1])
    for row, (table, lo, hi, xlabel) in enumerate(rows):
        if row == 0:
            continue
        x = 0.5 * (np.asarray(table[lo]) + np.asarray(table[hi]))
        for col, (key, ylabel) in enumerate(columns):
            ax = axes[row, col]
            y = np.asarray(table[key], dtype=float)
            err_key = SHELL_ERRORS.get(key)
            if x.size:
                ax.plot(x, y, marker="o", markersize=3, linewidth=0.9, color="#0072B2")
                if err_key is not None and err_key in table:
                    err = np.asarray(table[err_key], dtype=float)
                    # counts and diameters are not negative: the bar stops at zero
                    low = np.where(np.isfinite(y), np.minimum(err, np.maximum(y, 0.0)), err)
                    ax.errorbar(
                        x,
                        y,
                        yerr=np.vstack([low, err]),
                        fmt="none",
                        ecolor="#0072B2",
                        elinewidth=0.7,
                        capsize=2,
                    )
                finite = y[np.isfinite(y)]
                if finite.size:
                    mean = float(finite.mean())
                    ax.axhline(mean, color="0.4", linestyle="--", linewidth=0.7)
                    spread = float(finite.std() / mean) if mean else float("nan")
                    ax.set_title(f"mean {mean:.4g}, spread {100 * spread:.1f} %", fontsize=7)
            else:
                note(ax, "no interior window")
            ax.set_xlabel(xlabel)
            ax.set_ylabel(ylabel)
    fig.suptitle(
        "Interior window: layers along z (± 1 standard error; dotted: the whole window), "
        "shells about the centre (± 1 standard error)",
        fontsize=8,
    )
    return fig
