"""The ``csv`` exporter: particle table, vertex table and metadata (exact round trip).

CSV keeps every array of the packing exactly (floats are written with
:func:`repr`, the shortest text that reads back to the same double) and is
read back by :func:`read_csv`:

>>> import tempfile
>>> from pathlib import Path
>>> from regopack.testing import packing_from_polygons
>>> p = packing_from_polygons([[(0, 0), (1, 0), (1, 1), (0, 1)]])
>>> with tempfile.TemporaryDirectory() as tmp:
...     path = CsvExporter().export(p, Path(tmp) / "packing.csv")
...     q = read_csv(path)
>>> bool((q.vertices == p.vertices).all()), q.mineral_names == p.mineral_names
(True, True)
"""

from __future__ import annotations

import csv
import io
import json
from collections.abc import Iterable, Mapping, Sequence
from pathlib import Path
from typing import Any

import numpy as np
from numpy.typing import NDArray
from pydantic import BaseModel, ConfigDict

from regopack.base.errors import ExportError
from regopack.packing.core import Packing
from regopack.plugins.exporters.export_common import (
    _dumps,
    _header,
    _mineral_name,
    _num,
    _packing_from,
    _read_header,
    _write_text,
)
from regopack.registry.interfaces import Analyzer, Exporter

__all__ = [
    "CSV_FORMAT",
    "PARTICLE_COLUMNS",
    "VERTEX_COLUMNS",
    "CsvConfig",
    "CsvExporter",
    "companion_paths",
    "read_csv",
]

CSV_FORMAT = "regopack-csv"
"""Value of ``format`` in the ``<stem>_meta.json`` file of a CSV export."""

PARTICLE_COLUMNS = (
    "index",
    "placed",
    "insertion_index",
    "mineral",
    "radius",
    "orientation",
    "cx",
    "cy",
    "n_vertices",
)
"""Columns of the particle table of a CSV export."""

VERTEX_COLUMNS = ("particle", "vertex", "x", "y")
"""Columns of the vertex table of a CSV export (``x``, ``y`` relative to the centre)."""


class CsvConfig(BaseModel):
    """Parameters of the CSV exporter (it has none)."""

    model_config = ConfigDict(extra="forbid", strict=True)


def companion_paths(path: Path) -> tuple[Path, Path]:
    """Vertex table and metadata file written beside the CSV particle table ``path``.

    Examples
    --------
    >>> [p.name for p in companion_paths(Path("out/packing.csv"))]
    ['packing_vertices.csv', 'packing_meta.json']
    """
    path = Path(path)
    return (
        path.with_name(f"{path.stem}_vertices.csv"),
        path.with_name(f"{path.stem}_meta.json"),
    )


def _csv_text(header: Sequence[str], rows: Iterable[Sequence[object]]) -> str:
    buf = io.StringIO()
    writer = csv.writer(buf, lineterminator="\n")
    writer.writerow(header)
    writer.writerows(rows)
    return buf.getvalue()


