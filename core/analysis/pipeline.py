"""Structure analysis of a packing: run the analyzers, write their results.

:func:`run_analyses` computes the requested analyzers and, first, the ones they
require (an analyzer names them in its ``requires``); nothing else is computed,
so asking for ``rdf`` alone never finds the contacts. :func:`write_analysis`
writes what the analyzers found into one directory:

``analysis.json``
    Every analyzer's :meth:`~regopack.registry.interfaces.Analyzer.results` under its
    name, plus the contact tolerance, η and exclusion margin used, the regopack
    version and the packing file.
``<table>.csv`` (or ``<table>.npz``)
    One file per table of :meth:`~regopack.registry.interfaces.Analyzer.tables`: a
    header row, then numeric columns (booleans as 0/1).
``figures/*.png``, ``figures/*.svg``
    The figures that plugins draw for the computed analyzers (see
    :func:`regopack.registry.hookspecs.regopack_analysis_figures`; the built-in
    analysis plugin draws them with matplotlib).
``report.md``
    The main numbers as Markdown tables, with the figures embedded.

The folder is written as a whole (see :func:`write_analysis`): it holds
either the complete earlier analysis or the complete new one.
"""

from __future__ import annotations

import io
import json
import math
import os
import warnings
from collections.abc import Iterable, Mapping, Sequence
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any, Literal

import numpy as np

from regopack.analysis import __all__ as __all__  # public names, listed in the package
from regopack.base.errors import ConfigError, PluginError
from regopack.base.outdir import mark_folder, rebase, replace_folder
from regopack.base.units import DEFAULT_LENGTH_UNIT, length_unit
from regopack.packing.core import Packing, _atomic_file, write_json_atomic
from regopack.registry.interfaces import Analyzer
from regopack.registry.manager import Registry
from regopack.registry.plugin_types import FigureSpec
from regopack.scenes.analysis_plan import DEFAULT_ANALYSES as DEFAULT_ANALYSES
from regopack.scenes.analysis_plan import DEFAULT_ANALYSES_3D as DEFAULT_ANALYSES_3D
from regopack.scenes.analysis_plan import run_analyses as run_analyses

ANALYSIS_KIND = "analysis"
"""Kind of the folder :func:`write_analysis` writes (in its marker file)."""

TableFormat = Literal["csv", "npz"]

_RESERVED = frozenset(
    {
        "regopack_version",
        "packing",
        "packing_version",
        "scene",
        "seed",
        "n_particles",
        "n_placed",
        "mineral_names",
        "length_unit",
        "tol",
        "eta",
        "interior_margin",
        "analyses",
        "dimension",
    }
)
"""Top-level keys of ``analysis.json`` that are not analyzer names."""


# ---------------------------------------------------------------------------
# writing


@dataclass(frozen=True)
class AnalysisFiles:
    """Files written by :func:`write_analysis`.

    Attributes
    ----------
    out_dir
        The directory.
    results
        ``analysis.json``.
    tables
        Table name to its file.
    figures
        Figure files (PNG and SVG).
    report
        ``report.md``.
    summary
        What ``analysis.json`` holds.
    """

    out_dir: Path
    results: Path
    tables: dict[str, Path] = field(default_factory=dict)
    figures: tuple[Path, ...] = ()
    report: Path | None = None
    summary: dict[str, Any] = field(default_factory=dict)

    def moved(self, old: Path, new: Path) -> AnalysisFiles:
        """Return the same files after the folder ``old`` they lie in became ``new``."""
        return AnalysisFiles(
            out_dir=rebase(self.out_dir, old, new),
            results=rebase(self.results, old, new),
            tables={k: rebase(v, old, new) for k, v in self.tables.items()},
            figures=tuple(rebase(p, old, new) for p in self.figures),
            report=rebase(self.report, old, new),
            summary=self.summary,
        )


def _first(results: Mapping[str, Mapping[str, Any]], key: str) -> Any:
    for res in results.values():
        value = res.get(key)
        if value is not None:
            return value
    return None


