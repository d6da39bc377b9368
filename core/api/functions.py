"""The Python API: one function for each command of ``regopack``.

=============================  ==========================  =====================================
function                       command                     returns
=============================  ==========================  =====================================
:func:`scene`                  ``regopack config``         a validated scene
:func:`pack`                   ``regopack run``            the :class:`~regopack.Packing`
:func:`pack_and_summarise`     ``regopack run``            packing, summary and files written
:func:`analyze`                ``regopack analyze``        analysis results by analyzer
:func:`verify`                 ``regopack verify``         a bool-like report
:func:`export`                 ``regopack export``         the file written
:func:`sweep`                  ``regopack sweep``          the results table
=============================  ==========================  =====================================

The command line calls these functions, so the two cannot drift apart. Every
function is importable from the package root (``regopack.pack``). ``pack`` and
``analyze`` write only into the ``out`` folder they are given; ``export``
writes beside the packing file when no path is given, and ``sweep`` into
``runs/<experiment name>`` by default, as the commands do. User mistakes raise
:class:`~regopack.base.errors.RegopackError` subclasses with one-line messages that
name the argument at fault.
"""

from __future__ import annotations

import os
from collections.abc import Callable, Iterator, Mapping, Sequence
from contextlib import contextmanager
from pathlib import Path
from typing import TYPE_CHECKING, Any

from regopack.analysis.results import AnalysisResults
from regopack.base.errors import ConfigError
from regopack.packing.core import Packing, load
from regopack.registry.interfaces import ProgressCallback
from regopack.scenes.model import dotted_name, make_scene, plain_value, registry_or_default

if TYPE_CHECKING:
    from regopack.analysis.pipeline import TableFormat
    from regopack.experiments.api import SweepTable
    from regopack.registry.manager import Registry
    from regopack.run.pipeline import RunOutcome
    from regopack.scenes.model import ResolvedScene
    from regopack.verification.polygons import VerifyReport
    from regopack.verification.polyhedra import Report3D

__all__ = [
    "analyze",
    "export",
    "pack",
    "pack_and_summarise",
    "scene",
    "settled",
    "sweep",
    "verify",
]

Progress = bool | ProgressCallback


def _out_path(value: Any, what: str) -> Path:
    """Return an output path given by the caller: a str or path-like, never blank."""
    if not isinstance(value, str | os.PathLike):
        raise ConfigError(
            f"{what}: expected a path (str or os.PathLike), not {type(value).__name__}"
        )
    text = os.fspath(value)
    if not isinstance(text, str) or not text.strip():
        raise ConfigError(f"{what}: {text!r} is an empty path; give a folder or file name")
    return Path(text)


def _flag(value: Any, what: str, allow_none: bool = False) -> None:
    if isinstance(value, bool) or (allow_none and value is None):
        return
    allowed = "True, False or None" if allow_none else "True or False"
    raise ConfigError(f"{what}: expected {allowed}, not {value!r}")


def scene(
    source: str | os.PathLike[str] | Mapping[str, Any] | ResolvedScene | None = None,
    /,
    *,
    seed: int | None = None,
    registry: Registry | None = None,
    **overrides: Any,
) -> ResolvedScene:
    """Read, change and validate a scene, as ``regopack config`` does.

    Parameters
    ----------
    source
        ``None`` for the default scene (``table1``), the name of a built-in
        scene (``regopack scenes`` lists them), the path of a TOML file, a
        dictionary with the file's content, or a scene to change.
    seed
        Replaces the scene's seed.
    registry
        Where plugins are looked up (default: the built-in and installed ones).
    **overrides
        Fields to change, by dotted name as for ``--set``: ``__`` stands for
        the dot (``domain__width=400``), or pass a dictionary
        (``**{"domain.width": 400}``). Values are Python values.

    Returns
    -------
    ResolvedScene
        The scene with every plugin's parameters validated and defaults
        filled in; ``.with_(...)`` changes it again, ``.to_toml()`` writes it.

    Raises
    ------
    ConfigError
        One line naming the file or keyword, the field, the value and what is
        allowed.

    Examples
    --------
    >>> import regopack
    >>> s = regopack.scene("small", domain__width=120, **{"density.eta": 5})
    >>> s.scene.domain.width, s.density.config.eta
    (120.0, 5.0)
    >>> s.with_(seed=4).seed
    4
    """
    return make_scene(source, seed=seed, registry=registry, overrides=overrides)


