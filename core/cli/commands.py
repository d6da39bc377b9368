"""Command line: ``regopack run | compile | scenes | config | verify | analyze | export | ...``.

A user error (:class:`~regopack.base.errors.RegopackError`, an invalid scene or
TOML file, a missing file, a bad option) prints one line
``regopack: error: <message>`` and exits with status 2; anything unexpected
keeps its traceback. ``Ctrl-C`` (SIGINT) exits with status 130 and SIGTERM
(what batch schedulers send at a time limit) with status 143, each after one
line and leaving no partial output: output folders are swapped in only when
complete (see :mod:`regopack.base.outdir`).
"""

from __future__ import annotations

import argparse
import json
import math
import os
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
from rich.table import Table
from rich.text import Text

from regopack._version import __version__
from regopack.base.errors import ConfigError, RegopackError, Terminated
from regopack.cli.args import output_path
from regopack.registry.plugin_types import KINDS

__all__ = ["build_parser", "main"]

EXIT_OK = 0
EXIT_VIOLATED = 1
EXIT_USAGE = 2
EXIT_INTERRUPTED = 130
EXIT_TERMINATED = 143


class _ArgumentParser(argparse.ArgumentParser):
    """Argument parser whose usage errors are one line, like every other user error."""

    def error(self, message: str) -> NoReturn:
        command = self.prog.removeprefix("regopack").strip()
        where = f"{command}: " if command else ""
        self.exit(EXIT_USAGE, f"regopack: error: {where}{message} (see '{self.prog} --help')\n")


def _rel_tol(text: str) -> float:
    """Argument type of ``--rel-tol``: a finite number >= 0."""
    try:
        value = float(text)
    except ValueError:
        value = math.nan
    if not (math.isfinite(value) and value >= 0):
        raise argparse.ArgumentTypeError(f"{text!r}: must be a finite number >= 0, e.g. 1e-9")
    return value


def _add_set(parser: argparse.ArgumentParser, metavar: str, help_text: str) -> None:
    """Add the repeatable option ``--set`` (into ``overrides``)."""
    parser.add_argument(
        "--set", dest="overrides", action="append", default=[], metavar=metavar, help=help_text
    )


def _add_scene_arguments(parser: argparse.ArgumentParser) -> None:
    parser.add_argument(
        "scene",
        nargs="?",
        metavar="SCENE",
        help="built-in scene name or path of a TOML scene file (default: table1)",
    )
    _add_set(parser, "KEY=VALUE", "override a scene value, e.g. --set density.eta=10 (repeatable)")
    parser.add_argument("--seed", type=int, metavar="N", help="seed of the random generator")