def analysis_summary(
    packing: Packing,
    analyzers: Mapping[str, Analyzer],
    packing_path: str | Path | None = None,
) -> dict[str, Any]:
    """Return the content of ``analysis.json``: the run's context, then each analyzer's results.

    ``tol``, ``eta`` and ``interior_margin`` are the first values that an
    analyzer reports under these keys (η falls back to the scene's density
    section); they are ``None`` when no analyzer used them.
    """
    from regopack._version import __version__

    results = {name: analyzer.results() for name, analyzer in analyzers.items()}
    clash = sorted(_RESERVED & set(results))
    if clash:
        raise PluginError(f"analyzer name {clash[0]!r} is a reserved key of analysis.json")
    eta = _first(results, "eta")
    if eta is None:
        density = packing.scene.get("density")
        eta = density.get("eta") if isinstance(density, dict) else None
    if eta is None:
        eta = packing.stats.get("eta")  # the eta a density target chose
    summary: dict[str, Any] = {
        "regopack_version": __version__,
        "packing": None if packing_path is None else str(packing_path),
        "packing_version": packing.version,
        "scene": packing.scene.get("name"),
        "seed": packing.seed,
        "n_particles": packing.n_particles,
        "n_placed": packing.n_placed,
        "mineral_names": list(packing.mineral_names),
        "length_unit": length_unit(packing),
        "tol": _first(results, "tol"),
        "eta": eta,
        "interior_margin": _first(results, "interior_margin"),
        "analyses": list(results),
    }
    if packing.dimension == 3:
        summary["dimension"] = 3
    summary.update(results)
    return summary


def _columns(table: str, columns: Mapping[str, Any]) -> dict[str, np.ndarray]:
    out: dict[str, np.ndarray] = {}
    length = None
    for name, values in columns.items():
        arr = np.asarray(values)
        if arr.ndim != 1:
            raise PluginError(f"table {table!r}: column {name!r} is not one-dimensional")
        if arr.dtype == np.bool_:
            arr = arr.astype(np.int64)
        if not (np.issubdtype(arr.dtype, np.integer) or np.issubdtype(arr.dtype, np.floating)):
            raise PluginError(f"table {table!r}: column {name!r} is not numeric ({arr.dtype})")
        if length is not None and arr.shape[0] != length:
            raise PluginError(f"table {table!r}: columns have different lengths")
        length = arr.shape[0]
        out[str(name)] = arr
    return out


def _csv_bytes(columns: Mapping[str, np.ndarray]) -> bytes:
    names = list(columns)
    if not names:
        return b"\n"
    fmt = ["%d" if np.issubdtype(a.dtype, np.integer) else "%.15g" for a in columns.values()]
    data = np.column_stack([a.astype(np.float64, copy=False) for a in columns.values()])
    buf = io.StringIO()
    buf.write(",".join(names) + "\n")
    if data.shape[0]:
        np.savetxt(buf, data, fmt=fmt, delimiter=",")
    return buf.getvalue().encode("utf-8")


def _write_bytes(path: Path, data: bytes) -> None:
    with _atomic_file(path) as fh:
        fh.write(data)


def _write_tables(
    out_dir: Path, analyzers: Mapping[str, Analyzer], table_format: TableFormat
) -> tuple[dict[str, Path], dict[str, list[str]]]:
    written: dict[str, Path] = {}
    names: dict[str, list[str]] = {}
    for analyzer_name, analyzer in analyzers.items():
        for table, cols in analyzer.tables().items():
            name = table if table not in written else f"{analyzer_name}_{table}"
            columns = _columns(name, cols)
            path = out_dir / f"{name}.{table_format}"
            if table_format == "csv":
                _write_bytes(path, _csv_bytes(columns))
            else:
                buf = io.BytesIO()
                np.savez(buf, **columns)  # type: ignore[arg-type]
                _write_bytes(path, buf.getvalue())
            written[name] = path
            names[name] = list(columns)
    return written, names


def _draw_figures(
    packing: Packing,
    analyzers: Mapping[str, Analyzer],
    out_dir: Path,
    registry: Registry | None,
) -> tuple[list[Path], dict[str, str]]:
    """Call the figure specs of the computed analyzers; return the files and their captions."""
    if registry is None:
        from regopack.registry.manager import default_registry

        registry = default_registry()
    paths: list[Path] = []
    captions: dict[str, str] = {}
    for spec in registry.figures():
        if spec.analyzer not in analyzers:
            continue
        drawn = _drawn_files(spec, packing, analyzers, out_dir)
        paths += [p for p in drawn if p not in paths]
        for stem, text in spec.captions.items():
            captions.setdefault(stem, text)  # an earlier (built-in) caption stays
    return paths, captions


class FigureWarning(UserWarning):
    """A figure of a plugin could not be drawn; the rest of the analysis is written."""