def _as_scene(
    source: str | os.PathLike[str] | Mapping[str, Any] | ResolvedScene | None,
    seed: int | None,
    overrides: Mapping[str, Any],
    registry: Registry | None = None,
) -> ResolvedScene:
    from regopack.scenes.model import ResolvedScene

    if isinstance(source, ResolvedScene) and seed is None and not overrides and registry is None:
        return source
    return scene(source, seed=seed, registry=registry, **overrides)


@contextmanager
def _progress(progress: Progress, label: str) -> Iterator[ProgressCallback | None]:
    """Yield a progress callback: a bar on stderr for ``True``, the callable itself, or none."""
    if progress is False or progress is None:
        yield None
        return
    if progress is not True:
        if not callable(progress):
            raise ConfigError(
                f"progress: expected True, False or a callable, not {type(progress).__name__}"
            )
        yield progress
        return
    import sys

    from rich.console import Console

    from regopack.run.progress import progress_bar

    console = Console(file=sys.stderr)
    if not kernels_cached():
        console.print(
            "[dim]compiling the packing kernels (first run after an install or upgrade; "
            "cached afterwards; `regopack compile` does it ahead of time)[/dim]"
        )
    with progress_bar(console, True, label) as callback:
        yield callback


def kernels_cached() -> bool:
    """Return whether the compiled-kernel cache holds compiled code (a first run compiles)."""
    from regopack.base.jit import kernel_cache_dir

    folder = Path(os.environ.get("NUMBA_CACHE_DIR") or kernel_cache_dir())
    return folder.is_dir() and any(folder.rglob("*.nbi"))


def pack_and_summarise(
    source: str | os.PathLike[str] | Mapping[str, Any] | ResolvedScene | None = None,
    /,
    *,
    seed: int | None = None,
    progress: Progress = False,
    out: str | os.PathLike[str] | None = None,
    verify: bool | None = None,
    figures: bool = True,
    registry: Registry | None = None,
    workers: int | None = None,
    threads_per_worker: int | None = None,
    client: Any = None,
    **overrides: Any,
) -> RunOutcome:
    """Pack a scene and summarise the run, as ``regopack run`` does.

    Takes the arguments of :func:`pack`, plus ``figures`` (draw the figures
    of the scene's analyses when ``out`` is given) and ``registry`` (where
    plugins are looked up).

    Returns
    -------
    RunOutcome
        The packing, the summary (what ``summary.json`` holds) and the files
        written.
    """
    from regopack.base.outdir import check_replaceable
    from regopack.run.pipeline import RUN_FOLDER, check_runnable, run_scene

    _flag(verify, "verify", allow_none=True)
    _flag(figures, "figures")
    resolved = _as_scene(source, seed, overrides, registry)
    folder = None if out is None else _out_path(out, "out")
    if folder is not None:
        if isinstance(source, str | os.PathLike) and Path(source).is_file():
            refuse_inside(Path(source), folder, "scene file")
        check_replaceable(folder, RUN_FOLDER)
    check_runnable(resolved)
    from regopack.tiling.executors import InProcess, executor_for
    from regopack.tiling.run import check_tiled, packer_for

    tiled = resolved.scene.tiles is not None
    if tiled:
        check_tiled(resolved)
    with (
        executor_for(tiled, workers, threads_per_worker, client) as executor,
        _progress(progress, f"packing {resolved.name}") as callback,
    ):
        packer = packer_for(executor if executor is not None else InProcess()) if tiled else None
        return run_scene(
            resolved,
            folder,
            progress=callback,
            verify=verify,
            figures=figures,
            tiled=packer,
        )


