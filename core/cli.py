"""Command line: ``regopack run | scenes | config | verify | analyze | export | plugins | schema``.

A user error (:class:`~regopack.errors.RegopackError`, an invalid scene or
TOML file, a missing file, a bad option) prints one line
``regopack: error: <message>`` and exits with status 2; anything unexpected
keeps its traceback. ``Ctrl-C`` (SIGINT) exits with status 130 and SIGTERM
(what batch schedulers send at a time limit) with status 143, each after one
line and leaving no partial output: output folders are swapped in only when
complete (see :mod:`regopack.outdir`).
"""

from __future__ import annotations

import argparse
import json
import math
import signal
import sys
import threading
import tomllib
from collections.abc import Callable, Iterator, Sequence
from contextlib import contextmanager
from pathlib import Path
from typing import Any, NoReturn

from pydantic import ValidationError
from rich import box
from rich.console import Console
from rich.progress import (
    BarColumn,
    Progress,
    ProgressColumn,
    Task,
    TextColumn,
    TimeElapsedColumn,
    TimeRemainingColumn,
)
from rich.table import Table
from rich.text import Text

from regopack import __version__
from regopack.errors import ConfigError, RegopackError, Terminated
from regopack.interfaces import ProgressCallback
from regopack.plugin_types import KINDS

__all__ = ["build_parser", "main"]

EXIT_OK = 0
EXIT_VIOLATED = 1
EXIT_USAGE = 2
EXIT_INTERRUPTED = 130
EXIT_TERMINATED = 143


class _RateColumn(ProgressColumn):
    """Particles handled per second."""

    def render(self, task: Task) -> Text:
        speed = task.finished_speed or task.speed
        return Text("-- particles/s" if speed is None else f"{speed:,.0f} particles/s")


class _PlacedColumn(ProgressColumn):
    """Particles placed out of the total drawn."""

    def render(self, task: Task) -> Text:
        placed = int(task.fields.get("placed", 0))
        total = "?" if task.total is None else f"{int(task.total):,}"
        return Text(f"{placed:,}/{total} placed")


@contextmanager
def _progress_bar(console: Console, enabled: bool, label: str) -> Iterator[ProgressCallback | None]:
    """Show a rich progress bar fed by ``progress(done, placed, total)`` calls."""
    if not enabled:
        yield None
        return
    columns = (
        TextColumn("{task.description}"),
        BarColumn(bar_width=30),
        _PlacedColumn(),
        _RateColumn(),
        TimeElapsedColumn(),
        TimeRemainingColumn(),
    )
    with shown_until_error(Progress(*columns, console=console, transient=False)) as bar:
        task = bar.add_task(label, total=None, placed=0)

        def update(done: int, placed: int, total: int) -> None:
            bar.update(task, completed=done, total=total, placed=placed)

        yield update


@contextmanager
def shown_until_error(progress: Progress) -> Iterator[Progress]:
    """Show ``progress`` during the block; an error removes it, leaving only the error's line.

    On a terminal the display is erased; into a file or pipe (where it is
    drawn once, at the end) it is not drawn at all.
    """
    console = progress.console
    was_quiet = console.quiet
    try:
        with progress:
            try:
                yield progress
            except BaseException:
                if console.is_terminal:
                    progress.live.transient = True
                else:
                    console.quiet = True
                raise
    finally:
        console.quiet = was_quiet


class _ArgumentParser(argparse.ArgumentParser):
    """Argument parser whose usage errors are one line, like every other user error."""

    def error(self, message: str) -> NoReturn:
        command = self.prog.removeprefix("regopack").strip()
        where = f"{command}: " if command else ""
        self.exit(EXIT_USAGE, f"regopack: error: {where}{message} (see '{self.prog} --help')\n")


def output_path(text: str) -> Path:
    """Argument type of ``--out``: a path, never the empty string (which would mean ``.``)."""
    if not text.strip():
        raise argparse.ArgumentTypeError(
            f"{text!r} is an empty path; give a folder or file name, e.g. runs/mine"
        )
    return Path(text)


def _rel_tol(text: str) -> float:
    """Argument type of ``--rel-tol``: a finite number >= 0."""
    try:
        value = float(text)
    except ValueError:
        value = math.nan
    if not (math.isfinite(value) and value >= 0):
        raise argparse.ArgumentTypeError(f"{text!r}: must be a finite number >= 0, e.g. 1e-9")
    return value


