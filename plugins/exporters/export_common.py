"""What the built-in exporters share: writing text files, the export header, numbers.

The CSV and JSON exports carry the same header (:func:`_header`) and are read
back into a :class:`~regopack.packing.core.Packing` by the same code
(:func:`_packing_from`); every exporter writes its files atomically through
:func:`_write_text`.
"""

from __future__ import annotations

import json
import math
from collections.abc import Callable, Mapping
from pathlib import Path
from typing import Any

import numpy as np
from numpy.typing import NDArray
from pydantic import BaseModel

from regopack.base.errors import ExportError, GeometryError, PackingError
from regopack.geometry.domain import domain_from_dict
from regopack.packing.core import Packing, _atomic_file, _finite_or_none
from regopack.registry.interfaces import Analyzer
from regopack.registry.plugin_types import ExporterSpec

__all__ = ["EXPORT_FORMAT_VERSION"]

FloatArray = NDArray[np.float64]
IntArray = NDArray[np.int64]
AnyPacking = Packing
"""A packing of either dimension, as the exporters of both take it (``packing.dimension``)."""
Analyses = Mapping[str, Analyzer] | None
"""The ``analyses`` an exporter is given: computed analyzers by name, or none."""

EXPORT_FORMAT_VERSION = 1
"""Version of the CSV and JSON export layouts."""


def both_dimensions(
    name: str, config: type[BaseModel], factory: Callable[[Any], Any], description: str
) -> ExporterSpec:
    """Return the spec of an exporter of both dimensions, once registered for 3D as ``<name>3d``.

    The old name (``vtk3d``) selects it for one release, for 3D packings only.
    """
    aliases = (f"{name}3d",)
    return ExporterSpec(
        name,
        config,
        factory,
        description,
        dimensions=(2, 3),
        aliases=aliases,
        alias_dimensions=(3,),
    )


def scene_label(packing: Any) -> str:
    r"""Return the packing's scene name as one line of printable text, for file comments.

    A packing file from elsewhere may carry any name; a line break in it would
    end a comment of a script and start a command.

    Examples
    --------
    >>> scene_label(type("P", (), {"scene": {"name": "a\\nprint(1)"}})())
    'a?print(1)'
    """
    name = str(packing.scene.get("name", "?"))
    return "".join(c if c.isprintable() else "?" for c in name)


def _num(value: float) -> str:
    """Shortest text that reads back to the same double (``nan`` for NaN)."""
    return repr(float(value))


def _write_text(path: Path, text: str) -> None:
    try:
        with _atomic_file(path) as fh:
            fh.write(text.encode("utf-8"))
    except OSError as err:
        why = err.strerror or type(err).__name__
        raise ExportError(f"cannot write {path}: {why}") from err


def _header(packing: Packing, fmt: str) -> dict[str, Any]:
    """Return what a CSV or JSON export stores besides the particles.

    ``rounding`` (one radius per particle) is present only when some particle
    is rounded (a disk).
    """
    extra = {"rounding": packing.rounding_radius.tolist()} if packing.rounded else {}
    return {
        **extra,
        "format": fmt,
        "format_version": EXPORT_FORMAT_VERSION,
        "version": packing.version,
        "seed": packing.seed,
        "mineral_names": list(packing.mineral_names),
        "domain": packing.domain.to_dict(),
        "scene": packing.scene,
        "stats": packing.stats,
    }


def _dumps(obj: Any, indent: int | None = None) -> str:
    return json.dumps(_finite_or_none(obj), indent=indent, allow_nan=False) + "\n"


def _read_header(path: Path, data: object, fmt: str) -> dict[str, Any]:
    if not isinstance(data, dict) or data.get("format") != fmt:
        raise ExportError(f"{path}: not a regopack {fmt.removeprefix('regopack-')} export")
    version = data.get("format_version")
    if not isinstance(version, int) or version > EXPORT_FORMAT_VERSION:
        raise ExportError(f"{path}: unsupported export format version {version!r}")
    return data


def _packing_from(
    header: Mapping[str, Any], arrays: Mapping[str, NDArray[Any]], path: Path
) -> Packing:
    try:
        domain = domain_from_dict(header["domain"], 2)
        names = tuple(str(m) for m in header["mineral_names"])
        rounding = header.get("rounding")
        if rounding is not None:
            rounding = np.asarray([float(r) for r in rounding], dtype=np.float64)
            if rounding.shape != np.shape(arrays["radius"]):
                raise ValueError("one rounding radius per particle expected")
    except (KeyError, TypeError, ValueError, GeometryError) as err:
        raise ExportError(f"{path}: incomplete header ({err})") from err
    stats = {
        str(k): (math.nan if v is None else v) for k, v in dict(header.get("stats") or {}).items()
    }
    try:
        return Packing(
            radius=np.asarray(arrays["radius"], dtype=np.float64),
            mineral=np.asarray(arrays["mineral"], dtype=np.int64),
            mineral_names=names,
            vertices=np.asarray(arrays["vertices"], dtype=np.float64).reshape(-1, 2),
            offsets=np.asarray(arrays["offsets"], dtype=np.int64),
            orientation=np.asarray(arrays["orientation"], dtype=np.float64),
            centre=np.asarray(arrays["centre"], dtype=np.float64).reshape(-1, 2),
            insertion_index=np.asarray(arrays["insertion_index"], dtype=np.int64),
            domain=domain,
            scene=dict(header.get("scene") or {}),
            seed=int(header.get("seed", 0)),
            version=str(header.get("version", "unknown")),
            stats=stats,
            rounding=rounding,
        )
    except PackingError as err:  # the particles break the packing format
        raise ExportError(f"{path}: {err}") from err


def _mineral_name(packing: Packing, k: int) -> str:
    names = packing.mineral_names
    return names[k] if 0 <= k < len(names) else str(k)