def pack(
    source: str | os.PathLike[str] | Mapping[str, Any] | ResolvedScene | None = None,
    /,
    *,
    seed: int | None = None,
    progress: Progress = False,
    out: str | os.PathLike[str] | None = None,
    verify: bool | None = None,
    workers: int | None = None,
    threads_per_worker: int | None = None,
    client: Any = None,
    **overrides: Any,
) -> Packing:
    """Pack a scene, as ``regopack run`` does (a 3D packing for a 3D scene).

    Parameters
    ----------
    source
        A scene (see :func:`scene`): ``None`` for ``table1``, a built-in name,
        a TOML path, a dictionary or a scene object.
    seed
        Replaces the scene's seed.
    progress
        ``True`` shows a progress bar on stderr; a callable is called as
        ``progress(done, placed, total)``.
    out
        Run folder to write (packing, ``summary.json``, the scene's analyses
        and exports), replaced as a whole as by ``regopack run --out``.
        ``None`` writes nothing.
    verify
        Check the packing for overlaps (``None``: when the insertion
        settings may overlap); the outcome is in ``summary.json``.
    workers
        Local worker processes that pack a tiled scene's tiles (``tiles``
        in the scene); ``None`` or 1: this process. The packing is the same.
    threads_per_worker
        Compiled-kernel threads of each local worker (default: its share
        of the cores).
    client
        A ``distributed.Client`` (or a scheduler's address) whose cluster
        packs a tiled scene's tiles.
    **overrides
        Scene fields to change, as for :func:`scene` (``density__eta=5``).

    Returns
    -------
    Packing
        Every drawn particle and where it was placed; the same scene and seed
        give the same packing, bit for bit.

    Examples
    --------
    >>> import regopack
    >>> p = regopack.pack("small", domain__width=60, domain__height=60, count=40)
    >>> p.n_particles, p.n_placed > 30
    (40, True)
    """
    outcome = pack_and_summarise(
        source,
        seed=seed,
        progress=progress,
        out=out,
        verify=verify,
        workers=workers,
        threads_per_worker=threads_per_worker,
        client=client,
        **overrides,
    )
    return outcome.packing


def refuse_inside(path: Path, folder: Path, what: str) -> None:
    """Refuse an output folder that holds ``path``: replacing it would delete the input."""
    real, real_folder = os.path.realpath(path), os.path.realpath(folder)
    if os.path.commonpath([real, real_folder]) == real_folder:
        raise ConfigError(
            f"output folder {folder}: holds the {what} {path}, and the output folder is "
            "replaced as a whole; give another folder"
        )


def _packing(packing: Packing | str | os.PathLike[str]) -> Packing:
    """Return the packing given, or the one its file holds (2D or 3D)."""
    if isinstance(packing, Packing):
        return packing
    if isinstance(packing, str | os.PathLike):
        return load(Path(packing))
    raise ConfigError(
        f"packing: expected a Packing or the path of a packing file, not {type(packing).__name__}"
    )


def analysis_params(
    params: Mapping[str, Any], known: Callable[[str], bool] | None = None
) -> dict[str, dict[str, Any]]:
    """Parameters by analyzer from keywords: ``contacts={"tol": 0.1}`` or ``contacts__tol=0.1``.

    Examples
    --------
    >>> analysis_params({"contacts__tol": 0.1, "rdf": {"dr": 0.5}})
    {'contacts': {'tol': 0.1}, 'rdf': {'dr': 0.5}}
    """
    out: dict[str, dict[str, Any]] = {}
    for name, value in params.items():
        key = dotted_name(name)
        analyzer, dot, field = key.partition(".")
        if dot:
            if not field or "." in field:
                raise ConfigError(f"{name}: expected ANALYZER__FIELD=value, e.g. contacts__tol=0.1")
            out.setdefault(analyzer, {})[field] = value
        elif isinstance(value, Mapping):
            out.setdefault(analyzer, {}).update({str(k): v for k, v in value.items()})
        else:
            raise ConfigError(
                f"{name}={value!r}: expected a dictionary of {name}'s parameters, "
                f"e.g. {name}={{...}}, or {name}__FIELD=value"
            )
    return out