def _add_scene_arguments(parser: argparse.ArgumentParser) -> None:
    parser.add_argument(
        "scene",
        nargs="?",
        metavar="SCENE",
        help="built-in scene name or path of a TOML scene file (default: table1)",
    )
    parser.add_argument(
        "--set",
        dest="overrides",
        action="append",
        default=[],
        metavar="KEY=VALUE",
        help="override a scene value, e.g. --set density.eta=10 (repeatable)",
    )
    parser.add_argument("--seed", type=int, metavar="N", help="seed of the random generator")


def build_parser() -> argparse.ArgumentParser:
    """Build the argument parser of the ``regopack`` command."""
    parser = _ArgumentParser(
        prog="regopack",
        description="Dense 2D packings of lunar regolith particles.",
    )
    parser.add_argument("--version", action="version", version=f"regopack {__version__}")
    sub = parser.add_subparsers(dest="command", metavar="COMMAND")

    run = sub.add_parser("run", help="pack a scene and write the packing and its summary")
    _add_scene_arguments(run)
    run.add_argument(
        "--out",
        type=output_path,
        metavar="DIR",
        help="output folder, replaced as a whole by the run (default: runs/<scene>-seed<seed>)",
    )
    run.add_argument("--quiet", action="store_true", help="print no progress and no summary")
    run.add_argument(
        "--verify",
        action="store_true",
        help="check the packing for overlaps and wall violations; exit 1 if violated "
        "(done anyway, without the exit status, when the insertion settings may overlap)",
    )
    run.set_defaults(handler=_cmd_run)

    scenes = sub.add_parser("scenes", help="list the built-in scenes")
    scenes.set_defaults(handler=_cmd_scenes)

    config = sub.add_parser("config", help="print the fully resolved scene as TOML")
    _add_scene_arguments(config)
    config.set_defaults(handler=_cmd_config)

    verify = sub.add_parser("verify", help="check a packing for overlaps and wall violations")
    verify.add_argument("packing", type=Path, metavar="PACKING", help="packing file (.npz)")
    verify.add_argument(
        "--rel-tol",
        type=_rel_tol,
        default=1e-9,
        metavar="X",
        help="tolerated overlap, relative to the smaller particle area (default: 1e-9)",
    )
    verify.set_defaults(handler=_cmd_verify)

    analyze = sub.add_parser(
        "analyze",
        help="analyse a packing: density, contacts, coordination, g(r), network",
        description=(
            "Run structure analyses on a saved packing and write analysis.json, one table "
            "per analysis, figures (PNG and SVG) and report.md."
        ),
    )
    analyze.add_argument("packing", type=Path, metavar="PACKING", help="packing file (.npz)")
    analyze.add_argument(
        "--only",
        action="append",
        default=[],
        metavar="NAME[,NAME...]",
        help="run only these analyzers (and what they need); default: "
        "density, contacts, coordination, rdf, network",
    )
    analyze.add_argument(
        "--tol",
        type=float,
        metavar="X",
        help="contact tolerance in micrometres (sets contacts.tol; default 0.05)",
    )
    analyze.add_argument(
        "--set",
        dest="overrides",
        action="append",
        default=[],
        metavar="NAME.FIELD=VALUE",
        help="set an analyzer parameter, e.g. --set contacts.tol_max=1 (repeatable)",
    )
    analyze.add_argument(
        "--out",
        type=output_path,
        metavar="DIR",
        help="output folder, replaced as a whole (default: <packing dir>/analysis)",
    )
    analyze.add_argument(
        "--tables",
        choices=("csv", "npz"),
        default="csv",
        help="file format of the tables (default: csv)",
    )
    analyze.add_argument("--no-figures", action="store_true", help="draw no figures")
    analyze.set_defaults(handler=_cmd_analyze)

    export = sub.add_parser(
        "export",
        help="write a packing for LAMMPS, HOOMD-blue (GSD), VTK, image tools, CSV, JSON or SVG",
        description=(
            "Write a saved packing in another program's file format with an exporter "
            "plugin (see 'regopack plugins --kind export')."
        ),
    )
    export.add_argument("packing", type=Path, metavar="PACKING", help="packing file (.npz)")
    export.add_argument(
        "--to",
        required=True,
        metavar="FORMAT",
        help="exporter name: csv, json, svg, vtk, lammps, gsd, image or one from a plugin",
    )
    export.add_argument(
        "--out",
        type=output_path,
        metavar="PATH",
        help="output file, or a directory (default: the packing's name with the format's suffix)",
    )
    export.add_argument(
        "--set",
        dest="overrides",
        action="append",
        default=[],
        metavar="FIELD=VALUE",
        help="set an exporter parameter, e.g. --set stiffness=1e5 (repeatable)",
    )
    export.add_argument(
        "--analyses",
        action="append",
        default=[],
        metavar="NAME[,NAME...]",
        help="run these analyzers first and pass their results on (vtk adds Z from coordination)",
    )
    export.set_defaults(handler=_cmd_export)

    plugins = sub.add_parser(
        "plugins",
        help="list the plugins with their origin and parameters",
        description=(
            "List every registered plugin: its kind, name, the module that provides it, "
            "the distribution package and version that installed it, and its parameters "
            "with their type, default and description."
        ),
    )
    plugins.add_argument(
        "--kind",
        choices=tuple(KINDS),
        help="list only the plugins of this kind",
    )
    plugins.add_argument(
        "--json", action="store_true", help="print machine-readable JSON instead of tables"
    )
    plugins.set_defaults(handler=_cmd_plugins)

    schema = sub.add_parser(
        "schema",
        help="print the JSON Schema of scene files, with the plugins' parameters",
        description=(
            "Print the JSON Schema (draft 2020-12) of scene files, including the parameters "
            "of every installed plugin, so that editors can check scene files."
        ),
    )
    schema.add_argument(
        "--output",
        type=Path,
        metavar="FILE",
        help="write the schema to FILE instead of standard output",
    )
    schema.set_defaults(handler=_cmd_schema)

    from regopack.sweep_cli import add_sweep_parser

    add_sweep_parser(sub)
    return parser


