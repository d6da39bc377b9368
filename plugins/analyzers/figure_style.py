"""How the analysis figures look: size, style, files, length units and maps of the packing.

Every figure module draws with these (and none imports another figure
module): the journal width and resolution, the matplotlib style, atomic
files, axis units in the packing's decade, and the frame, zoom window and
links of a map of a 2D packing.
"""

from __future__ import annotations

import math
from collections.abc import Iterator, Sequence
from contextlib import contextmanager
from pathlib import Path
from typing import Any, cast

import matplotlib
import numpy as np
from matplotlib.axes import Axes
from matplotlib.figure import Figure
from matplotlib.patches import ConnectionPatch, Rectangle
from matplotlib.ticker import FuncFormatter
from numpy.typing import NDArray

from regopack.packing.core import Packing, _atomic_file

WIDTH = 7.0
"""Width of the figures in inches (a two-column journal page)."""

DPI = 300
"""Resolution of the PNG files."""

RASTERISE_ABOVE = 2000
"""Collections with more items than this are rasterised inside the SVG files."""

_STYLE: dict[str, Any] = {
    "font.size": 8,
    "axes.titlesize": 8,
    "axes.labelsize": 8,
    "xtick.labelsize": 7,
    "ytick.labelsize": 7,
    "legend.fontsize": 7,
    "legend.frameon": False,
    "axes.linewidth": 0.6,
    "xtick.major.width": 0.6,
    "ytick.major.width": 0.6,
    "xtick.minor.width": 0.4,
    "ytick.minor.width": 0.4,
    "lines.linewidth": 1.0,
    "lines.markersize": 3.5,
    "svg.fonttype": "none",
    "svg.hashsalt": "regopack",
    "figure.constrained_layout.use": True,
}

TOTAL = "#000000"
"""Colour of whole-packing curves (all minerals together)."""


@contextmanager
def style() -> Iterator[None]:
    """Within the block, matplotlib draws in the style of the analysis figures."""
    with matplotlib.rc_context(cast(Any, _STYLE)):
        yield


def save(fig: Figure, out_dir: Path, stem: str, formats: Sequence[str]) -> list[Path]:
    """Write ``fig`` as ``stem.<format>`` for every format, each atomically."""
    paths = []
    for fmt in formats:
        path = out_dir / f"{stem}.{fmt}"
        metadata = {"Date": None} if fmt == "svg" else {}
        with _atomic_file(path) as fh:
            fig.savefig(fh, format=fmt, dpi=DPI, metadata=metadata)
        paths.append(path)
    return paths


DENSITY_DECADES = 3
"""A number density is drawn in 10⁻³ length unit⁻² at the built-in scale."""

_SUPERSCRIPT = str.maketrans("-0123456789", "⁻⁰¹²³⁴⁵⁶⁷⁸⁹")


def axis_unit(power: int, unit: str, scale: float) -> tuple[str, float]:
    """Return the axis unit of a quantity of length dimension ``power``, and its factor.

    The values are drawn in decades of ``unit`` chosen so that they read as at
    the built-in scale (``scale``, :func:`~regopack.base.units.length_scale`, is 1):
    a packing in millimetres draws its coordinates and mean diameter in
    10⁻³ mm and its number density in 10³ mm⁻², the same numbers as µm and
    10⁻³ µm⁻².

    Examples
    --------
    >>> axis_unit(-2, "µm", 1.0), axis_unit(-2, "mm", 1e-3), axis_unit(1, "mm", 1e-3)
    (('10⁻³ µm⁻²', 1000.0), ('10³ mm⁻²', 0.001), ('10⁻³ mm', 1000.0))
    >>> axis_unit(1, "µm", 1.0), axis_unit(0, "µm", 1.0)
    (('µm', 1.0), ('', 1.0))
    """
    if power == 0:
        return "", 1.0
    decade = round(-math.log10(scale)) if math.isfinite(scale) and scale > 0 else 0
    exponent = decade * power + (DENSITY_DECADES if power == -2 else 0)
    text = unit if power == 1 else f"{unit}{str(power).translate(_SUPERSCRIPT)}"
    if exponent == 0:
        return text, 1.0
    return f"10{str(-exponent).translate(_SUPERSCRIPT)} {text}", float(10.0**exponent)


def length_ticks(ax: Axes, unit: str, scale: float) -> str:
    """Write the x and y ticks of a map in the decade of ``unit`` of :func:`axis_unit`.

    Returns the unit text of the axis labels (``unit`` itself at the built-in
    scale, where the ticks are left as matplotlib writes them).
    """
    text, factor = axis_unit(1, unit, scale)
    if factor != 1.0:
        ticks = FuncFormatter(lambda v, _: f"{v * factor:.6g}".replace("-", "\N{MINUS SIGN}"))
        ax.xaxis.set_major_formatter(ticks)
        ax.yaxis.set_major_formatter(ticks)
    return text