class CsvExporter(Exporter[Packing]):
    """Particle table, vertex table and a small metadata file (exact round trip).

    ``<stem>.csv`` has one row per drawn particle (columns
    :data:`PARTICLE_COLUMNS`), ``<stem>_vertices.csv`` one row per outline
    vertex relative to the particle's centre (:data:`VERTEX_COLUMNS`), and
    ``<stem>_meta.json`` the domain, scene, seed, version, mineral names and
    run statistics. :func:`read_csv` reads the three back.
    """

    suffix = ".csv"

    def __init__(self, config: CsvConfig | None = None) -> None:
        self.config = config or CsvConfig()

    def companions(self, path: Path) -> tuple[Path, ...]:
        """Return the vertex table and the metadata file (see :func:`companion_paths`)."""
        return companion_paths(path)

    def export(
        self, packing: Packing, path: Path, *, analyses: Mapping[str, Analyzer] | None = None
    ) -> Path:
        """Write the three files; return the path of the particle table."""
        path = Path(path)
        vertices_path, meta_path = companion_paths(path)
        counts = np.diff(packing.offsets)
        particles = (
            (
                j,
                int(packing.insertion_index[j] >= 0),
                int(packing.insertion_index[j]),
                _mineral_name(packing, int(packing.mineral[j])),
                _num(packing.radius[j]),
                _num(packing.orientation[j]),
                _num(packing.centre[j, 0]),
                _num(packing.centre[j, 1]),
                int(counts[j]),
            )
            for j in range(packing.n_particles)
        )
        owner = np.repeat(np.arange(packing.n_particles), counts)
        within = np.arange(packing.vertices.shape[0]) - np.repeat(packing.offsets[:-1], counts)
        vertex_rows = (
            (int(owner[i]), int(within[i]), _num(x), _num(y))
            for i, (x, y) in enumerate(packing.vertices.tolist())
        )
        _write_text(path, _csv_text(PARTICLE_COLUMNS, particles))
        _write_text(vertices_path, _csv_text(VERTEX_COLUMNS, vertex_rows))
        _write_text(meta_path, _dumps(_header(packing, CSV_FORMAT), indent=2))
        return path


def _read_table(path: Path, columns: Sequence[str]) -> list[list[str]]:
    try:
        with open(path, newline="", encoding="utf-8") as fh:
            rows = list(csv.reader(fh))
    except OSError as err:
        raise ExportError(f"{path}: {err.strerror or type(err).__name__}") from err
    if not rows or tuple(rows[0]) != tuple(columns):
        raise ExportError(f"{path}: expected the columns {', '.join(columns)}")
    return rows[1:]


def read_csv(path: str | Path) -> Packing:
    """Read a packing written by the ``csv`` exporter.

    Parameters
    ----------
    path
        The particle table ``<stem>.csv``; ``<stem>_vertices.csv`` and
        ``<stem>_meta.json`` are read from the same directory.

    Raises
    ------
    ExportError
        One line, if a file is missing or does not have the expected layout.
    """
    path = Path(path)
    vertices_path, meta_path = companion_paths(path)
    try:
        meta = json.loads(meta_path.read_text(encoding="utf-8"))
    except (OSError, json.JSONDecodeError) as err:
        raise ExportError(f"{meta_path}: cannot read the metadata ({err})") from err
    header = _read_header(meta_path, meta, CSV_FORMAT)
    names = [str(m) for m in header.get("mineral_names", [])]
    index_of = {name: k for k, name in reversed(list(enumerate(names)))}
    rows = _read_table(path, PARTICLE_COLUMNS)
    vrows = _read_table(vertices_path, VERTEX_COLUMNS)
    try:
        mineral = [index_of[r[3]] if r[3] in index_of else int(r[3]) for r in rows]
        counts = np.array([int(r[8]) for r in rows], dtype=np.int64)
        arrays: dict[str, NDArray[Any]] = {
            "radius": np.array([float(r[4]) for r in rows], dtype=np.float64),
            "mineral": np.array(mineral, dtype=np.int64),
            "orientation": np.array([float(r[5]) for r in rows], dtype=np.float64),
            "centre": np.array([(float(r[6]), float(r[7])) for r in rows], dtype=np.float64),
            "insertion_index": np.array([int(r[2]) for r in rows], dtype=np.int64),
            "offsets": np.concatenate([[0], np.cumsum(counts)]).astype(np.int64),
            "vertices": np.array([(float(r[2]), float(r[3])) for r in vrows], dtype=np.float64),
        }
        owners = np.array([int(r[0]) for r in vrows], dtype=np.int64)
    except (ValueError, IndexError) as err:
        raise ExportError(f"{path}: malformed row ({err})") from err
    if int(counts.sum()) != len(vrows) or not np.array_equal(
        owners, np.repeat(np.arange(len(rows)), counts)
    ):
        raise ExportError(f"{vertices_path}: the vertices do not match the n_vertices of {path}")
    return _packing_from(header, arrays, path)