def _drawn_files(
    spec: FigureSpec, packing: Packing, analyzers: Mapping[str, Analyzer], out_dir: Path
) -> list[Path]:
    """Call ``spec.draw`` and return the files it wrote inside ``out_dir``.

    A figure is an addition to the results: when a plugin's ``draw`` raises,
    or returns something other than files inside ``out_dir``, a
    :class:`FigureWarning` says so and the figure is left out, so that the
    tables, the results and the packing of a run are still written.
    """
    what = f"the figures of {spec.analyzer!r} ({getattr(spec.draw, '__module__', '?')})"
    try:
        returned = spec.draw(packing, analyzers, out_dir)
    except Exception as exc:  # a plugin's own failure must not lose the analysis
        warnings.warn(f"{what} were not drawn: {exc}", FigureWarning, stacklevel=2)
        return []
    if isinstance(returned, str | bytes | os.PathLike) or not isinstance(returned, Iterable):
        warnings.warn(
            f"{what} were left out: draw returned {type(returned).__name__}, not a list of files",
            FigureWarning,
            stacklevel=2,
        )
        return []
    files: list[Path] = []
    root = Path(out_dir).resolve()
    for item in returned:
        if not isinstance(item, str | os.PathLike):
            warnings.warn(f"{what}: {item!r} is not a file name", FigureWarning, stacklevel=2)
            continue
        path = Path(item)
        full = (path if path.is_absolute() else Path(out_dir) / path).resolve()
        if not full.is_relative_to(root) or not full.is_file():
            warnings.warn(
                f"{what}: {item} is not a file in the figures folder", FigureWarning, stacklevel=2
            )
            continue
        files.append(Path(out_dir) / full.relative_to(root))
    return files


def write_analysis(
    out_dir: str | Path,
    packing: Packing,
    analyzers: Mapping[str, Analyzer],
    *,
    figures: bool = True,
    packing_path: str | Path | None = None,
    table_format: TableFormat = "csv",
    registry: Registry | None = None,
) -> AnalysisFiles:
    """Write the results, tables, figures and report of computed analyzers.

    The folder is written as a whole: the files go into a fresh temporary
    folder beside ``out_dir``, which then replaces ``out_dir`` (see
    :func:`regopack.base.outdir.replace_folder`), so ``out_dir`` holds this
    analysis and nothing of an earlier one, and an interrupted call leaves the
    earlier one untouched.

    Parameters
    ----------
    out_dir
        The analysis folder: one that does not exist, an empty one, or one
        that an earlier analysis wrote.
    packing
        The analysed packing.
    analyzers
        Computed analyzers by name, as :func:`run_analyses` returns them.
    figures
        Draw the figures (PNG and SVG, under ``figures/``) of the figure specs
        in ``registry`` whose analyzers were computed.
    packing_path
        The packing file, recorded in ``analysis.json`` and the report.
    table_format
        ``"csv"`` (default) or ``"npz"`` (one archive per table, one array per column).
    registry
        Registry whose figure specs (:meth:`~regopack.registry.manager.Registry.figures`)
        draw the figures; by default :func:`~regopack.registry.manager.default_registry`,
        built only when figures are drawn.

    Returns
    -------
    AnalysisFiles
        The paths written and the content of ``analysis.json``.

    Raises
    ------
    ConfigError
        When the folder may not be replaced, or cannot be created or written.
    """
    if table_format not in ("csv", "npz"):
        raise ConfigError(f"table format {table_format!r}: expected 'csv' or 'npz'")
    out = Path(out_dir)
    with replace_folder(out, ANALYSIS_KIND) as tmp:
        files = write_analysis_files(
            tmp,
            packing,
            analyzers,
            figures=figures,
            packing_path=packing_path,
            table_format=table_format,
            registry=registry,
        )
    return files.moved(tmp, out)


def write_analysis_files(
    out_dir: str | Path,
    packing: Packing,
    analyzers: Mapping[str, Analyzer],
    *,
    figures: bool = True,
    packing_path: str | Path | None = None,
    table_format: TableFormat = "csv",
    registry: Registry | None = None,
) -> AnalysisFiles:
    """Write what :func:`write_analysis` writes, into ``out_dir`` as it is.

    ``out_dir`` is created if needed and marked as an analysis folder; files
    already in it stay. A run uses this inside its own temporary folder.
    """
    if table_format not in ("csv", "npz"):
        raise ConfigError(f"table format {table_format!r}: expected 'csv' or 'npz'")
    out = Path(out_dir)
    try:
        out.mkdir(parents=True, exist_ok=True)
    except OSError as err:
        raise ConfigError(f"cannot create the output directory {out}: {err}") from err
    summary = analysis_summary(packing, analyzers, packing_path)
    try:
        mark_folder(out, ANALYSIS_KIND)
        results_path = out / "analysis.json"
        write_json_atomic(results_path, summary)
        tables, columns = _write_tables(out, analyzers, table_format)
        figure_paths: list[Path] = []
        captions: Mapping[str, str] = {}
        if figures and analyzers:
            figure_paths, captions = _draw_figures(packing, analyzers, out / "figures", registry)
        report_path = out / "report.md"
        text = _report(summary, tables, columns, figure_paths, captions, out)
        _write_bytes(report_path, text.encode("utf-8"))
    except (PermissionError, IsADirectoryError, NotADirectoryError) as err:
        raise ConfigError(f"cannot write the analysis output: {err}") from err
    return AnalysisFiles(
        out_dir=out,
        results=results_path,
        tables=tables,
        figures=tuple(figure_paths),
        report=report_path,
        summary=summary,
    )


