"""Write a packing in another program's file format through an exporter plugin.

The formats are the plugins of kind ``"export"`` (see
:func:`regopack.registry.hookspecs.regopack_exporters`); the built-in ones are ``vtk``,
``lammps`` and ``gsd`` for packings of both dimensions, ``csv``, ``json``,
``svg`` and ``image`` for 2D packings, and ``stl`` and ``slice`` for 3D
packings. Each exporter's spec lists the dimensions it writes; a packing of
another dimension is refused in one line that names the exporters that fit.
An exporter names the suffix of its main file per dimension
(:meth:`~regopack.registry.interfaces.Exporter.suffix_for`: ``vtk`` writes
``.vtp`` polygons and ``.vtu`` polyhedra).

Examples
--------
>>> import tempfile
>>> from regopack.registry.manager import default_registry
>>> from regopack.testing import packing_from_polygons
>>> p = packing_from_polygons([[(0, 0), (1, 0), (1, 1), (0, 1)]])
>>> with tempfile.TemporaryDirectory() as tmp:
...     path = export_packing(p, "svg", Path(tmp) / "p.svg", registry=default_registry())
...     path.name
'p.svg'
"""

from __future__ import annotations

import os
from collections.abc import Mapping, Sequence
from pathlib import Path
from typing import Any

from pydantic import ValidationError

from regopack.base.errors import ConfigError, ExportError, PluginError
from regopack.base.messages import describe_validation_error
from regopack.packing.core import Packing
from regopack.registry.interfaces import Analyzer, Exporter
from regopack.registry.manager import Registry
from regopack.registry.plugin_types import misplaced_field, served_dimensions

__all__ = [
    "build_exporter",
    "check_exporter_dimension",
    "export_packing",
    "exporter_dimensions",
    "output_path",
    "run_exports",
]


def _takes_analyses(exporter: Exporter[Any]) -> bool:
    """Whether ``exporter.export`` takes the keyword ``analyses``."""
    import inspect

    params = inspect.signature(exporter.export).parameters.values()
    return any(p.name == "analyses" or p.kind is p.VAR_KEYWORD for p in params)


def exporter_dimensions(registry: Registry, kind: str) -> tuple[int, ...]:
    """Dimensions of the packings the exporter ``kind`` writes (2D unless its spec says).

    An old name writes the dimensions it wrote before (``vtk3d``: 3D), see
    :func:`~regopack.registry.plugin_types.served_dimensions`.
    """
    return served_dimensions(registry.get("export", kind), kind)


def check_exporter_dimension(
    registry: Registry, kind: str, dimension: int, source: str | None = None
) -> None:
    """Refuse, in one line, an exporter that does not write packings of ``dimension``.

    Parameters
    ----------
    registry
        Registry to look the exporter up in.
    kind
        Name of the exporter.
    dimension
        2 or 3, the packing's dimension.
    source
        What the message starts with (the packing file, or a scene field).

    Raises
    ------
    ConfigError
        Naming the source, the exporter, the dimensions it writes and the
        exporters of ``dimension``.

    Examples
    --------
    >>> from regopack.registry.manager import default_registry
    >>> try:
    ...     check_exporter_dimension(default_registry(), "svg", 3, "p.npz")
    ... except ConfigError as err:
    ...     print(err)
    p.npz: exporter 'svg' writes 2D packings, and this is a 3D packing; 3D exporters: ...
    """
    own = exporter_dimensions(registry, kind)
    if dimension in own:
        return
    fitting = [n for n in registry.names("export") if dimension in exporter_dimensions(registry, n)]
    listed = (
        f"{dimension}D exporters: {', '.join(fitting)}"
        if fitting
        else (f"no {dimension}D exporter is installed")
    )
    text = (
        f"exporter {kind!r} writes {'/'.join(f'{d}D' for d in own)} packings, and this is a "
        f"{dimension}D packing; {listed}"
    )
    raise ConfigError(f"{source}: {text}" if source else text)


