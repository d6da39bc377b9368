"""Plugin manager and registry of plugin implementations.

The plugin manager is built by :func:`build_plugin_manager`, never at import
time. It registers the built-in plugins listed in :data:`BUILTIN_PLUGINS`,
then third-party plugins from the ``regopack`` entry-point group (unless
autoloading is turned off), and rejects hook implementations that match no
hook specification.

:class:`Registry` calls every hook once and flattens the spec records by plugin
kind (``"size"``, ``"shape"``, ``"insertion"``, ``"density"``, ``"analysis"``,
``"export"``); the figure specs of the analyses, which belong to no kind, are
kept in order beside them (:meth:`Registry.figures`). A spec's old names
(its ``aliases``) still select it, with a deprecation warning (:meth:`Registry.get`).
"""

from __future__ import annotations

import importlib
import importlib.metadata
import os
import types
import warnings
from collections.abc import Iterable, Iterator, Mapping, Sequence
from dataclasses import dataclass
from typing import Any

import pluggy
from pydantic import BaseModel

from regopack.base.errors import DeprecatedNameWarning, PluginError
from regopack.base.messages import closest
from regopack.registry import hookspecs
from regopack.registry.plugin_types import KINDS, FigureSpec, PluginSpec

__all__ = [
    "BUILTIN_PLUGINS",
    "DISABLE_AUTOLOAD_ENV",
    "ENTRY_POINT_GROUP",
    "HOOK_OF_KIND",
    "PluginInfo",
    "Registry",
    "build_plugin_manager",
    "default_registry",
]

BUILTIN_PLUGINS: tuple[str, ...] = (
    "regopack.plugins.sizes.change5",
    "regopack.plugins.shapes.octagon",
    "regopack.plugins.inserters.available_arc",
    "regopack.plugins.density.eta",
    "regopack.plugins.density.target",
    "regopack.plugins.analyzers",
    "regopack.plugins.sizes.distributions",
    "regopack.plugins.shapes.polygons",
    "regopack.plugins.shapes.disk",
    "regopack.plugins.shapes.sphere",
    "regopack.plugins.shapes.polyhedra.shape",
    "regopack.plugins.shapes.solid_templates.shape",
    "regopack.plugins.inserters.available_surface.inserter",
    "regopack.plugins.inserters.rsa",
    "regopack.plugins.exporters",
    "regopack.plugins.exporters.image_export",
    "regopack.plugins.exporters.gsd_export",
)
"""Modules of the built-in plugins, imported and registered in this order."""

ENTRY_POINT_GROUP = "regopack"
"""Entry-point group through which third-party plugins are found."""

DISABLE_AUTOLOAD_ENV = "REGOPACK_DISABLE_PLUGIN_AUTOLOAD"
"""Environment variable that, when set to a non-empty value, turns entry-point loading off."""

HOOK_OF_KIND: dict[str, str] = {
    "size": "regopack_size_distributions",
    "shape": "regopack_shapes",
    "insertion": "regopack_inserters",
    "density": "regopack_density_controllers",
    "analysis": "regopack_analyzers",
    "export": "regopack_exporters",
}
"""Hook that provides each plugin kind.

The kinds are the keys of :data:`~regopack.registry.plugin_types.KINDS`.
"""