def frame(ax: Axes, bounds: Sequence[float], unit: str = "µm", scale: float = 1.0) -> None:
    """Set the limits, equal aspect and labels of a map of the packing.

    Lengths are in ``unit`` at the ``scale`` of the packing (:func:`axis_unit`:
    coordinates of a packing in mm are labelled in 10⁻³ mm).
    """
    xmin, xmax, ymin, ymax = (float(b) for b in bounds)
    ax.set_xlim(xmin, xmax)
    ax.set_ylim(ymin, ymax)
    ax.set_aspect("equal")
    text = length_ticks(ax, unit, scale)
    ax.set_xlabel(f"x ({text})")
    ax.set_ylabel(f"y ({text})")


NICE_STEPS = (1.0, 1.2, 1.5, 2.0, 2.5, 3.0, 4.0, 5.0, 6.0, 8.0, 10.0)
"""Mantissas of the round lengths that zoom windows take."""


def nice_length(length: float, most: float | None = None) -> float:
    """Round ``length`` to the nearest (in ratio) of 1, 1.2, 1.5, 2, 2.5, 3, 4, 5, 6, 8 × 10^k.

    With ``most``, the result is the largest such length not above ``most``
    when the nearest one is (and ``most`` itself when no round length is).

    Examples
    --------
    >>> nice_length(128.447), nice_length(100.0), nice_length(0.0173)
    (120.0, 100.0, 0.015)
    >>> nice_length(128.447, most=110.0)
    100.0
    """
    if not (length > 0 and np.isfinite(length)):
        return length
    exponent = 10.0 ** np.floor(np.log10(length))
    candidates = [float(f"{m * exponent * s:.6g}") for s in (0.1, 1.0) for m in NICE_STEPS]
    if most is not None:
        below = [c for c in candidates if c <= most]
        if not below:
            return most
        if min(candidates, key=lambda c: abs(np.log(c / length))) > most:
            return max(below)
        candidates = below
    return min(candidates, key=lambda c: abs(np.log(c / length)))


def length_text(value: float) -> str:
    """Format a length for a title: three significant digits, no exponent below 10^6.

    Examples
    --------
    >>> length_text(128.447), length_text(1600.0), length_text(0.012345)
    ('128', '1600', '0.0123')
    """
    return f"{float(f'{value:.3g}'):g}"


def zoom_window(packing: Packing) -> tuple[float, float, float, float]:
    """Square window at the domain's centre: an eighth of its size, at least 20 mean radii.

    The side is rounded to a round length (:func:`nice_length`), at most the
    domain's shorter side.
    """
    dom = packing.domain
    short = min(dom.width, dom.height)
    placed = packing.placed
    mean_r = float(packing.radius[placed].mean()) if placed.any() else short / 40
    side = nice_length(min(short, max(short / 8, 20.0 * mean_r)), most=short)
    cx, cy = dom.center
    return cx - side / 2, cx + side / 2, cy - side / 2, cy + side / 2


def zoom_size(window: Sequence[float], unit: str = "µm") -> str:
    """``"120 × 120 µm"`` for a window ``(x0, x1, y0, y1)`` (lengths in ``unit``)."""
    x0, x1, y0, y1 = window
    return f"{length_text(x1 - x0)} × {length_text(y1 - y0)} {unit}"


def in_window(packing: Packing, window: Sequence[float]) -> NDArray[np.int64]:
    """Placed particles that may reach into ``window``."""
    x0, x1, y0, y1 = window
    idx = np.flatnonzero(packing.placed)
    c = packing.centre[idx]
    r = packing.circumradius[idx]
    near = (c[:, 0] + r > x0) & (c[:, 0] - r < x1) & (c[:, 1] + r > y0) & (c[:, 1] - r < y1)
    return idx[near].astype(np.int64)


def link_zoom(fig: Figure, ax: Axes, zoom: Axes, window: Sequence[float], colour: str) -> None:
    """Outline ``window`` on ``ax`` and join its right corners to the left side of ``zoom``."""
    x0, x1, y0, y1 = window
    ax.add_patch(Rectangle((x0, y0), x1 - x0, y1 - y0, fill=False, edgecolor=colour, linewidth=0.9))
    for y_data, y_axes in ((y1, 1.0), (y0, 0.0)):
        fig.add_artist(
            ConnectionPatch(
                xyA=(x1, y_data),
                coordsA=ax.transData,
                xyB=(0.0, y_axes),
                coordsB=zoom.transAxes,
                color=colour,
                linewidth=0.7,
            )
        )


def note(ax: Axes, text: str) -> None:
    """Write ``text`` in grey at the middle of ``ax`` (a panel with nothing to draw)."""
    ax.text(0.5, 0.5, text, transform=ax.transAxes, ha="center", va="center", color="#555555")