def build_parser() -> argparse.ArgumentParser:
    """Build the argument parser of the ``regopack`` command."""
    parser = _ArgumentParser(
        prog="regopack",
        description="Dense 2D and 3D packings of lunar regolith particles.",
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
    run.add_argument(
        "--workers",
        type=int,
        metavar="N",
        help="local worker processes that pack a tiled scene's tiles (default: 1, this "
        "process); the packing is the same on any number",
    )
    run.add_argument(
        "--threads-per-worker",
        type=int,
        metavar="T",
        help="compiled-kernel threads of each local worker (default: its share of the cores)",
    )
    run.add_argument(
        "--scheduler",
        metavar="ADDR",
        help="pack a tiled scene's tiles on a Dask cluster, e.g. tcp://host:8786 "
        "(needs Dask: pip install distributed)",
    )
    run.set_defaults(handler=_cmd_run)

    compile_ = sub.add_parser(
        "compile",
        help="compile every kernel ahead of time (e.g. for a cluster image)",
        description=(
            "Compile every built-in kernel now and cache it, by packing, analysing and "
            "exporting a few tiny scenes; later runs then start at once."
        ),
    )
    compile_.add_argument("--quiet", action="store_true", help="print nothing")
    compile_.set_defaults(handler=_cmd_compile)

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
        "density, contacts, coordination, rdf, network (3D packings: density3d, contacts3d, "
        "coordination3d, rdf3d, network3d)",
    )
    analyze.add_argument(
        "--tol",
        type=float,
        metavar="X",
        help="contact tolerance in the packing's length unit (sets contacts.tol; "
        "default d_min / 40, 0.05 for the built-in scenes)",
    )
    _add_set(
        analyze,
        "NAME.FIELD=VALUE",
        "set an analyzer parameter, e.g. --set contacts.tol_max=1 (repeatable)",
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
        help="write a packing for LAMMPS, LIGGGHTS, YADE, GSD, VTK, image tools, CSV, JSON or SVG",
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
        help=(
            "exporter name: vtk, lammps, gsd, image (2D and 3D packings); csv, json, svg "
            "(2D packings); stl, slice, liggghts, yade (3D packings); or one from a plugin"
        ),
    )
    export.add_argument(
        "--out",
        type=output_path,
        metavar="PATH",
        help="output file, or a directory (default: the packing's name with the format's suffix)",
    )
    _add_set(
        export, "FIELD=VALUE", "set an exporter parameter, e.g. --set stiffness=1e5 (repeatable)"
    )
    export.add_argument(
        "--analyses",
        action="append",
        default=[],
        metavar="NAME[,NAME...]",
        help="run these analyzers first and pass their results on (vtk adds Z from coordination)",
    )
    export.add_argument(
        "--force",
        action="store_true",
        help=(
            "overwrite companion files (e.g. a LAMMPS input script) that exist beside a main "
            "file that does not"
        ),
    )
    export.set_defaults(handler=_cmd_export)

    settled = sub.add_parser(
        "settled",
        help="read the final state of a DEM run (YADE, LIGGGHTS, LAMMPS) into a packing file",
        description=(
            "Write the packing as the run of its exported files left it: the same particles, "
            "moved and turned, for every analysis to compare before and after."
        ),
    )
    settled.add_argument("packing", type=Path, metavar="PACKING", help="the exported packing")
    settled.add_argument(
        "state",
        type=Path,
        metavar="STATE",
        help="the run's final state (yade: <stem>.final.txt; liggghts, lammps: <stem>.final.dump)",
    )
    settled.add_argument(
        "--from",
        dest="exporter",
        required=True,
        metavar="FORMAT",
        help="the exporter that wrote the run's files: yade, liggghts or lammps",
    )
    settled.add_argument(
        "--out",
        type=output_path,
        metavar="PATH",
        help="packing file to write (default: the state's name with .npz, beside it)",
    )
    _add_set(
        settled,
        "FIELD=VALUE",
        "an exporter parameter of the export that sets lengths, e.g. --set length_scale=1e-6",
    )
    settled.set_defaults(handler=_cmd_settled)

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

    from regopack.cli.sweep import add_sweep_parser

    add_sweep_parser(sub)
    return parser


def _resolve(args: argparse.Namespace) -> Any:
    from regopack.registry.manager import default_registry
    from regopack.scenes.model import load_scene, resolve_scene

    scene = load_scene(args.scene, args.overrides, seed=args.seed)
    return resolve_scene(scene, default_registry())