def build_plugin_manager(
    *,
    autoload: bool | None = None,
    extra: Iterable[object] = (),
    builtins: Sequence[str] = BUILTIN_PLUGINS,
) -> pluggy.PluginManager:
    """Build a plugin manager with the built-in and installed plugins.

    Parameters
    ----------
    autoload
        Load third-party plugins from the ``regopack`` entry-point group. The
        default (``None``) loads them unless the environment variable
        ``REGOPACK_DISABLE_PLUGIN_AUTOLOAD`` is set to a non-empty value.
    extra
        Further plugin objects (modules or instances with hook implementations)
        to register, e.g. fakes in tests.
    builtins
        Module names of the built-in plugins to import and register.

    Returns
    -------
    pluggy.PluginManager
        The manager, with every hook implementation checked against its spec.

    Raises
    ------
    PluginError
        If a plugin is registered twice or implements a hook that does not exist.

    Examples
    --------
    >>> pm = build_plugin_manager(autoload=False, builtins=())
    >>> pm.get_plugins()
    set()
    """
    pm = pluggy.PluginManager(hookspecs.PROJECT)
    pm.add_hookspecs(hookspecs)
    modules = [(name, importlib.import_module(name)) for name in builtins]
    try:
        for module_name, module in modules:
            pm.register(module, name=module_name)
        if autoload is None:
            autoload = not os.environ.get(DISABLE_AUTOLOAD_ENV)
        if autoload:
            pm.load_setuptools_entrypoints(ENTRY_POINT_GROUP)
        for plugin in extra:
            pm.register(plugin)
        pm.check_pending()
    except (ValueError, pluggy.PluginValidationError) as err:
        raise PluginError(f"cannot register plugin: {_one_line(str(err))}") from err
    return pm


def _one_line(text: str) -> str:
    return " ".join(text.split())


@dataclass(frozen=True)
class PluginInfo:
    """Where a plugin implementation comes from.

    Attributes
    ----------
    plugin
        Name of the plugin in the plugin manager: the module name of a built-in
        plugin, the entry-point name of an installed one.
    module
        Module that holds the hook implementations.
    distribution
        Distribution package that installed the plugin (``"regopack"`` for the
        built-in plugins), or ``None`` when it is not known, e.g. for a module
        passed to :func:`regopack.testing.make_registry` from a source tree.
    version
        Version of ``distribution``, or ``None``.

    Examples
    --------
    >>> PluginInfo("square", "regopack_square", "regopack-square", "0.1.0").package
    'regopack-square 0.1.0'
    >>> PluginInfo("fake", "fakes", None, None).package
    '-'
    """

    plugin: str
    module: str
    distribution: str | None = None
    version: str | None = None

    @property
    def package(self) -> str:
        """``"<distribution> <version>"``, or ``"-"`` when the distribution is unknown."""
        if self.distribution is None:
            return "-"
        return f"{self.distribution} {self.version}" if self.version else self.distribution


def _module_of(plugin: object) -> str:
    if isinstance(plugin, types.ModuleType):
        return plugin.__name__
    return str(getattr(type(plugin), "__module__", "") or type(plugin).__name__)


def _distribution_of_module(module: str) -> tuple[str | None, str | None]:
    """Distribution named like the top-level package of ``module``, and its version."""
    top = module.partition(".")[0]
    if not top:
        return None, None
    try:
        dist = importlib.metadata.distribution(top)
    except (importlib.metadata.PackageNotFoundError, ValueError):
        return None, None
    return str(dist.metadata["Name"] or top), dist.version


def _plugin_infos(pm: pluggy.PluginManager) -> dict[str, PluginInfo]:
    """Map plugin names to where they come from.

    Plugins loaded from an entry point are attributed to the distribution that
    declares the entry point; the others to the distribution that installed
    the distribution named like their top-level package (``regopack`` for the
    built-in plugins), where one is installed.
    """
    from_entry_points: dict[str, tuple[str, str | None]] = {}
    for plugin, dist in pm.list_plugin_distinfo():
        name = pm.get_name(plugin)
        if name is not None:
            project = str(getattr(dist, "project_name", None) or dist.metadata["name"])
            from_entry_points[name] = (project, getattr(dist, "version", None))
    out: dict[str, PluginInfo] = {}
    for name, plugin in pm.list_name_plugin():
        if plugin is None:  # blocked plugin
            continue
        module = _module_of(plugin)
        found: tuple[str | None, str | None] | None = from_entry_points.get(name)
        dist_name, version = found or _distribution_of_module(module)
        out[name] = PluginInfo(name, module, dist_name, version)
    return out