def _resolve(args: argparse.Namespace) -> Any:
    from regopack.manager import default_registry
    from regopack.scene import load_scene, resolve_scene

    scene = load_scene(args.scene, args.overrides, seed=args.seed)
    return resolve_scene(scene, default_registry())


def _kernels_not_cached() -> bool:
    """Return whether the compiled-kernel cache folder holds no compiled code yet."""
    import os
    from pathlib import Path

    from regopack.jit import kernel_cache_dir

    folder = Path(os.environ.get("NUMBA_CACHE_DIR") or kernel_cache_dir())
    return not any(folder.rglob("*.nbi")) if folder.is_dir() else True


def _refuse_inside(path: Path, folder: Path, what: str) -> None:
    """Refuse an output folder that holds ``path``: replacing it would delete the input."""
    import os

    real, real_folder = os.path.realpath(path), os.path.realpath(folder)
    if os.path.commonpath([real, real_folder]) == real_folder:
        raise ConfigError(
            f"output folder {folder}: holds the {what} {path}, and the output folder is "
            "replaced as a whole; give another folder"
        )


def _cmd_run(args: argparse.Namespace, out: Console, err: Console) -> int:
    from regopack.outdir import check_replaceable
    from regopack.run import RUN_FOLDER, check_scene, default_out_dir, run_scene, summary_rows

    resolved = _resolve(args)
    out_dir = args.out if args.out is not None else default_out_dir(resolved)
    if args.scene is not None and Path(args.scene).is_file():
        _refuse_inside(Path(args.scene), out_dir, "scene file")
    check_replaceable(out_dir, RUN_FOLDER)  # before the progress bar: errors stay one line
    check_scene(resolved)
    if not args.quiet and _kernels_not_cached():
        err.print(
            "[dim]compiling the packing kernels (first run after an install or upgrade; "
            "about 15-30 s, then cached)[/dim]"
        )
    with _progress_bar(err, not args.quiet, f"packing {resolved.name}") as progress:
        outcome = run_scene(resolved, out_dir, progress=progress, verify=args.verify or None)
    tried, placed = outcome.summary["tried"], outcome.summary["placed"]
    checked = outcome.summary.get("verify")
    violated = False
    if checked is not None and not checked["ok"]:
        violated = True
        print(
            f"regopack: warning: the packing is violated: {checked['overlap_pairs']:,} "
            f"overlapping pairs (worst {checked['worst_overlap']:.3g} of the smaller area), "
            f"{checked['outside']:,} particles outside the domain; see 'verify' in "
            f"{outcome.summary_path}",
            file=sys.stderr,
        )
    status = EXIT_VIOLATED if violated and args.verify else EXIT_OK
    if tried and not placed:
        print(
            f"regopack: warning: no particle was placed: none of the {tried:,} particles drawn "
            f"fits into the domain; the packing in {outcome.packing_path} is empty",
            file=sys.stderr,
        )
    if args.quiet:
        return status
    table = Table(title=f"regopack run: {resolved.name}", show_header=False)
    table.add_column("quantity", style="bold")
    table.add_column("value", justify="right")
    for label, value in summary_rows(outcome.summary):
        table.add_row(label, value)
    table.add_row("packing", str(outcome.packing_path))
    table.add_row("summary", str(outcome.summary_path))
    if outcome.analysis is not None:
        table.add_row("analysis", str(outcome.analysis.report))
    for path in outcome.exports:
        table.add_row("export", str(path))
    out.print(table)
    return status


