"""Hook specifications of regopack.

Every hook returns an iterable of spec records (:mod:`regopack.registry.plugin_types`)
and is called once when the registry is built
(:meth:`regopack.registry.manager.Registry.from_manager`); none is ``firstresult``.
"""

from __future__ import annotations

from collections.abc import Iterable

import pluggy

from regopack.registry.plugin_types import (
    AnalyzerSpec,
    DensityControllerSpec,
    ExporterSpec,
    FigureSpec,
    InserterSpec,
    ShapeSpec,
    SizeDistributionSpec,
)

PROJECT = "regopack"
hookspec = pluggy.HookspecMarker(PROJECT)
hookimpl = pluggy.HookimplMarker(PROJECT)


@hookspec
def regopack_size_distributions() -> Iterable[SizeDistributionSpec]:
    """Return the size distributions this plugin provides.

    Called once when the registry is built. Not ``firstresult``: the results of
    all plugins are collected.

    Example
    -------
    .. code-block:: python

        @hookimpl
        def regopack_size_distributions():
            return [SizeDistributionSpec("fixed", FixedConfig, Fixed)]
    """
    raise NotImplementedError


@hookspec
def regopack_shapes() -> Iterable[ShapeSpec]:
    """Return the particle shape generators this plugin provides.

    Called once when the registry is built. Not ``firstresult``.

    Example
    -------
    .. code-block:: python

        @hookimpl
        def regopack_shapes():
            return [ShapeSpec("square", SquareConfig, Square)]
    """
    raise NotImplementedError


@hookspec
def regopack_inserters() -> Iterable[InserterSpec]:
    """Return the insertion strategies this plugin provides.

    Called once when the registry is built. Not ``firstresult``.

    Example
    -------
    .. code-block:: python

        @hookimpl
        def regopack_inserters():
            return [InserterSpec("rsa", RsaConfig, RandomSequentialAddition)]
    """
    raise NotImplementedError


@hookspec
def regopack_density_controllers() -> Iterable[DensityControllerSpec]:
    """Return the density controllers this plugin provides.

    Called once when the registry is built. Not ``firstresult``.

    Example
    -------
    .. code-block:: python

        @hookimpl
        def regopack_density_controllers():
            return [DensityControllerSpec("none", NoConfig, lambda cfg: Identity())]
    """
    raise NotImplementedError


@hookspec
def regopack_analyzers() -> Iterable[AnalyzerSpec]:
    """Return the structure analyzers this plugin provides.

    Called once when the registry is built. Not ``firstresult``.

    Example
    -------
    .. code-block:: python

        @hookimpl
        def regopack_analyzers():
            return [AnalyzerSpec("density", DensityConfig, Density)]
    """
    raise NotImplementedError


@hookspec
def regopack_exporters() -> Iterable[ExporterSpec]:
    """Return the exporters (file formats of ``regopack export``) this plugin provides.

    Called once when the registry is built. Not ``firstresult``.

    Example
    -------
    .. code-block:: python

        @hookimpl
        def regopack_exporters():
            return [ExporterSpec("xyz", XyzConfig, XyzExporter)]
    """
    raise NotImplementedError


@hookspec
def regopack_analysis_figures() -> Iterable[FigureSpec]:
    """Return the figures this plugin draws for analyzers (its own or other plugins').

    Called once when the registry is built. Not ``firstresult``: the figure
    specs of all plugins are collected, built-in plugins first, and
    :func:`regopack.analysis.pipeline.write_analysis` calls each spec whose analyzer was
    computed, in that order. Several specs may name the same analyzer.

    Example
    -------
    .. code-block:: python

        @hookimpl
        def regopack_analysis_figures():
            return [FigureSpec("shares", draw_shares, {"shares": "Area share per mineral"})]
    """
    raise NotImplementedError