def _hook_records(
    pm: pluggy.PluginManager, hook_name: str, record_type: type, origins: Mapping[str, str]
) -> Iterator[tuple[Any, str, Any]]:
    """Yield ``(hookimpl, origin, record)`` for every record the hook's implementations return.

    Wrappers are skipped and an implementation may return ``None``; anything
    that is not an iterable of records (a bare record included) is refused
    in one line naming the plugin.
    """
    for impl in getattr(pm.hook, hook_name).get_hookimpls():
        if impl.hookwrapper or getattr(impl, "wrapper", False):
            continue
        origin = origins.get(impl.plugin_name, impl.plugin_name)
        records = impl.function()
        if records is None:
            continue
        if isinstance(records, record_type) or not isinstance(records, Iterable):
            raise PluginError(
                f"plugin {origin!r}: {hook_name} must return an iterable of "
                f"{record_type.__name__}, got {type(records).__name__}"
            )
        for record in records:
            yield impl, origin, record


def _origins(pm: pluggy.PluginManager) -> dict[str, str]:
    """Map plugin names to the distribution that installed them, where known."""
    out: dict[str, str] = {}
    for plugin, dist in pm.list_plugin_distinfo():
        name = pm.get_name(plugin)
        if name is not None:
            out[name] = str(getattr(dist, "project_name", None) or dist.metadata["name"])
    return out