def _cmd_scenes(args: argparse.Namespace, out: Console, err: Console) -> int:
    from regopack.scene import DEFAULT_SCENE, builtin_scenes

    table = Table(title="built-in scenes")
    table.add_column("name", style="bold")
    table.add_column("description")
    for name, description in builtin_scenes().items():
        table.add_row(name + (" (default)" if name == DEFAULT_SCENE else ""), description)
    out.print(table)
    return EXIT_OK


def _cmd_config(args: argparse.Namespace, out: Console, err: Console) -> int:
    resolved = _resolve(args)
    out.file.write(resolved.to_toml())
    return EXIT_OK


def _cmd_verify(args: argparse.Namespace, out: Console, err: Console) -> int:
    from regopack.packing import load
    from regopack.verify import verify

    report = verify(load(args.packing), rel_tol=args.rel_tol)
    out.file.write(f"{report}\n")
    return EXIT_OK if report.ok else EXIT_VIOLATED


def _analyzer_names(only: Sequence[str]) -> list[str]:
    """Names given to ``--only`` (comma-separated, repeatable), in order, without repeats."""
    names: list[str] = []
    for text in only:
        parts = [p.strip() for p in text.split(",")]
        if not all(parts):
            raise ConfigError(f"--only {text!r}: empty analyzer name")
        names += [p for p in parts if p not in names]
    return names


def _analyzer_params(overrides: Sequence[str], tol: float | None) -> dict[str, dict[str, Any]]:
    """Parameters by analyzer from ``--set NAME.FIELD=VALUE`` and ``--tol``."""
    params: dict[str, dict[str, Any]] = {}
    for text in overrides:
        key, sep, raw = text.partition("=")
        name, dot, field = key.strip().partition(".")
        if not sep or not dot or not name.strip() or not field.strip() or "." in field:
            raise ConfigError(f"--set {text!r}: expected NAME.FIELD=VALUE, e.g. contacts.tol_max=1")
        try:
            value = tomllib.loads("v = " + raw.strip())["v"]
        except tomllib.TOMLDecodeError:
            value = raw.strip()
        params.setdefault(name.strip(), {})[field.strip()] = value
    if tol is not None:
        params.setdefault("contacts", {})["tol"] = tol
    return params


def _cmd_analyze(args: argparse.Namespace, out: Console, err: Console) -> int:
    from regopack.analysis import (
        ANALYSIS_KIND,
        DEFAULT_ANALYSES,
        main_numbers,
        run_analyses,
        write_analysis,
    )
    from regopack.manager import default_registry
    from regopack.outdir import check_replaceable
    from regopack.packing import load

    names = _analyzer_names(args.only) or list(DEFAULT_ANALYSES)
    params = _analyzer_params(args.overrides, args.tol)
    packing = load(args.packing)
    out_dir = args.out if args.out is not None else args.packing.parent / "analysis"
    _refuse_inside(args.packing, out_dir, "packing file")
    check_replaceable(out_dir, ANALYSIS_KIND)
    registry = default_registry()
    with err.status(f"analysing {args.packing}"):
        analyzers = run_analyses(packing, registry, [(n, {}) for n in names], params=params)
        files = write_analysis(
            out_dir,
            packing,
            analyzers,
            figures=not args.no_figures,
            packing_path=args.packing,
            table_format=args.tables,
            registry=registry,
        )
    table = Table(title=f"regopack analyze: {args.packing}", show_header=False)
    table.add_column("quantity", style="bold")
    table.add_column("value", justify="right")
    table.add_row("analyses", ", ".join(analyzers))
    for label, value in main_numbers(files.summary):
        table.add_row(label, value)
    out.print(table)
    written = [("results", str(files.results))]
    if files.tables:
        table_files = ", ".join(p.name for p in files.tables.values())
        written.append(("tables", f"{files.out_dir} ({table_files})"))
    if files.figures:
        pngs = [p for p in files.figures if p.suffix == ".png"]
        written.append(("figures", f"{files.out_dir / 'figures'} ({len(pngs)} × PNG + SVG)"))
    written.append(("report", str(files.report)))
    for label, text in written:  # whole paths, never cut to the terminal's width
        out.print(f"{label:<8} {text}", soft_wrap=True, markup=False, highlight=False)
    return EXIT_OK


