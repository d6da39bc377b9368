"""The ``svg`` exporter: a picture of the placed particles, coloured by mineral."""

from __future__ import annotations

from collections.abc import Mapping
from pathlib import Path
from xml.sax.saxutils import escape, quoteattr

import numpy as np
from pydantic import BaseModel, ConfigDict, Field

from regopack.geometry.domain import Circle, Rectangle
from regopack.packing.core import Packing
from regopack.plugins.exporters.export_common import _mineral_name, _write_text
from regopack.registry.interfaces import Analyzer, Exporter

__all__ = ["SvgConfig", "SvgExporter"]


class SvgConfig(BaseModel):
    """Parameters of the SVG exporter."""

    model_config = ConfigDict(extra="forbid", strict=True)

    width_px: int = Field(
        1000, gt=0, description="Width of the picture in pixels; the height keeps the aspect."
    )
    stroke_width: float = Field(
        0.0,
        ge=0,
        description="Width of the particle outlines in the length unit; 0 draws no outline.",
    )
    domain_outline: bool = Field(True, description="Draw the outline of the domain.")
    digits: int = Field(
        10, ge=4, le=17, description="Significant digits of the coordinates in the file."
    )


class SvgExporter(Exporter[Packing]):
    """Picture of the placed particles, coloured by mineral.

    The ``viewBox`` is in the scene's length unit and the y axis points up (the
    drawing is flipped with ``scale(1,-1)``). Particles are ``<polygon>``
    elements grouped by mineral (one ``<g>`` per mineral, with the colours of
    the analysis figures); the domain is a ``<rect>`` (rectangles), ``<circle>``
    or ``<polygon>``.
    """

    suffix = ".svg"

    def __init__(self, config: SvgConfig | None = None) -> None:
        self.config = config or SvgConfig()

    def export(
        self, packing: Packing, path: Path, *, analyses: Mapping[str, Analyzer] | None = None
    ) -> Path:
        """Write the picture; return ``path``."""
        from regopack.base.colours import mineral_colours

        cfg = self.config
        path = Path(path)
        d = packing.domain
        xmin, xmax, ymin, ymax = (float(v) for v in d.bounds())
        width, height = xmax - xmin, ymax - ymin

        def num(x: float) -> str:
            return format(float(x), f".{cfg.digits}g")

        height_px = max(1, round(cfg.width_px * height / width)) if width > 0 else cfg.width_px
        view = " ".join(num(v) for v in (xmin, -ymax, width, height))
        title = f"regopack packing: {packing.scene.get('name', '?')}, seed {packing.seed}"
        lines = [
            '<?xml version="1.0" encoding="UTF-8"?>',
            f'<svg xmlns="http://www.w3.org/2000/svg" viewBox="{view}" '
            f'width="{cfg.width_px}" height="{height_px}">',
            f"<title>{escape(title)}</title>",
            '<g transform="scale(1,-1)">',
        ]
        if cfg.domain_outline:
            line = num(0.002 * max(width, height))
            style = f'fill="none" stroke="#000000" stroke-width="{line}"'
            if isinstance(d, Rectangle):
                lines.append(
                    f'<rect class="domain" x="{num(xmin)}" y="{num(ymin)}" width="{num(width)}" '
                    f'height="{num(height)}" {style}/>'
                )
            elif isinstance(d, Circle):
                lines.append(
                    f'<circle class="domain" cx="{num(d.cx)}" cy="{num(d.cy)}" '
                    f'r="{num(d.radius)}" {style}/>'
                )
            else:
                corners = " ".join(f"{num(x)},{num(y)}" for x, y in d.outline())
                lines.append(f'<polygon class="domain" points="{corners}" {style}/>')
        colours = mineral_colours(packing.mineral_names)
        idx = np.flatnonzero(packing.placed)
        polygons = packing.polygons(idx)
        stroke = (
            f' stroke="#000000" stroke-width="{num(cfg.stroke_width)}"'
            if cfg.stroke_width > 0
            else ""
        )
        minerals = packing.mineral[idx]
        for k in sorted(set(minerals.tolist())):
            colour = colours[k % len(colours)] if colours else "#999999"
            name = quoteattr(_mineral_name(packing, k))
            lines.append(
                f'<g class="mineral" id="mineral-{k}" data-mineral={name} fill="{colour}"{stroke}>'
            )
            for j, poly in zip(idx.tolist(), polygons, strict=True):
                if packing.mineral[j] != k:
                    continue
                points = " ".join(f"{num(x)},{num(y)}" for x, y in poly.tolist())
                lines.append(f'<polygon data-index="{j}" points="{points}"/>')
            lines.append("</g>")
        lines += ["</g>", "</svg>"]
        _write_text(path, "\n".join(lines) + "\n")
        return path