class Registry:
    """Plugin implementations by kind and name.

    Parameters
    ----------
    specs
        ``specs[kind][name] = (spec, origin)`` where ``origin`` names the plugin
        (or its distribution) that provided the spec. Use :meth:`from_manager`
        rather than building this mapping by hand.
    infos
        ``infos[kind][name]``: where each implementation comes from (see
        :meth:`info`); by default only the ``origin`` is known.
    figures
        Figure specs (see :meth:`figures`), in the order they are drawn.

    Examples
    --------
    >>> reg = Registry.from_manager(build_plugin_manager(autoload=False, builtins=()))
    >>> reg.names("shape")
    []
    """

    def __init__(
        self,
        specs: Mapping[str, Mapping[str, tuple[PluginSpec[Any], str]]],
        infos: Mapping[str, Mapping[str, PluginInfo]] | None = None,
        figures: Sequence[FigureSpec] = (),
    ) -> None:
        self._specs: dict[str, dict[str, tuple[PluginSpec[Any], str]]] = {
            kind: dict(specs.get(kind, {})) for kind in KINDS
        }
        self._infos: dict[str, dict[str, PluginInfo]] = {
            kind: dict((infos or {}).get(kind, {})) for kind in KINDS
        }
        self._figures: tuple[FigureSpec, ...] = tuple(figures)
        self._aliases = {kind: _aliases_of(kind, self._specs[kind]) for kind in KINDS}
        self._warned: set[tuple[str, str]] = set()

    @classmethod
    def from_manager(cls, pm: pluggy.PluginManager) -> Registry:
        """Call every hook of ``pm`` once and collect the spec records.

        Raises
        ------
        PluginError
            If two plugins claim the same name (or old name) within a kind (the
            message names both), or a hook returns something other than that
            kind's spec records.
        """
        origins = _origins(pm)
        plugin_infos = _plugin_infos(pm)
        specs: dict[str, dict[str, tuple[PluginSpec[Any], str]]] = {kind: {} for kind in KINDS}
        infos: dict[str, dict[str, PluginInfo]] = {kind: {} for kind in KINDS}
        for kind, hook_name in HOOK_OF_KIND.items():
            record_type = KINDS[kind]
            for impl, origin, record in _hook_records(pm, hook_name, record_type, origins):
                cls._check_record(record, record_type, origin, hook_name)
                previous = specs[kind].get(record.name)
                if previous is not None:
                    raise PluginError(
                        f"{kind} kind {record.name!r} is provided by two plugins: "
                        f"{previous[1]!r} and {origin!r}"
                    )
                specs[kind][record.name] = (record, origin)
                infos[kind][record.name] = plugin_infos.get(
                    impl.plugin_name, PluginInfo(impl.plugin_name, _module_of(impl.plugin))
                )
        return cls(specs, infos, cls._collect_figures(pm, origins))

    @staticmethod
    def _collect_figures(pm: pluggy.PluginManager, origins: Mapping[str, str]) -> list[FigureSpec]:
        """Call the figure hook of every plugin, in order.

        The hook is :func:`~regopack.registry.hookspecs.regopack_analysis_figures`.
        """
        figures: list[FigureSpec] = []
        hook_name = "regopack_analysis_figures"
        for _, origin, record in _hook_records(pm, hook_name, FigureSpec, origins):
            if not isinstance(record, FigureSpec):
                raise PluginError(
                    f"plugin {origin!r}: regopack_analysis_figures returned a "
                    f"{type(record).__name__}, expected FigureSpec"
                )
            if not isinstance(record.analyzer, str) or not record.analyzer:
                raise PluginError(f"plugin {origin!r}: a FigureSpec names no analyzer")
            if not callable(record.draw):
                raise PluginError(
                    f"plugin {origin!r}: the FigureSpec of {record.analyzer!r} has no callable draw"
                )
            captions = record.captions
            if not isinstance(captions, Mapping) or not all(
                isinstance(k, str) and isinstance(v, str) for k, v in captions.items()
            ):
                raise PluginError(
                    f"plugin {origin!r}: the captions of the FigureSpec of "
                    f"{record.analyzer!r} must map file stems to texts"
                )
            figures.append(record)
        return figures

    @staticmethod
    def _check_record(
        record: object, record_type: type[PluginSpec[Any]], origin: str, hook_name: str
    ) -> None:
        if not isinstance(record, record_type):
            raise PluginError(
                f"plugin {origin!r}: {hook_name} returned a {type(record).__name__}, "
                f"expected {record_type.__name__}"
            )
        if not isinstance(record.name, str) or not record.name:
            raise PluginError(f"plugin {origin!r}: {hook_name} returned a record without a name")
        model = record.config_model
        if not (isinstance(model, type) and issubclass(model, BaseModel)):
            raise PluginError(
                f"plugin {origin!r}: {record_type.__name__} {record.name!r} has a config_model "
                "that is not a pydantic model class"
            )
        if not callable(record.factory):
            raise PluginError(
                f"plugin {origin!r}: {record_type.__name__} {record.name!r} has no callable factory"
            )
        aliases = record.aliases
        if not isinstance(aliases, tuple) or not all(isinstance(a, str) and a for a in aliases):
            raise PluginError(
                f"plugin {origin!r}: the aliases of {record_type.__name__} {record.name!r} "
                "must be a tuple of names"
            )
        dims = getattr(record, "alias_dimensions", ())
        if not isinstance(dims, tuple) or not all(d in (2, 3) for d in dims):
            raise PluginError(
                f"plugin {origin!r}: the alias_dimensions of {record_type.__name__} "
                f"{record.name!r} must be a tuple of 2 and 3"
            )

    def _kind(self, kind: str) -> dict[str, tuple[PluginSpec[Any], str]]:
        try:
            return self._specs[kind]
        except KeyError:
            raise PluginError(
                f"unknown plugin kind {kind!r}; known plugin kinds: {', '.join(KINDS)}"
            ) from None

    def get(self, kind: str, name: str) -> PluginSpec[Any]:
        """Return the spec registered as ``name`` for ``kind``.

        An old name of a spec (see :attr:`PluginSpec.aliases
        <regopack.registry.plugin_types.PluginSpec.aliases>`) gives that spec and
        warns, once per registry, with a
        :class:`~regopack.base.errors.DeprecatedNameWarning` naming the new name.

        Raises
        ------
        PluginError
            One line naming the unknown name and the known ones, e.g.
            ``unknown shape kind 'octagn'; did you mean 'octagon'? known kinds: octagon``.
        """
        new = self.canonical(kind, name)
        if new != name and (kind, name) not in self._warned:
            self._warned.add((kind, name))
            warnings.warn(
                f"the {kind} kind {name!r} is deprecated and will be removed in the next "
                f"release; use {new!r}",
                DeprecatedNameWarning,
                stacklevel=2,
            )
        return self._specs[kind][new][0]

    def canonical(self, kind: str, name: str) -> str:
        """Return the name registered for ``name``: ``name`` itself, or the new name of an old one.

        Unlike :meth:`get` it does not warn. Raises :class:`PluginError` as :meth:`get` does.

        Examples
        --------
        >>> default_registry(autoload=False).canonical("analysis", "contacts3d")
        'contacts'
        """
        specs = self._kind(kind)
        if name in specs:
            return name
        new = self._aliases[kind].get(name)
        if new is not None:
            return new
        known = ", ".join(sorted(specs)) or "(none)"
        guess = closest(name, sorted(specs))
        hint = f" did you mean {guess!r}?" if guess is not None else ""
        raise PluginError(f"unknown {kind} kind {name!r};{hint} known kinds: {known}")

    def names(self, kind: str) -> list[str]:
        """Sorted names registered for ``kind`` (without the old names, see :meth:`aliases`)."""
        return sorted(self._kind(kind))

    def aliases(self, kind: str) -> dict[str, str]:
        """Return the old names of ``kind`` that still work, each with the name that replaced it."""
        self._kind(kind)
        return dict(sorted(self._aliases[kind].items()))

    def origin(self, kind: str, name: str) -> str:
        """Name of the plugin (or the distribution that installed it) providing ``name``."""
        return self._kind(kind)[self.canonical(kind, name)][1]

    def info(self, kind: str, name: str) -> PluginInfo:
        """Where the implementation ``name`` of ``kind`` comes from.

        Examples
        --------
        >>> info = default_registry(autoload=False).info("shape", "octagon")
        >>> info.module, info.distribution
        ('regopack.plugins.shapes.octagon', 'regopack')
        """
        name = self.canonical(kind, name)
        found = self._infos[kind].get(name)
        if found is None:
            origin = self._specs[kind][name][1]
            return PluginInfo(plugin=origin, module=origin)
        return found

    def figures(self, analyzer: str | None = None) -> tuple[FigureSpec, ...]:
        """Figure specs of the plugins, built-in plugins first, or those of ``analyzer``.

        Examples
        --------
        >>> [f.analyzer for f in default_registry(autoload=False).figures("rdf")]
        ['rdf']
        """
        if analyzer is None:
            return self._figures
        return tuple(f for f in self._figures if f.analyzer == analyzer)

    def __contains__(self, item: object) -> bool:
        """Whether ``(kind, name)`` is registered, under that name or as an old name."""
        if not (isinstance(item, tuple) and len(item) == 2):
            return False
        kind, name = item
        return kind in self._specs and (name in self._specs[kind] or name in self._aliases[kind])

    def __repr__(self) -> str:
        parts = (f"{kind}={sorted(names)}" for kind, names in self._specs.items())
        return f"Registry({', '.join(parts)})"


def _aliases_of(kind: str, specs: Mapping[str, tuple[PluginSpec[Any], str]]) -> dict[str, str]:
    """Map every old name of a spec of ``kind`` to the spec's name.

    Raises
    ------
    PluginError
        When an old name is also a name, or the old name of two specs (naming both plugins).
    """
    out: dict[str, str] = {}
    for name, (spec, origin) in specs.items():
        for alias in getattr(spec, "aliases", ()):
            taken = specs.get(alias) or (specs[out[alias]] if alias in out else None)
            if taken is not None:
                raise PluginError(
                    f"{kind} kind {alias!r} is an old name of {name!r} ({origin!r}) "
                    f"and also names {taken[0].name!r} ({taken[1]!r})"
                )
            out[alias] = name
    return out


def default_registry(*, autoload: bool | None = None) -> Registry:
    """Build a fresh registry of the built-in and installed plugins (nothing is cached)."""
    return Registry.from_manager(build_plugin_manager(autoload=autoload))