def _exporter_params(overrides: Sequence[str]) -> dict[str, Any]:
    """Return the exporter parameters given as ``--set FIELD=VALUE``."""
    params: dict[str, Any] = {}
    for text in overrides:
        key, sep, raw = text.partition("=")
        if not sep or not key.strip():
            raise ConfigError(f"--set {text!r}: expected FIELD=VALUE, e.g. stiffness=1e5")
        try:
            value = tomllib.loads("v = " + raw.strip())["v"]
        except tomllib.TOMLDecodeError:
            value = raw.strip()
        params[key.strip()] = value
    return params


def _cmd_export(args: argparse.Namespace, out: Console, err: Console) -> int:
    from regopack.analysis import run_analyses
    from regopack.export import build_exporter, export_packing, output_path
    from regopack.manager import default_registry
    from regopack.packing import load

    registry = default_registry()
    params = _exporter_params(args.overrides)
    exporter = build_exporter(registry, args.to, params)
    packing = load(args.packing)
    names = _analyzer_names(args.analyses)
    analyzers = run_analyses(packing, registry, [(n, {}) for n in names]) if names else None
    path = output_path(exporter, args.packing, args.out)
    written = export_packing(
        packing, args.to, path, registry=registry, params=params, analyses=analyzers
    )
    out.print(f"wrote {written}", soft_wrap=True, markup=False, highlight=False)
    return EXIT_OK


KIND_TITLES: dict[str, str] = {
    "size": "size distribution, scene section [size]",
    "shape": "shape generator, scene key phases[].shape",
    "insertion": "insertion strategy, scene section [insertion]",
    "density": "density controller, scene section [density]",
    "analysis": "analyzer, scene key outputs.analyses",
    "export": "exporter, scene key outputs.exports and regopack export --to",
}
"""What each plugin kind is and where a scene selects it."""


def _format_number(value: Any) -> str:
    if isinstance(value, float):
        text = repr(value)
        return text if len(text) <= 8 else f"{value:.6g}"
    return json.dumps(value, ensure_ascii=False)


def _format_default(field: dict[str, Any]) -> str:
    """Format a field's default as a TOML-like literal, or ``required`` or ``none``."""
    if field["required"]:
        return "required"
    value = field["default"]
    if value is None:
        return "none"
    if isinstance(value, list):
        shown = [_format_number(v) for v in value[: 3 if len(value) > 4 else 4]]
        more = f", … ({len(value)} values)" if len(value) > 4 else ""
        return "[" + ", ".join(shown) + more + "]"
    return _format_number(value)


def _cmd_plugins(args: argparse.Namespace, out: Console, err: Console) -> int:
    from regopack import __version__
    from regopack.manager import default_registry
    from regopack.schema import describe_plugins

    entries = describe_plugins(default_registry(), args.kind)
    if args.json:
        out.file.write(
            json.dumps({"regopack": __version__, "plugins": entries}, indent=2, ensure_ascii=False)
            + "\n"
        )
        return EXIT_OK
    overview = Table(title="regopack plugins", title_justify="left")
    overview.add_column("kind")
    overview.add_column("name", style="bold")
    overview.add_column("origin module", overflow="fold")
    overview.add_column("package", overflow="fold")
    for entry in entries:
        overview.add_row(
            *(Text(t) for t in (entry["kind"], entry["name"], entry["module"], _package(entry)))
        )
    if not entries:
        overview.add_row("(none)", "", "", "")
    out.print(overview)
    for entry in entries:
        out.print()
        header = Text.assemble(
            (f"{entry['kind']} ", "dim"),
            (entry["name"], "bold"),
            f"  {KIND_TITLES[entry['kind']]}\n",
            (f"{entry['module']} ({_package(entry)})", "dim"),
        )
        if entry["description"]:
            header.append("\n" + entry["description"])
        out.print(header)
        if not entry["fields"]:
            out.print("  no parameters", style="dim")
            continue
        fields = Table(box=box.SIMPLE_HEAD, show_edge=False, padding=(0, 1, 0, 2), expand=True)
        fields.add_column("parameter", style="cyan", no_wrap=True)
        fields.add_column("type")
        fields.add_column("default")
        fields.add_column("description", ratio=1)
        for field in entry["fields"]:
            fields.add_row(
                *(
                    Text(t)
                    for t in (
                        field["name"],
                        field["type"],
                        _format_default(field),
                        field["description"],
                    )
                )
            )
        out.print(fields)
    return EXIT_OK