def _without_prefix(
    params: dict[str, Any], kind: str, fields: Mapping[str, Any], source: str | None
) -> dict[str, Any]:
    """Accept the exporter's own name as a prefix: ``lammps.steps`` for ``steps``.

    As ``analyze --set psd.tolerance=...`` takes an analyzer's parameters;
    the prefixed key may also come nested (``{"lammps": {"steps": 5}}``).

    Raises
    ------
    ConfigError
        When a parameter is given both with the prefix and without it.
    """
    if kind in fields:
        return params
    prefix = f"{kind}."
    moved: list[tuple[str, Any]] = []
    out: dict[str, Any] = {}
    for key, value in params.items():
        if key == kind and isinstance(value, Mapping):
            moved.extend((str(k), v) for k, v in value.items())
        elif isinstance(key, str) and key.startswith(prefix):
            moved.append((key[len(prefix) :], value))
        else:
            out[key] = value
    for key, value in moved:
        if key in out:
            where = f"{source}: " if source else ""
            raise ConfigError(
                f"{where}exporter {kind!r}: {key} given twice, as {prefix}{key} and as {key}"
            )
        out[key] = value
    return out


def build_exporter(
    registry: Registry,
    kind: str,
    params: Mapping[str, Any] | None = None,
    *,
    source: str | None = None,
    dimension: int | None = None,
) -> Exporter[Any]:
    """Validate ``params`` with the exporter's config model and build the exporter.

    Parameters
    ----------
    registry, kind
        Registry to look the exporter up in, and the exporter's name.
    params
        Its parameters.
    source
        Where the parameters came from (e.g. ``"--set"``), named in messages.
    dimension
        The dimension of the packing to write, when known: a parameter that
        has no meaning in it (``lammps.thickness`` for a 3D packing) is refused.

    Raises
    ------
    PluginError
        If no exporter is registered as ``kind`` (the message lists the known ones),
        or the plugin does not build an :class:`~regopack.registry.interfaces.Exporter`.
    ConfigError
        One line naming the exporter, the parameter, its value and the allowed
        parameters, if a parameter is unknown or out of range (or, with
        ``dimension``, has no meaning in that dimension).

    Examples
    --------
    >>> from regopack.registry.manager import default_registry
    >>> try:
    ...     build_exporter(default_registry(), "svg", {"widht_px": 300})
    ... except ConfigError as err:
    ...     print(err)
    exporter 'svg': widht_px = 300: unknown field; did you mean 'width_px'? allowed: ...
    """
    spec = registry.get("export", kind)
    given = _without_prefix(dict(params or {}), kind, spec.config_model.model_fields, source)
    try:
        config = spec.config_model.model_validate(given)
    except ValidationError as err:
        text = describe_validation_error(err, source=None, model=spec.config_model)
        where = f"{source}: " if source else ""
        raise ConfigError(f"{where}exporter {kind!r}: {text}") from err
    misplaced = None if dimension is None else misplaced_field(config, dimension)
    if misplaced is not None:
        where = f"{source}: " if source else ""
        raise ConfigError(f"{where}exporter {kind!r}: {misplaced[1]}")
    exporter = spec.factory(config)
    if not isinstance(exporter, Exporter):
        raise PluginError(
            f"export plugin {kind!r} ({registry.origin('export', kind)}) built a "
            f"{type(exporter).__name__}, not an Exporter"
        )
    return exporter


def output_path(
    exporter: Exporter[Any], packing_path: Path, out: Path | None = None, *, dimension: int = 2
) -> Path:
    """Where to write: ``out``, or ``<out>/<stem><suffix>`` if ``out`` is a directory.

    Without ``out``, the packing file's name with the exporter's suffix for
    packings of ``dimension`` (:meth:`~regopack.registry.interfaces.Exporter.suffix_for`).

    Examples
    --------
    >>> from regopack.plugins.exporters import VtkExporter
    >>> output_path(VtkExporter(), Path("runs/a/packing.npz")).as_posix()
    'runs/a/packing.vtp'
    >>> output_path(VtkExporter(), Path("runs/a/packing.npz"), dimension=3).as_posix()
    'runs/a/packing.vtu'
    """
    name = Path(packing_path).with_suffix(exporter.suffix_for(dimension)).name
    if out is None:
        return Path(packing_path).with_name(name)
    if out.is_dir():
        return out / name
    return out