def analyze(
    packing: Packing | str | os.PathLike[str],
    only: str | Sequence[str] | None = None,
    *,
    out: str | os.PathLike[str] | None = None,
    figures: bool = True,
    tables: TableFormat = "csv",
    registry: Registry | None = None,
    params: Mapping[str, Any] | None = None,
    params_source: str | None = None,
    **kwargs: Any,
) -> AnalysisResults:
    """Analyse a packing, as ``regopack analyze`` does.

    Parameters
    ----------
    packing
        A 2D or 3D packing or the path of a packing file.
    only
        Analyzer names (a name, a comma-separated string or a sequence); by
        default those ``regopack analyze`` runs on a packing of that
        dimension (see :func:`regopack.analysis.pipeline.default_analyses`). Analyzers
        they require run too; an analyzer of another dimension is refused.
    out
        Folder for ``analysis.json``, the tables, figures and report,
        replaced as a whole. ``None`` writes nothing.
    figures, tables
        With ``out``: draw the figures; write the tables as ``"csv"`` or ``"npz"``.
    registry
        Where analyzers are looked up (default: built-in and installed).
    params, **kwargs
        Parameters by analyzer: ``contacts={"tol": 0.1}`` or ``contacts__tol=0.1``
        (keywords win over ``params``). Parameters for an analyzer that does
        not run are refused.
    params_source
        Where ``params`` come from (``regopack analyze`` gives ``--set``); it
        starts the message that refuses a parameter.

    Returns
    -------
    AnalysisResults
        A mapping from analyzer name to its result: ``res["density"]["phi_domain"]``,
        ``res["rdf"].tables["rdf_near"]["total"]``, ``res["contacts"].to_pandas()``.
        ``res.files`` holds the files written, or ``None``.

    Examples
    --------
    >>> import regopack
    >>> p = regopack.pack("small", domain__width=60, domain__height=60, count=40)
    >>> res = regopack.analyze(p, "density", density__margin=0.0)
    >>> list(res), round(res["density"]["phi_domain"], 6) == round(p.phi, 6)
    (['density'], True)
    """
    from regopack.analysis.pipeline import ANALYSIS_KIND, write_analysis
    from regopack.base.outdir import check_replaceable
    from regopack.scenes.analysis_plan import default_analyses, run_analyses

    _flag(figures, "figures")
    if tables not in ("csv", "npz"):
        raise ConfigError(f'tables = {tables!r}: expected "csv" or "npz"')
    loaded = _packing(packing)
    folder = None if out is None else _out_path(out, "out")
    if folder is not None:
        if not isinstance(packing, Packing):
            refuse_inside(Path(packing), folder, "packing file")
        check_replaceable(folder, ANALYSIS_KIND)
    if only is None:
        names = list(default_analyses(loaded))
    else:
        if not isinstance(only, str | Sequence):
            raise ConfigError(
                f"only: expected an analyzer name or a list of names, not {type(only).__name__}"
            )
        parts = [only] if isinstance(only, str) else list(only)
        if not parts:
            raise ConfigError("only: no analyzer named; leave it out (None) for the defaults")
        names = []
        for part in parts:
            if not isinstance(part, str):
                raise ConfigError(f"only: expected analyzer names, not {type(part).__name__}")
            for name in (p.strip() for p in part.split(",")):
                if not name:
                    raise ConfigError(f"only: empty analyzer name in {part!r}")
                if name not in names:
                    names.append(name)
    reg = registry_or_default(registry)
    if params is not None and not isinstance(params, Mapping):
        raise ConfigError(
            f"params: expected a dictionary of parameters by analyzer, not {type(params).__name__}"
        )
    merged = analysis_params(params or {})
    for name, fields in analysis_params(kwargs).items():
        merged.setdefault(name, {}).update(fields)
    source = None if isinstance(packing, Packing) else str(packing)
    analyzers = run_analyses(
        loaded,
        reg,
        [(n, {}) for n in names],
        params=merged,
        source=source,
        params_source=params_source,
        warn=only is not None,
    )
    results = AnalysisResults(analyzers)
    if folder is not None:
        packing_path = None if isinstance(packing, Packing) else Path(packing)
        results.files = write_analysis(
            folder,
            loaded,
            analyzers,
            figures=figures,
            packing_path=packing_path,
            table_format=tables,
            registry=reg,
        )
    return results


def verify(
    packing: Packing | str | os.PathLike[str], rel_tol: float = 1e-9
) -> VerifyReport | Report3D:
    """Check a packing for overlaps and particles outside the domain, as ``regopack verify``.

    The check is independent of the insertion code: shapely polygons in 2D,
    :func:`regopack.verification.polyhedra.verify_polyhedra` in 3D (which reports the
    worst overlap as a fraction of the smaller volume).

    Returns
    -------
    VerifyReport
        True in a boolean context when nothing is violated; ``worst_overlap``
        and ``worst_outside`` name the worst case.

    Examples
    --------
    >>> import regopack
    >>> report = regopack.verify(regopack.pack("small", count=30))
    >>> bool(report), report.worst_overlap
    (True, None)
    """
    from regopack.verification.summary import verify_packing

    if isinstance(rel_tol, bool) or not isinstance(rel_tol, int | float) or not rel_tol >= 0:
        raise ConfigError(f"rel_tol = {rel_tol!r}: expected a number >= 0")
    return verify_packing(_packing(packing), rel_tol=float(rel_tol))


