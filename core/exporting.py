"""Write a packing in another program's file format through an exporter plugin.

The formats are the plugins of kind ``"export"`` (see
:func:`regopack.hookspecs.regopack_exporters`); the built-in ones are ``csv``,
``json``, ``svg``, ``vtk``, ``lammps``, ``gsd`` and ``image``.

Examples
--------
>>> import tempfile
>>> from regopack.manager import default_registry
>>> from regopack.testing import packing_from_polygons
>>> p = packing_from_polygons([[(0, 0), (1, 0), (1, 1), (0, 1)]])
>>> with tempfile.TemporaryDirectory() as tmp:
...     path = export_packing(p, "svg", Path(tmp) / "p.svg", registry=default_registry())
...     path.name
'p.svg'
"""

from __future__ import annotations

from collections.abc import Mapping
from pathlib import Path
from typing import Any

from pydantic import ValidationError

from regopack.errors import ConfigError, ExportError, PluginError
from regopack.interfaces import Analyzer, Exporter
from regopack.manager import Registry
from regopack.messages import describe_validation_error
from regopack.packing import Packing

__all__ = ["build_exporter", "export_packing", "output_path"]


def build_exporter(
    registry: Registry,
    kind: str,
    params: Mapping[str, Any] | None = None,
    *,
    source: str | None = None,
) -> Exporter:
    """Validate ``params`` with the exporter's config model and build the exporter.

    Parameters
    ----------
    registry
        Registry to look the exporter up in.
    kind
        Name of the exporter.
    params
        Its parameters.
    source
        Where the parameters came from (e.g. ``"--set"``), named in messages.

    Raises
    ------
    PluginError
        If no exporter is registered as ``kind`` (the message lists the known ones),
        or the plugin does not build an :class:`~regopack.interfaces.Exporter`.
    ConfigError
        One line naming the exporter, the parameter, its value and the allowed
        parameters, if a parameter is unknown or out of range.

    Examples
    --------
    >>> from regopack.manager import default_registry
    >>> try:
    ...     build_exporter(default_registry(), "svg", {"widht_px": 300})
    ... except ConfigError as err:
    ...     print(err)
    exporter 'svg': widht_px = 300: unknown field; did you mean 'width_px'? allowed: ...
    """
    spec = registry.get("export", kind)
    try:
        config = spec.config_model.model_validate(dict(params or {}))
    except ValidationError as err:
        text = describe_validation_error(err, source=None, model=spec.config_model)
        where = f"{source}: " if source else ""
        raise ConfigError(f"{where}exporter {kind!r}: {text}") from err
    exporter = spec.factory(config)
    if not isinstance(exporter, Exporter):
        raise PluginError(
            f"export plugin {kind!r} ({registry.origin('export', kind)}) built a "
            f"{type(exporter).__name__}, not an Exporter"
        )
    return exporter


def output_path(exporter: Exporter, packing_path: Path, out: Path | None = None) -> Path:
    """Where to write: ``out``, or ``<out>/<stem><suffix>`` if ``out`` is a directory.

    Without ``out``, the packing file's name with the exporter's suffix.

    Examples
    --------
    >>> from regopack.plugins.exporters import VtkExporter
    >>> output_path(VtkExporter(), Path("runs/a/packing.npz")).as_posix()
    'runs/a/packing.vtp'
    """
    name = Path(packing_path).with_suffix(exporter.suffix).name
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
) -> Path:
    """Write ``packing`` to ``path`` with the exporter ``kind``; return the main file.

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

    Raises
    ------
    ExportError
        One line, if the file cannot be written.
    """
    exporter = build_exporter(registry, kind, params)
    try:
        return exporter.export(packing, Path(path), analyses=analyses)
    except OSError as err:
        why = err.strerror or type(err).__name__
        raise ExportError(f"cannot write {path}: {why}") from err
