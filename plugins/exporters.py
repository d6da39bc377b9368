"""Built-in exporters: CSV, JSON, SVG, VTK and LAMMPS (in :mod:`.lammps_export`).

Every exporter writes one main file (and, for CSV, two companion files named
after its stem). CSV and JSON keep every array of the packing exactly (floats
are written with :func:`repr`, the shortest text that reads back to the same
double) and are read back by :func:`read_csv` and :func:`read_json`:

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
import math
from collections.abc import Iterable, Mapping, Sequence
from pathlib import Path
from typing import Any
from xml.sax.saxutils import escape, quoteattr

import numpy as np
from numpy.typing import NDArray
from pydantic import BaseModel, ConfigDict, Field

from regopack.domain import Circle, Rectangle, domain_from_dict
from regopack.errors import ExportError, GeometryError, PackingError
from regopack.hookspecs import hookimpl
from regopack.interfaces import Analyzer, Exporter
from regopack.packing import Packing, _atomic_file, _finite_or_none
from regopack.plugin_types import ExporterSpec
from regopack.plugins.lammps_export import LammpsConfig, LammpsExporter

__all__ = [
    "CSV_FORMAT",
    "JSON_FORMAT",
    "CsvConfig",
    "CsvExporter",
    "JsonConfig",
    "JsonExporter",
    "LammpsConfig",
    "LammpsExporter",
    "SvgConfig",
    "SvgExporter",
    "VtkConfig",
    "VtkExporter",
    "companion_paths",
    "read_csv",
    "read_json",
]

FloatArray = NDArray[np.float64]
IntArray = NDArray[np.int64]

CSV_FORMAT = "regopack-csv"
"""Value of ``format`` in the ``<stem>_meta.json`` file of a CSV export."""

JSON_FORMAT = "regopack-json"
"""Value of ``format`` in a JSON export."""

EXPORT_FORMAT_VERSION = 1
"""Version of the CSV and JSON export layouts."""

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
        domain = domain_from_dict(header["domain"])
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


# ---------------------------------------------------------------------------
# CSV


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


class CsvExporter(Exporter):
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


# ---------------------------------------------------------------------------
# JSON


class JsonConfig(BaseModel):
    """Parameters of the JSON exporter."""

    model_config = ConfigDict(extra="forbid", strict=True)

    indent: int = Field(
        0, ge=0, le=8, description="Spaces of indentation; 0 writes the document on one line."
    )


class JsonExporter(Exporter):
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


# ---------------------------------------------------------------------------
# SVG


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


class SvgExporter(Exporter):
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
        from regopack.plugins.analysis.figures import mineral_colours

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


# ---------------------------------------------------------------------------
# VTK


class VtkConfig(BaseModel):
    """Parameters of the VTK exporter (it has none)."""

    model_config = ConfigDict(extra="forbid", strict=True)


def _coordination(packing: Packing, analyses: Mapping[str, Analyzer] | None) -> IntArray | None:
    """Per-particle coordination number from a computed ``coordination`` analyzer."""
    if not analyses or "coordination" not in analyses:
        return None
    z = getattr(analyses["coordination"], "per_particle", None)
    if z is None:
        return None
    z = np.asarray(z)
    if z.shape != (packing.n_particles,):
        raise ExportError(
            f"coordination results have {z.shape[0] if z.ndim else 0} values for "
            f"{packing.n_particles} particles"
        )
    return z.astype(np.int64)


def _data_array(name: str, vtk_type: str, values: Iterable[str], components: int = 1) -> str:
    comps = f' NumberOfComponents="{components}"' if components != 1 else ""
    body = " ".join(values)
    return (
        f'<DataArray type="{vtk_type}" Name="{name}"{comps} format="ascii">\n{body}\n</DataArray>'
    )


class VtkExporter(Exporter):
    """VTK XML PolyData (``.vtp``, ASCII) with one polygon per placed particle.

    Points are the absolute outline vertices (z = 0). Cell data: ``index``
    (the particle's draw index), ``mineral`` (index into the mineral names,
    listed in a comment), ``radius``, ``orientation``, ``insertion_index`` and,
    when a computed ``coordination`` analyzer is passed in ``analyses``, ``Z``.
    """

    suffix = ".vtp"

    def __init__(self, config: VtkConfig | None = None) -> None:
        self.config = config or VtkConfig()

    def export(
        self, packing: Packing, path: Path, *, analyses: Mapping[str, Analyzer] | None = None
    ) -> Path:
        """Write the PolyData file; return ``path``."""
        path = Path(path)
        z = _coordination(packing, analyses)
        idx = np.flatnonzero(packing.placed).astype(np.int64)
        polygons = packing.polygons(idx)
        points = np.concatenate(polygons) if polygons else np.empty((0, 2))
        counts = np.array([len(p) for p in polygons], dtype=np.int64)
        offsets = np.cumsum(counts)
        names = ", ".join(f"{k} = {name}" for k, name in enumerate(packing.mineral_names))
        cell = [
            _data_array("index", "Int64", (str(j) for j in idx.tolist())),
            _data_array("mineral", "Int32", (str(m) for m in packing.mineral[idx].tolist())),
            _data_array("radius", "Float64", (_num(r) for r in packing.radius[idx].tolist())),
            _data_array(
                "orientation", "Float64", (_num(r) for r in packing.orientation[idx].tolist())
            ),
            _data_array(
                "insertion_index", "Int64", (str(i) for i in packing.insertion_index[idx].tolist())
            ),
        ]
        if z is not None:
            cell.append(_data_array("Z", "Int32", (str(v) for v in z[idx].tolist())))
        xyz = (f"{_num(x)} {_num(y)} 0.0" for x, y in points.tolist())
        lines = [
            '<?xml version="1.0"?>',
            f"<!-- regopack {packing.version} packing: scene "
            f"{escape(str(packing.scene.get('name', '?')))}, seed {packing.seed}; "
            f"minerals: {escape(names)} -->",
            '<VTKFile type="PolyData" version="1.0" byte_order="LittleEndian" '
            'header_type="UInt64">',
            "<PolyData>",
            f'<Piece NumberOfPoints="{points.shape[0]}" NumberOfVerts="0" NumberOfLines="0" '
            f'NumberOfStrips="0" NumberOfPolys="{len(idx)}">',
            "<Points>",
            _data_array("Points", "Float64", xyz, components=3),
            "</Points>",
            "<Polys>",
            _data_array("connectivity", "Int64", (str(i) for i in range(points.shape[0]))),
            _data_array("offsets", "Int64", (str(o) for o in offsets.tolist())),
            "</Polys>",
            '<CellData Scalars="mineral">',
            *cell,
            "</CellData>",
            "</Piece>",
            "</PolyData>",
            "</VTKFile>",
        ]
        _write_text(path, "\n".join(lines) + "\n")
        return path


# ---------------------------------------------------------------------------
# LAMMPS


def polygon_moments(v: FloatArray) -> tuple[float, FloatArray, float, float, float]:
    """Area, centroid and second moments of a counter-clockwise polygon.

    Returns
    -------
    tuple
        ``(area, centroid, ixx, iyy, ixy)`` with ``ixx = ∫ y² dA``,
        ``iyy = ∫ x² dA`` and ``ixy = ∫ x y dA``, about the centroid.

    Examples
    --------
    >>> sq = np.array([[-1.0, -1.0], [1.0, -1.0], [1.0, 1.0], [-1.0, 1.0]])
    >>> a, c, ixx, iyy, ixy = polygon_moments(sq + 3.0)
    >>> float(a), c.tolist(), round(ixx, 12), round(iyy, 12), round(ixy, 12)
    (4.0, [3.0, 3.0], 1.333333333333, 1.333333333333, 0.0)
    """
    x0, y0 = v[:, 0], v[:, 1]
    x1, y1 = np.roll(x0, -1), np.roll(y0, -1)
    cross = x0 * y1 - x1 * y0
    area = float(cross.sum()) / 2.0
    cx = float(((x0 + x1) * cross).sum()) / (6.0 * area)
    cy = float(((y0 + y1) * cross).sum()) / (6.0 * area)
    x0, x1, y0, y1 = x0 - cx, x1 - cx, y0 - cy, y1 - cy
    cross = x0 * y1 - x1 * y0
    ixx = float(((y0 * y0 + y0 * y1 + y1 * y1) * cross).sum()) / 12.0
    iyy = float(((x0 * x0 + x0 * x1 + x1 * x1) * cross).sum()) / 12.0
    ixy = float(((x0 * y1 + 2 * x0 * y0 + 2 * x1 * y1 + x1 * y0) * cross).sum()) / 24.0
    return area, np.array([cx, cy]), ixx, iyy, ixy


# ---------------------------------------------------------------------------
# registration


@hookimpl
def regopack_exporters() -> Iterable[ExporterSpec]:
    """Register the built-in exporters."""
    return [
        ExporterSpec(
            "csv", CsvConfig, CsvExporter, "Particle and vertex tables (exact round trip)."
        ),
        ExporterSpec("json", JsonConfig, JsonExporter, "One JSON document (exact round trip)."),
        ExporterSpec("svg", SvgConfig, SvgExporter, "Picture of the particles, by mineral."),
        ExporterSpec("vtk", VtkConfig, VtkExporter, "VTK XML PolyData (.vtp) for ParaView."),
        ExporterSpec(
            "lammps",
            LammpsConfig,
            LammpsExporter,
            "LAMMPS data file (body rounded/polygon) and an input script that runs it.",
        ),
    ]
