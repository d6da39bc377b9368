"""Shape plugins: polygons, disks, polyhedra, solid templates and spheres.

The names of :mod:`regopack.plugins.shapes.polygons` (the random convex,
regular and template polygons) are offered here as well.
"""

from __future__ import annotations

from typing import TYPE_CHECKING

from regopack._exports import lazy_exports

if TYPE_CHECKING:
    from regopack.plugins.shapes.polygons import RandomConvexPolygon as RandomConvexPolygon
    from regopack.plugins.shapes.polygons import RandomPolygonConfig as RandomPolygonConfig
    from regopack.plugins.shapes.polygons import RegularConfig as RegularConfig
    from regopack.plugins.shapes.polygons import RegularPolygon as RegularPolygon
    from regopack.plugins.shapes.polygons import Template as Template
    from regopack.plugins.shapes.polygons import TemplateConfig as TemplateConfig
    from regopack.plugins.shapes.polygons import TemplateError as TemplateError
    from regopack.plugins.shapes.polygons import TemplatePolygon as TemplatePolygon
    from regopack.plugins.shapes.polygons import TemplateWarning as TemplateWarning
    from regopack.plugins.shapes.polygons import read_templates as read_templates

__all__ = [
    "RandomConvexPolygon",
    "RandomPolygonConfig",
    "RegularConfig",
    "RegularPolygon",
    "Template",
    "TemplateConfig",
    "TemplateError",
    "TemplatePolygon",
    "TemplateWarning",
    "read_templates",
]

__getattr__, __dir__ = lazy_exports(globals(), "regopack.plugins.shapes.polygons")
