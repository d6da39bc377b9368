"""Spec records that plugins return from their hooks.

Each record names one implementation, the pydantic model that validates its
parameters (``extra="forbid"``, every field described) and a factory that
builds the implementation from a validated config.
"""

from __future__ import annotations

from collections.abc import Callable, Mapping, Sequence
from dataclasses import dataclass, field
from pathlib import Path
from typing import TYPE_CHECKING, Any, Generic, TypeVar

from pydantic import BaseModel

from regopack.registry.interfaces import (
    Analyzer,
    DensityController,
    Exporter,
    InsertionStrategy,
    ShapeGenerator,
    SizeDistribution,
    SolidGenerator,
)

if TYPE_CHECKING:
    from regopack.packing.core import Packing

T = TypeVar("T")


@dataclass(frozen=True)
class PluginSpec(Generic[T]):
    """One named implementation of a plugin kind.

    Attributes
    ----------
    name
        The ``kind`` users write in a scene (e.g. ``"octagon"``).
    config_model
        Pydantic model of the parameters.
    factory
        Builds the implementation from a validated ``config_model`` instance.
    description
        One sentence shown by the command line and the docs.
    aliases
        Old names that still select this implementation, for one release:
        :meth:`regopack.registry.manager.Registry.get` warns with a
        :class:`~regopack.base.errors.DeprecatedNameWarning` naming :attr:`name`
        (keyword only).
    alias_dimensions
        Dimensions the old names served, when fewer than the implementation's
        (``contacts3d``: 3); an old name asked for in another dimension is
        refused as it was before (keyword only; empty: no restriction).
    """

    name: str
    config_model: type[BaseModel]
    factory: Callable[[Any], T]
    description: str = ""
    aliases: tuple[str, ...] = field(default=(), kw_only=True)
    alias_dimensions: tuple[int, ...] = field(default=(), kw_only=True)

    def build(self, params: dict[str, Any]) -> T:
        """Validate ``params`` with :attr:`config_model` and build the implementation."""
        return self.factory(self.config_model.model_validate(params))


class SizeDistributionSpec(PluginSpec[SizeDistribution]):
    """Spec of a size distribution plugin."""


@dataclass(frozen=True)
class ShapeSpec(PluginSpec[ShapeGenerator | SolidGenerator]):
    """Spec of a shape generator plugin.

    ``dimension`` is 2 for outlines (a :class:`~regopack.registry.interfaces.ShapeGenerator`)
    and 3 for solids (a :class:`~regopack.registry.interfaces.SolidGenerator`).
    """

    dimension: int = 2


@dataclass(frozen=True)
class InserterSpec(PluginSpec[InsertionStrategy]):
    """Spec of an insertion strategy plugin; ``dimensions`` lists the dimensions it packs."""

    dimensions: tuple[int, ...] = (2,)


class DensityControllerSpec(PluginSpec[DensityController]):
    """Spec of a density controller plugin."""


@dataclass(frozen=True)
class AnalyzerSpec(PluginSpec[Analyzer]):
    """Spec of an analyzer plugin; ``dimensions`` lists the dimensions of packings it analyses."""

    dimensions: tuple[int, ...] = (2,)


@dataclass(frozen=True)
class ExporterSpec(PluginSpec[Exporter[Any]]):
    """Spec of an exporter plugin; ``dimensions`` lists the dimensions of the packings it writes.

    Its factory builds an :class:`~regopack.registry.interfaces.Exporter`, for
    2D packings unless ``dimensions`` says otherwise (``(2, 3)``: both).
    """

    dimensions: tuple[int, ...] = (2,)


def served_dimensions(spec: PluginSpec[Any], name: str) -> tuple[int, ...]:
    """Dimensions that ``name``, the spec's own name or one of its old names, serves.

    An old name serves :attr:`PluginSpec.alias_dimensions` when the spec gives
    them (``vtk3d``: 3D); otherwise every name serves the spec's
    ``dimensions`` (2D when it has none).

    Examples
    --------
    >>> spec = ExporterSpec("vtk", BaseModel, object, dimensions=(2, 3), aliases=("vtk3d",),
    ...                     alias_dimensions=(3,))
    >>> served_dimensions(spec, "vtk"), served_dimensions(spec, "vtk3d")
    ((2, 3), (3,))
    """
    if name != spec.name and spec.alias_dimensions:
        return tuple(spec.alias_dimensions)
    return tuple(getattr(spec, "dimensions", (2,)))


def field_dimensions(model: type[BaseModel]) -> dict[str, tuple[int, ...]]:
    """Return the parameters of ``model`` that have a meaning in some dimensions only.

    A field declares them as ``Field(..., json_schema_extra={"dimensions": [2]})``
    (``homogeneity.tiles``: 2D, ``homogeneity.shells``: 3D); the schema shows
    them, and a scene or call that sets one for a packing of another dimension
    is refused before anything is packed (:func:`misplaced_field`).
    """
    out: dict[str, tuple[int, ...]] = {}
    for name, info in model.model_fields.items():
        extra = info.json_schema_extra
        dims = extra.get("dimensions") if isinstance(extra, dict) else None
        if isinstance(dims, list | tuple):
            out[name] = tuple(int(d) for d in dims if isinstance(d, int))
    return out


def misplaced_field(config: BaseModel, dimension: int) -> tuple[str, str] | None:
    """Find the first parameter set in ``config`` that has no meaning in ``dimension``.

    Returns the field's name and one line starting with it (the caller puts
    where it was given before it); ``None`` when every set parameter fits.
    """
    dims = field_dimensions(type(config))
    for name in sorted(config.model_fields_set):
        own = dims.get(name)
        if own and dimension not in own and getattr(config, name) is not None:
            fitting = [f for f, d in dims.items() if dimension in d]
            hint = f"; its {dimension}D parameters: {', '.join(fitting)}" if fitting else ""
            return name, (
                f"{name} = {getattr(config, name)!r}: has no meaning for a {dimension}D packing, "
                f"only for {' or '.join(f'{d}D' for d in own)} ones{hint}"
            )
    return None


KINDS: dict[str, type[PluginSpec[Any]]] = {
    "size": SizeDistributionSpec,
    "shape": ShapeSpec,
    "insertion": InserterSpec,
    "density": DensityControllerSpec,
    "analysis": AnalyzerSpec,
    "export": ExporterSpec,
}
"""Plugin kinds by the scene section that selects them."""


FigureMaker = Callable[["Packing", Mapping[str, Analyzer], Path], Sequence[Path]]
"""``draw(packing, analyzers, out_dir)``: draw into ``out_dir``, return the files written."""


@dataclass(frozen=True)
class FigureSpec:
    """Figures of one analyzer, drawn into an analysis folder.

    Returned by :func:`regopack.registry.hookspecs.regopack_analysis_figures`. Unlike the
    records of :data:`KINDS`, a figure spec has no parameters and no name of
    its own: it belongs to the analyzer it draws.

    Attributes
    ----------
    analyzer
        Name of the analyzer whose results the figures show;
        :func:`regopack.analysis.pipeline.write_analysis` calls :attr:`draw` only when
        that analyzer was computed.
    draw
        ``draw(packing, analyzers, out_dir)`` receives the packing, every
        computed analyzer by name and the figures folder (``figures/`` of the
        analysis; create it when writing into it). It returns the files it
        wrote: each PNG file is embedded in ``report.md``, and an SVG file of
        the same stem is linked beside it.
    captions
        Caption of each figure in ``report.md``, by file stem (default: the
        stem with its hyphens as spaces).
    """

    analyzer: str
    draw: FigureMaker
    captions: Mapping[str, str] = field(default_factory=dict)