# ---------------------------------------------------------------------------
# presenting


def _fmt(value: Any, spec: str = ".4g") -> str:
    if value is None:
        return "n/a"
    if isinstance(value, bool):
        return str(value).lower()
    if isinstance(value, int):
        return f"{value:,}"
    if isinstance(value, float):
        return "n/a" if math.isnan(value) else format(value, spec)
    return str(value)


def _either(summary: Mapping[str, Any], name: str) -> Any:
    """Results of the analyzer ``name``, or of it filed under its old 3D name ``name + "3d"``."""
    value = summary.get(name)
    return value if value is not None else summary.get(f"{name}3d")


def _first_peak(rdf: Mapping[str, Any], unit: str) -> str:
    """Format the first peak of g(r) with two significant digits of its error, or its plateau.

    Examples
    --------
    >>> _first_peak({"first_peak_r": 4.434, "first_peak_r_err": 0.2287}, "µm")
    '4.43 ± 0.23 µm'
    >>> _first_peak({"first_peak_r": None, "first_plateau": [3.85, 5.35]}, "µm")
    'no distinct peak (plateau 3.85–5.35 µm)'
    """
    peak, err = rdf.get("first_peak_r"), rdf.get("first_peak_r_err")
    plateau = rdf.get("first_plateau")
    if peak is None and isinstance(plateau, list) and len(plateau) == 2:
        return f"no distinct peak (plateau {_fmt(plateau[0])}–{_fmt(plateau[1])} {unit})"
    if isinstance(peak, float) and isinstance(err, float) and math.isfinite(err) and err > 0:
        digits = max(0, 1 - math.floor(math.log10(err)))  # two significant digits of err
        return f"{peak:.{digits}f} ± {err:.{digits}f} {unit}"
    return f"{_fmt(peak)} {unit}"


def main_numbers(summary: Mapping[str, Any]) -> list[tuple[str, str]]:
    """``(label, value)`` rows of the headline numbers of ``analysis.json``.

    Rows appear for the built-in analyzers that were run: packing density,
    contacts, coordination numbers (overall, interior, per mineral), the first
    peak of g(r) (or its plateau, when the top is no distinct peak) and the
    fabric anisotropy with its sampling error, of either dimension, under the analyzers' names or
    their old 3D names (``contacts3d``, ...).
    """
    rows: list[tuple[str, str]] = []
    u = str(summary.get("length_unit") or DEFAULT_LENGTH_UNIT)
    margin = summary.get("interior_margin")
    interior = f"interior (margin {_fmt(margin, 'g')} {u})" if margin is not None else "interior"
    tol = summary.get("tol")
    if tol is not None:
        rows.append(("contact tolerance tol", f"{_fmt(tol, 'g')} {u}"))
    if summary.get("eta") is not None:
        rows.append(("η", _fmt(summary["eta"], "g")))
    density = _either(summary, "density")
    if isinstance(density, dict):
        rows.append(("φ domain", _fmt(density.get("phi_domain"))))
        rows.append((f"φ {interior}", _fmt(density.get("phi_interior"))))
    contacts = _either(summary, "contacts")
    if isinstance(contacts, dict):
        rows.append(("contacts", _fmt(contacts.get("n_contacts"))))
        rows.append(("median contact area A_c", f"{_fmt(contacts.get('median_area'))} {u}²"))
        if contacts.get("median_volume") is not None:
            rows.append(("median contact volume V_c", f"{_fmt(contacts['median_volume'])} {u}³"))
        rows.append(("median contact width b_c", f"{_fmt(contacts.get('median_width'))} {u}"))
    coordination = _either(summary, "coordination")
    if isinstance(coordination, dict):
        rows.append(("Z domain", _fmt(coordination.get("z_domain"))))
        rows.append((f"Z {interior}", _fmt(coordination.get("z_interior"))))
        per = coordination.get("z_per_mineral") or {}
        for mineral, z in per.items():
            rows.append((f"Z {mineral} (interior)", _fmt(z)))
    rdf = _either(summary, "rdf")
    if isinstance(rdf, dict):
        rows.append(("first g(r) peak", _first_peak(rdf, u)))
        rows.append(("far-field mean g(r)", _fmt(rdf.get("far_mean"))))
    network = _either(summary, "network")
    if isinstance(network, dict):
        a, err = network.get("anisotropy"), network.get("anisotropy_error")
        value = _fmt(a)
        if isinstance(a, float) and isinstance(err, float) and math.isfinite(err) and err > 0:
            digits = max(0, 1 - math.floor(math.log10(err)))  # two significant digits of err
            value = f"{a:.{digits}f} ± {err:.{digits}f}"
        rows.append(("fabric anisotropy", value))
    return rows