def export(
    packing: Packing | str | os.PathLike[str],
    to: str,
    path: str | os.PathLike[str] | None = None,
    *,
    analyses: AnalysisResults | Sequence[str] | None = None,
    registry: Registry | None = None,
    params: Mapping[str, Any] | None = None,
    params_source: str | None = None,
    force: bool = False,
    **kwargs: Any,
) -> Path:
    """Write a packing in another format, as ``regopack export`` does.

    Parameters
    ----------
    packing
        A packing (2D or 3D) or the path of a packing file.
    to
        The exporter (``regopack plugins`` lists them: ``lammps``, ``vtk`` and
        ``gsd`` for packings of both dimensions; ``image``, ``csv``, ... for 2D
        packings; ``stl`` and ``slice`` for 3D ones).
    path
        The main file to write, or a folder. Required for a packing object;
        for a packing file it defaults to the file's name with the exporter's
        suffix for the packing's dimension (``vtk``: ``.vtp`` or ``.vtu``), beside it.
    analyses
        Results of :func:`analyze`, or analyzer names to compute, whose
        per-particle results the exporter adds (e.g. Z in the VTK file).
    params, **kwargs
        The exporter's parameters (``stiffness=1e5``); keywords win over ``params``.
    params_source
        What error messages call the parameters (the command line passes
        ``"--set"``); by default the message starts with the exporter.
    force
        Overwrite companion files that exist beside a main file that does
        not (by default such a file is taken for the user's own and refused,
        see :func:`~regopack.exports.pipeline.export_packing`).

    Returns
    -------
    pathlib.Path
        The main file written; companions (e.g. LAMMPS' input script) sit beside it.
    """
    from regopack.exports.pipeline import (
        build_exporter,
        check_exporter_dimension,
        export_packing,
        output_path,
    )
    from regopack.scenes.analysis_plan import run_analyses

    reg = registry_or_default(registry)
    if not isinstance(to, str):
        raise ConfigError(f"to: expected the name of an exporter, not {type(to).__name__}")
    if params is not None and not isinstance(params, Mapping):
        raise ConfigError(
            f"params: expected a dictionary of {to}'s parameters, not {type(params).__name__}"
        )
    _flag(force, "force")
    merged = {**(params or {}), **{k: plain_value(v) for k, v in kwargs.items()}}
    exporter = build_exporter(reg, to, merged, source=params_source)
    loaded = _packing(packing)
    file = None if isinstance(packing, Packing) else Path(packing)
    check_exporter_dimension(reg, to, loaded.dimension, "packing" if file is None else str(file))
    if path is None:
        if file is None:
            raise ConfigError("export: give the path to write (the packing has no file)")
        target = output_path(exporter, file, dimension=loaded.dimension)
    else:
        source = Path("packing.npz") if file is None else file
        target = output_path(exporter, source, _out_path(path, "path"), dimension=loaded.dimension)
    if file is not None and os.path.realpath(target) == os.path.realpath(file):
        raise ConfigError(f"path {target}: is the packing file itself; give another file")
    if loaded.dimension == 3:
        if analyses:
            raise ConfigError(
                "analyses: the 3D exporters carry no analysis results; leave them out"
            )
        computed = None
    elif isinstance(analyses, AnalysisResults):
        computed = analyses.analyzers
    elif analyses is None:
        computed = None
    elif isinstance(analyses, str | Sequence):
        parts = [analyses] if isinstance(analyses, str) else list(analyses)
        if not all(isinstance(p, str) for p in parts):
            raise ConfigError("analyses: expected analyzer names or the results of analyze()")
        names = [n.strip() for p in parts for n in p.split(",") if n.strip()]
        computed = run_analyses(loaded, reg, [(n, {}) for n in names]) if names else None
    else:
        raise ConfigError(
            "analyses: expected analyzer names or the results of analyze(), "
            f"not {type(analyses).__name__}"
        )
    try:
        return export_packing(
            loaded, to, target, registry=reg, params=merged, analyses=computed, force=force
        )
    except ConfigError as err:  # a parameter that does not fit this packing
        named = {to, reg.canonical("export", to)}
        if params_source and any(str(err).startswith(f"exporter {n!r}: ") for n in named):
            raise ConfigError(f"{params_source}: {err}") from err
        raise