def _cmd_run(args: argparse.Namespace, out: Console, err: Console) -> int:
    from regopack.api.functions import pack_and_summarise, refuse_inside
    from regopack.run.pipeline import default_out_dir, summary_rows

    resolved = _resolve(args)
    out_dir = args.out if args.out is not None else default_out_dir(resolved)
    if args.scene is not None and Path(args.scene).is_file():
        refuse_inside(Path(args.scene), out_dir, "scene file")
    from regopack.tiling.executors import executor_for

    tiled = resolved.scene.tiles is not None
    flags = ("--workers", "--threads-per-worker", "--scheduler")
    with executor_for(tiled, args.workers, args.threads_per_worker, args.scheduler, flags=flags):
        pass  # the options are checked before anything is drawn
    outcome = pack_and_summarise(
        resolved,
        out=out_dir,
        progress=not args.quiet,
        verify=args.verify or None,
        workers=args.workers,
        threads_per_worker=args.threads_per_worker,
        client=args.scheduler,
    )
    tried, placed = outcome.summary["tried"], outcome.summary["placed"]
    checked = outcome.summary.get("verify")
    violated = False
    if checked is not None and not checked.get("ok", True):
        violated = True
        print(
            f"regopack: warning: the packing is violated: {checked['overlap_pairs']:,} "
            f"overlapping pairs (worst {checked['worst_overlap']:.3g} of the smaller "
            f"{'volume' if outcome.summary.get('dimension') == 3 else 'area'}), "
            f"{checked['outside']:,} particles outside the domain; see 'verify' in "
            f"{outcome.summary_path}",
            file=sys.stderr,
        )
    status = EXIT_VIOLATED if violated and args.verify else EXIT_OK
    if not placed:
        why = (
            f"none of the {tried:,} particles drawn fits into the domain"
            if tried
            else 'the scene gives no particle to draw (count = "auto": the domain holds '
            "less than half a particle of the mean size)"
        )
        print(
            f"regopack: warning: no particle was placed: {why}; the packing in "
            f"{outcome.packing_path} is empty",
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


def _cmd_compile(args: argparse.Namespace, out: Console, err: Console) -> int:
    import os

    from regopack.api.warmup import compile_kernels
    from regopack.base.jit import kernel_cache_dir

    def report(step: str, seconds: float) -> None:
        if not args.quiet:
            out.print(f"{seconds:6.1f} s  {step}", soft_wrap=True, markup=False, highlight=False)

    total = compile_kernels(report)
    if not args.quiet:
        folder = os.environ.get("NUMBA_CACHE_DIR") or str(kernel_cache_dir())
        out.print(
            f"compiled {total.functions} kernel signatures in {total.seconds:.1f} s; "
            f"cache: {folder}",
            soft_wrap=True,
            markup=False,
            highlight=False,
        )
    return EXIT_OK


def _cmd_scenes(args: argparse.Namespace, out: Console, err: Console) -> int:
    from regopack.scenes.model import DEFAULT_SCENE, builtin_scenes

    table = Table(title="built-in scenes")
    table.add_column("name", style="bold")
    table.add_column("description")
    for name, description in builtin_scenes().items():
        table.add_row(name + (" (default)" if name == DEFAULT_SCENE else ""), description)
    out.print(table)
    return EXIT_OK


def _cmd_config(args: argparse.Namespace, out: Console, err: Console) -> int:
    from regopack.run.pipeline import check_runnable

    resolved = _resolve(args)
    check_runnable(resolved)  # the checks of `regopack run`, before anything is drawn
    out.file.write(resolved.to_toml())
    return EXIT_OK


def _cmd_verify(args: argparse.Namespace, out: Console, err: Console) -> int:
    from regopack.api.functions import verify

    report = verify(args.packing, rel_tol=args.rel_tol)
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
    """Parameters by analyzer from ``--set NAME.FIELD=VALUE`` and ``--tol`` (of ``contacts``)."""
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
    from regopack.analysis.pipeline import main_numbers
    from regopack.api.functions import analyze

    names = _analyzer_names(args.only) or None
    params = _analyzer_params(args.overrides, args.tol)
    out_dir = args.out if args.out is not None else args.packing.parent / "analysis"
    with err.status(f"analysing {args.packing}"):
        results = analyze(
            args.packing,
            names,
            out=out_dir,
            figures=not args.no_figures,
            tables=args.tables,
            params=params,
            params_source="--set",
        )
    files = results.files
    assert files is not None  # written, since out is given
    analyzers = results.analyzers
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
    from regopack.api.functions import export

    params = _exporter_params(args.overrides)
    names = _analyzer_names(args.analyses)
    written = export(
        args.packing,
        args.to,
        args.out,
        analyses=names or None,
        params=params,
        params_source="--set",
        force=args.force,
    )
    out.print(f"wrote {written}", soft_wrap=True, markup=False, highlight=False)
    return EXIT_OK


def _cmd_settled(args: argparse.Namespace, out: Console, err: Console) -> int:
    from regopack.api.functions import settled
    from regopack.packing.core import save

    target = args.out or args.state.with_suffix(".npz")
    if target.is_dir():
        target = target / args.state.with_suffix(".npz").name
    if not target.parent.is_dir():
        raise ConfigError(f"--out {target}: its folder {target.parent} does not exist")
    for given in (args.packing, args.state):
        if target.exists() and given.exists() and target.samefile(given):
            raise ConfigError(f"--out {target}: is {given} itself; give another file")
    packing = settled(
        args.packing,
        args.state,
        args.exporter,
        params=_exporter_params(args.overrides),
        params_source="--set",
    )
    save(packing, target)
    out.print(f"wrote {target}", soft_wrap=True, markup=False, highlight=False)
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
    from regopack.registry.manager import default_registry
    from regopack.scenes.schema import describe_plugins

    entries = describe_plugins(default_registry(), args.kind)
    if args.json:
        out.file.write(
            json.dumps({"regopack": __version__, "plugins": entries}, indent=2, ensure_ascii=False)
            + "\n"
        )
        return EXIT_OK
    # names are never cut: they take the room they need, the other columns wrap
    overview = Table(title="regopack plugins", title_justify="left")
    overview.add_column("kind", no_wrap=True)
    overview.add_column("name", style="bold", no_wrap=True)
    overview.add_column("origin module", overflow="fold", ratio=3)
    overview.add_column("package", overflow="fold", ratio=2)
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
        fields.add_column("type", overflow="fold", ratio=2)
        fields.add_column("default", overflow="fold", ratio=2)
        fields.add_column("description", overflow="fold", ratio=5)
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
    from regopack.packing.core import write_json_atomic
    from regopack.registry.manager import default_registry
    from regopack.scenes.schema import dumps, json_schema

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
    out = _Console(file=sys.stdout)
    err = _Console(file=sys.stderr)
    try:
        with _signals_raise(), _warnings_as_lines():
            return handler(args, out, err)
    except BrokenPipeError:  # the reader went away, e.g. `regopack plugins | head -1`
        _discard_stdout()
        return EXIT_OK
    except (RegopackError, ValidationError, tomllib.TOMLDecodeError, FileNotFoundError) as exc:
        print(f"regopack: error: {_one_line(exc)}", file=sys.stderr)
        return EXIT_USAGE
    except Terminated:
        print("regopack: terminated; no partial files were written", file=sys.stderr)
        return EXIT_TERMINATED
    except KeyboardInterrupt:
        print("regopack: interrupted; no partial files were written", file=sys.stderr)
        return EXIT_INTERRUPTED


class _Console(Console):
    """A rich console that lets a closed pipe raise :class:`BrokenPipeError`.

    rich's own handling exits with status 1; :func:`main` ends quietly with 0.
    """

    def on_broken_pipe(self) -> None:
        """Raise :class:`BrokenPipeError` (handled by :func:`main`)."""
        raise BrokenPipeError


def _discard_stdout() -> None:
    """Point standard output at the null device, so that the final flush cannot fail."""
    try:
        fd = sys.stdout.fileno()
    except (AttributeError, OSError, ValueError):
        return
    devnull = os.open(os.devnull, os.O_WRONLY)
    os.dup2(devnull, fd)
    os.close(devnull)


@contextmanager
def _warnings_as_lines() -> Iterator[None]:
    """Within the block, regopack's own warnings print as one ``regopack: warning:`` line."""
    import warnings

    previous = warnings.showwarning

    def show(message: Any, category: Any, *args: Any, **kwargs: Any) -> None:
        own = isinstance(category, type) and category.__module__.split(".")[0] == "regopack"
        if own:
            print(f"regopack: warning: {' '.join(str(message).split())}", file=sys.stderr)
        else:
            previous(message, category, *args, **kwargs)

    warnings.showwarning = show
    try:
        yield
    finally:
        warnings.showwarning = previous


@contextmanager
def _signals_raise() -> Iterator[None]:
    """Within the block, SIGTERM raises :class:`Terminated` and SIGINT ``KeyboardInterrupt``.

    Both are deferred while an output folder is being swapped in (see
    :func:`regopack.base.outdir.raise_or_defer`). A signal that is ignored (e.g.
    SIGINT in a background job) stays ignored; a second SIGTERM is ignored
    while the first one is being handled.
    """
    from regopack.base.outdir import raise_or_defer

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
