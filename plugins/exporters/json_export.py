"""The ``json`` exporter: one JSON document per packing (exact round trip).

Floats are written with :func:`repr` (``null`` for NaN), so :func:`read_json`
gives back the same arrays.
"""

from __future__ import annotations

import json
import math
from collections.abc import Mapping
from pathlib import Path
from typing import Any

import numpy as np
from numpy.typing import NDArray
from pydantic import BaseModel, ConfigDict, Field

from regopack.base.errors import ExportError
from regopack.packing.core import Packing
from regopack.plugins.exporters.export_common import (
    _dumps,
    _header,
    _mineral_name,
    _packing_from,
    _read_header,
    _write_text,
)
from regopack.registry.interfaces import Analyzer, Exporter

__all__ = ["JSON_FORMAT", "JsonConfig", "JsonExporter", "read_json"]

JSON_FORMAT = "regopack-json"
"""Value of ``format`` in a JSON export."""


class JsonConfig(BaseModel):
    """Parameters of the JSON exporter."""

    model_config = ConfigDict(extra="forbid", strict=True)

    indent: int = Field(
        0, ge=0, le=8, description="Spaces of indentation; 0 writes the document on one line."
    )


class JsonExporter(Exporter[Packing]):
    """One JSON document with the header and one object per particle (exact round trip).

    The document holds ``format``, ``format_version``, ``version``, ``seed``,
    ``mineral_names``, ``domain``, ``scene``, ``stats`` and ``particles``; each
    particle has ``index``, ``placed``, ``insertion_index``, ``mineral`` (index),
    ``mineral_name``, ``radius``, ``orientation``, ``centre`` (``[x, y]``, with
    ``null`` for NaN) and ``vertices`` (``[[x, y], ...]`` relative to the centre).
    """

    suffix = ".json"

    def __init__(self, config: JsonConfig | None = None) -> None:
        self.config = config or JsonConfig()

    def export(
        self, packing: Packing, path: Path, *, analyses: Mapping[str, Analyzer] | None = None
    ) -> Path:
        """Write the document; return ``path``."""
        path = Path(path)
        doc = _header(packing, JSON_FORMAT)
        radius = packing.radius.tolist()
        orientation = packing.orientation.tolist()
        centre = packing.centre.tolist()
        vertices = packing.vertices.tolist()
        offsets = packing.offsets.tolist()
        doc["particles"] = [
            {
                "index": j,
                "placed": bool(packing.insertion_index[j] >= 0),
                "insertion_index": int(packing.insertion_index[j]),
                "mineral": int(packing.mineral[j]),
                "mineral_name": _mineral_name(packing, int(packing.mineral[j])),
                "radius": radius[j],
                "orientation": orientation[j],
                "centre": centre[j],
                "vertices": vertices[offsets[j] : offsets[j + 1]],
            }
            for j in range(packing.n_particles)
        ]
        _write_text(path, _dumps(doc, indent=self.config.indent or None))
        return path


def _float(value: object) -> float:
    return math.nan if value is None else float(value)  # type: ignore[arg-type]


def read_json(path: str | Path) -> Packing:
    """Read a packing written by the ``json`` exporter.

    Raises
    ------
    ExportError
        One line, if the file is missing or is not a regopack JSON export.
    """
    path = Path(path)
    try:
        data = json.loads(path.read_text(encoding="utf-8"))
    except (OSError, json.JSONDecodeError) as err:
        raise ExportError(f"{path}: cannot read ({err})") from err
    header = _read_header(path, data, JSON_FORMAT)
    try:
        particles = list(header["particles"])
        counts = [len(p["vertices"]) for p in particles]
        arrays: dict[str, NDArray[Any]] = {
            "radius": np.array([_float(p["radius"]) for p in particles], dtype=np.float64),
            "mineral": np.array([int(p["mineral"]) for p in particles], dtype=np.int64),
            "orientation": np.array(
                [_float(p["orientation"]) for p in particles], dtype=np.float64
            ),
            "centre": np.array(
                [[_float(c) for c in p["centre"]] for p in particles], dtype=np.float64
            ),
            "insertion_index": np.array(
                [int(p["insertion_index"]) for p in particles], dtype=np.int64
            ),
            "offsets": np.concatenate([[0], np.cumsum(counts, dtype=np.int64)]).astype(np.int64),
            "vertices": np.array(
                [[_float(c) for c in v] for p in particles for v in p["vertices"]],
                dtype=np.float64,
            ),
        }
    except (KeyError, TypeError, ValueError) as err:
        raise ExportError(f"{path}: malformed particle ({err})") from err
    return _packing_from(header, arrays, path)