def settled(
    packing: Packing | str | os.PathLike[str],
    state: str | os.PathLike[str],
    exporter: str,
    *,
    registry: Registry | None = None,
    params: Mapping[str, Any] | None = None,
    params_source: str | None = None,
) -> Packing:
    """Read the final state of a DEM run back into a packing, as ``regopack settled`` does.

    Parameters
    ----------
    packing
        The packing that was exported (or its file).
    state
        The final state the exported files made the program write:
        ``<stem>.final.txt`` of a ``yade`` script, ``<stem>.final.dump`` of a
        ``liggghts`` script.
    exporter
        The exporter that wrote the files (``yade``, ``liggghts``).
    params
        The exporter's parameters of the export (only those that set lengths
        matter: ``length_scale``, ``units``).
    params_source
        What error messages call the parameters (the command line: ``"--set"``).

    Returns
    -------
    Packing
        The same particles, moved and turned as the run left them; every
        analysis takes it (``analyze(settled(...), [...])``) to compare the
        sample before and after.

    Raises
    ------
    ConfigError
        One line, when the exporter reads no state back or a parameter is wrong.
    PackingFileError
        One line naming ``state``, when it is not a state of this packing.
    """
    from regopack.exports.pipeline import build_exporter

    reg = registry_or_default(registry)
    if not isinstance(exporter, str):
        raise ConfigError(f"exporter: expected an exporter's name, not {type(exporter).__name__}")
    loaded = _packing(packing)
    built = build_exporter(reg, exporter, dict(params or {}), source=params_source)
    try:
        moved: Packing = built.read_state(loaded, Path(state))
    except NotImplementedError:
        readers = [name for name in reg.names("export") if _reads_state(reg, name)]
        raise ConfigError(
            f"exporter {exporter!r} reads no state back; these do: {', '.join(readers)}"
        ) from None
    return moved


def _reads_state(reg: Registry, name: str) -> bool:
    """Say whether the exporter ``name`` overrides :meth:`Exporter.read_state`."""
    from regopack.registry.interfaces import Exporter

    factory = reg.get("export", name).factory
    method = getattr(factory, "read_state", None)
    return method is not None and method is not Exporter.read_state


def sweep(
    experiment: str | os.PathLike[str],
    *,
    out: str | os.PathLike[str] | None = None,
    workers: int | None = None,
    scheduler: str | None = None,
    progress: bool = False,
    plots: bool = True,
) -> SweepTable:
    """Run every run of an experiment file, as ``regopack sweep`` does.

    Parameters
    ----------
    experiment
        The experiment file (TOML), or the name of a built-in experiment.
    out
        Its folder (default ``runs/<experiment name>``); finished runs found
        there are reused.
    workers
        Local worker processes (default: one per core; ``1`` runs in this process).
    scheduler
        Address of a Dask scheduler instead of local workers.
    progress
        Show a progress bar on stderr.
    plots
        Draw the plots the results allow into ``<out>/plots``.

    Returns
    -------
    SweepTable
        One row per run (its parameters and metrics), with ``.columns``,
        ``.column(name)`` as a NumPy array and ``.to_pandas()``.
    """
    from regopack.experiments.api import run_sweep

    if not isinstance(experiment, str | os.PathLike):
        raise ConfigError(
            f"experiment: expected a file or a built-in experiment's name, "
            f"not {type(experiment).__name__}"
        )
    if workers is not None and (isinstance(workers, bool) or not isinstance(workers, int)):
        raise ConfigError(f"workers = {workers!r}: expected a whole number >= 1")
    if scheduler is not None and not isinstance(scheduler, str):
        raise ConfigError(f"scheduler = {scheduler!r}: expected an address, e.g. tcp://host:8786")
    _flag(progress, "progress")
    _flag(plots, "plots")
    if out is not None:
        out = _out_path(out, "out")
    return run_sweep(
        experiment,
        out=out,
        workers=workers,
        scheduler=scheduler,
        progress=progress,
        plots=plots,
    )