def export_packing(
    packing: Packing,
    kind: str,
    path: Path,
    *,
    registry: Registry,
    params: Mapping[str, Any] | None = None,
    analyses: Mapping[str, Analyzer] | None = None,
    source: str | None = None,
    force: bool = False,
) -> Path:
    """Write ``packing`` to ``path`` with the exporter ``kind``; return the main file.

    The main file is the one the caller names, and is overwritten. Its
    companions (:meth:`~regopack.registry.interfaces.Exporter.companions`) are
    overwritten too when the main file exists (an earlier export of the same
    files); a companion that exists beside a main file that does not is taken
    for a file of the user's, and refused unless ``force``.

    Parameters
    ----------
    packing
        The packing to write.
    kind
        Name of the exporter (``"csv"``, ``"json"``, ``"svg"``, ``"vtk"``, ...).
    path
        Main output file.
    registry
        Registry to look the exporter up in.
    params
        Parameters of the exporter.
    analyses
        Computed analyzers whose per-particle results the exporter may add.
    source
        Where the packing came from (e.g. its file), named when the exporter
        does not write packings of its dimension.
    force
        Overwrite companions whatever exists.

    Raises
    ------
    ConfigError
        One line, if the exporter does not write packings of this dimension,
        or a parameter has no meaning in it.
    ExportError
        One line, if the file cannot be written.
    """
    dimension = packing.dimension
    check_exporter_dimension(registry, kind, dimension, source)
    exporter = build_exporter(registry, kind, params, dimension=dimension)
    if not force:
        _refuse_users_files(exporter, Path(path))
    try:
        return exporter.export(packing, Path(path), analyses=analyses)
    except OSError as err:
        why = err.strerror or type(err).__name__
        raise ExportError(f"cannot write {path}: {why}") from err


def _refuse_users_files(exporter: Any, path: Path) -> None:
    """Refuse to write over a companion that exists beside a main file that does not."""
    if os.path.lexists(path):
        return
    companions = getattr(exporter, "companions", None)
    for other in companions(path) if callable(companions) else ():
        if os.path.lexists(other) and Path(other) != path:
            raise ExportError(
                f"{other}: exists, and {path} does not, so it is no earlier export's; "
                "give another path, move it, or pass --force (force=True) to overwrite it"
            )


def run_exports(
    packing: Packing,
    plugins: Sequence[Any],
    packing_path: Path,
    shown_path: Path,
    analyses: Mapping[str, Analyzer] | None = None,
) -> tuple[Path, ...]:
    """Write a run's ``outputs.exports`` beside its packing file; return the main files.

    Parameters
    ----------
    packing
        The packing of the run.
    plugins
        The resolved exporters of ``outputs.exports`` (already checked to
        write packings of its dimension when the scene was resolved).
    packing_path
        The packing file in the run's temporary folder; each file is
        ``<packing stem><suffix>`` beside it, the suffix of the packing's
        dimension.
    shown_path
        Where the packing file will be, for messages.
    analyses
        The run's computed analyzers, passed on to every exporter.
    """
    dimension = packing.dimension
    written = []
    for plugin in plugins:
        exporter = plugin.build()
        if not isinstance(exporter, Exporter):
            raise PluginError(
                f"export plugin {plugin.kind!r} ({plugin.origin}) built a "
                f"{type(exporter).__name__}, not an Exporter"
            )
        suffix = exporter.suffix_for(dimension)
        # an exporter written for 3D before the interfaces merged may take no analyses
        more = {"analyses": analyses} if analyses and _takes_analyses(exporter) else {}
        try:
            written.append(exporter.export(packing, packing_path.with_suffix(suffix), **more))
        except OSError as err:
            shown = shown_path.with_suffix(suffix)
            raise ExportError(f"cannot write {shown}: {err.strerror or err}") from err
    return tuple(written)