def _flatten(prefix: str, value: Any, out: list[tuple[str, str]]) -> None:
    if isinstance(value, dict):
        for key, item in value.items():
            _flatten(f"{prefix}.{key}" if prefix else str(key), item, out)
    elif isinstance(value, list | tuple):
        if len(value) <= 4 and all(not isinstance(v, dict) for v in value):
            out.append((prefix, json.dumps(_rounded(value), ensure_ascii=False)))
        else:
            out.append((prefix, f"{len(value)} values (see analysis.json)"))
    else:
        out.append((prefix, _fmt(value)))


def _rounded(value: Any) -> Any:
    if isinstance(value, float):
        return float(f"{value:.4g}")
    if isinstance(value, list | tuple):
        return [_rounded(v) for v in value]
    return value


def _md_table(header: tuple[str, str], rows: Sequence[tuple[str, str]]) -> list[str]:
    def cell(text: str) -> str:
        return text.replace("|", "\\|")

    lines = [f"| {header[0]} | {header[1]} |", "|---|---:|"]
    lines += [f"| {cell(a)} | {cell(b)} |" for a, b in rows]
    return lines


def _report(
    summary: Mapping[str, Any],
    tables: Mapping[str, Path],
    columns: Mapping[str, Sequence[str]],
    figure_paths: Sequence[Path],
    captions: Mapping[str, str],
    out: Path,
) -> str:
    scene = summary.get("scene") or "packing"
    u = str(summary.get("length_unit") or DEFAULT_LENGTH_UNIT)
    lines = [f"# Structure analysis: {scene}, seed {summary.get('seed')}", ""]
    source = summary.get("packing")
    lines.append(
        f"Packing {'`' + str(source) + '`' if source else '(in memory)'}: "
        f"{summary['n_placed']:,} of {summary['n_particles']:,} particles placed. "
        f"Analysed with regopack {summary['regopack_version']}; lengths in {u}. "
        f"Statistics marked *interior* exclude particles whose centre lies within "
        f"{_fmt(summary.get('interior_margin'), 'g')} {u} of a wall."
    )
    lines += ["", "## Main numbers", ""]
    lines += _md_table(("quantity", "value"), main_numbers(summary))

    pngs = [p for p in figure_paths if p.suffix == ".png"]
    if pngs:
        lines += ["", "## Figures"]
        for png in pngs:
            rel = png.relative_to(out).as_posix()
            caption = captions.get(png.stem, png.stem.replace("-", " "))
            svg = png.with_suffix(".svg")
            lines += ["", f"### {caption}", "", f"![{caption}]({rel})", ""]
            if svg in figure_paths:
                lines.append(f"Vector version: [{svg.name}]({svg.relative_to(out).as_posix()})")

    lines += ["", "## All results", ""]
    lines.append("Every scalar of `analysis.json`, by analyzer; long lists are only in the file.")
    for name in summary.get("analyses", []):
        rows: list[tuple[str, str]] = []
        _flatten("", summary[name], rows)
        lines += ["", f"### {name}", ""]
        lines += _md_table(("key", "value"), rows)

    if tables:
        minerals = ", ".join(f"{k} = {n}" for k, n in enumerate(summary["mineral_names"]))
        lines += ["", "## Tables", ""]
        lines.append(
            f"Particle indices are positions in the packing file; mineral indices: {minerals}."
        )
        lines.append("")
        for table, path in tables.items():
            cols = ", ".join(f"`{c}`" for c in columns.get(table, ()))
            lines.append(f"- [{path.name}]({path.relative_to(out).as_posix()}): {cols}")
    return "\n".join(lines) + "\n"