def _package(entry: dict[str, Any]) -> str:
    """``"<distribution> <version>"`` of a plugin entry, or ``"-"`` when not known."""
    if not entry["distribution"]:
        return "-"
    if entry["version"]:
        return f"{entry['distribution']} {entry['version']}"
    return str(entry["distribution"])


def _cmd_schema(args: argparse.Namespace, out: Console, err: Console) -> int:
    from regopack.manager import default_registry
    from regopack.packing import write_json_atomic
    from regopack.schema import dumps, json_schema

    schema = json_schema(default_registry(), "scene")
    if args.output is None:
        out.file.write(dumps(schema))
        return EXIT_OK
    try:
        write_json_atomic(args.output, schema)
    except OSError as exc:
        why = exc.strerror or type(exc).__name__
        raise ConfigError(f"cannot write the schema to {args.output}: {why}") from exc
    err.print(f"wrote the scene schema to {args.output}", soft_wrap=True, highlight=False)
    return EXIT_OK


def _one_line(exc: BaseException) -> str:
    if isinstance(exc, ValidationError):
        first = exc.errors(include_url=False)[0]
        loc = ".".join(str(p) for p in first["loc"])
        text = f"{loc}: {first['msg']}" if loc else first["msg"]
    elif isinstance(exc, OSError) and exc.filename is not None:
        text = f"{exc.filename}: {exc.strerror or exc}"
    else:
        text = str(exc) or type(exc).__name__
    return " ".join(text.split())


def main(argv: Sequence[str] | None = None) -> int:
    """Run the ``regopack`` command; return its exit status.

    Parameters
    ----------
    argv
        Arguments without the program name (default: ``sys.argv[1:]``).
    """
    parser = build_parser()
    try:
        args = parser.parse_args(argv)
    except SystemExit as exit_:  # --help, --version, usage errors
        return exit_.code if isinstance(exit_.code, int) else EXIT_USAGE
    handler: Callable[[argparse.Namespace, Console, Console], int] | None = getattr(
        args, "handler", None
    )
    if handler is None:
        parser.print_help(sys.stderr)
        return EXIT_USAGE
    out = Console(file=sys.stdout)
    err = Console(file=sys.stderr)
    try:
        with _signals_raise():
            return handler(args, out, err)
    except (RegopackError, ValidationError, tomllib.TOMLDecodeError, FileNotFoundError) as exc:
        print(f"regopack: error: {_one_line(exc)}", file=sys.stderr)
        return EXIT_USAGE
    except Terminated:
        print("regopack: terminated; no partial files were written", file=sys.stderr)
        return EXIT_TERMINATED
    except KeyboardInterrupt:
        print("regopack: interrupted; no partial files were written", file=sys.stderr)
        return EXIT_INTERRUPTED


@contextmanager
def _signals_raise() -> Iterator[None]:
    """Within the block, SIGTERM raises :class:`Terminated` and SIGINT ``KeyboardInterrupt``.

    Both are deferred while an output folder is being swapped in (see
    :func:`regopack.outdir.raise_or_defer`). A signal that is ignored (e.g.
    SIGINT in a background job) stays ignored; a second SIGTERM is ignored
    while the first one is being handled.
    """
    from regopack.outdir import raise_or_defer

    if threading.current_thread() is not threading.main_thread():
        yield
        return
    terminated = False

    def on_term(signum: int, frame: object) -> None:
        nonlocal terminated
        if not terminated:
            terminated = True
            raise_or_defer(Terminated())

    def on_int(signum: int, frame: object) -> None:
        raise_or_defer(KeyboardInterrupt())

    previous: dict[signal.Signals, Any] = {}
    for signum, handler, default in (
        (signal.SIGTERM, on_term, signal.SIG_DFL),
        (signal.SIGINT, on_int, signal.default_int_handler),
    ):
        if signal.getsignal(signum) is default:
            previous[signum] = signal.signal(signum, handler)
    try:
        yield
    finally:
        for signum, handler in previous.items():
            signal.signal(signum, handler)
