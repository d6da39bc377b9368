"""Experiments: sweeps of scene parameters described by a TOML file.

An experiment file names a base scene and the scene fields to vary::

    name = "eta-vs-seed"
    base = "small"                       # built-in scene or path of a scene file
    metrics = ["placed", "phi_interior"]  # optional; see DEFAULT_METRICS
    max_runs = 10000                     # optional; a larger grid is refused (MAX_RUNS)

    [set]                                # applied to every run
    count = 150

    [sweep]                              # every combination is run
    "density.eta" = [0, 5, 10]
    seed = "1..3"                        # integer range, both ends included

    [[zip]]                              # these vary together
    "domain.width" = [200, 400]
    "domain.height" = [200, 400]

:func:`load_experiment` reads and checks the file, :func:`expand` lists the
runs of the grid, :func:`check_runs` validates every run's scene, and
:func:`run_experiment` runs them (in worker processes, in-process, or on a Dask
cluster) and collects their summaries into ``results.csv``.
"""

from __future__ import annotations

import csv
import hashlib
import io
import itertools
import json
import math
import os
import re
import signal
import threading
import time
import uuid
from collections.abc import Callable, Iterator, Mapping, Sequence
from concurrent.futures import FIRST_COMPLETED, Future, ProcessPoolExecutor, wait
from concurrent.futures.process import BrokenProcessPool
from dataclasses import dataclass, field
from pathlib import Path
from typing import Annotated, Any, Literal

import numpy as np
from pydantic import (
    BaseModel,
    BeforeValidator,
    ConfigDict,
    Field,
    PrivateAttr,
    ValidationError,
    field_validator,
    model_validator,
)

from regopack import _toml
from regopack.errors import ConfigError, RegopackError
from regopack.manager import Registry, default_registry
from regopack.outdir import check_replaceable, name_key, remove_leftovers, replace_folder
from regopack.packing import Packing, _atomic_file, write_json_atomic
from regopack.run import RUN_FOLDER, run_scene
from regopack.scene_model import (
    ResolvedScene,
    builtin_scenes,
    load_scene,
    output_files,
    resolve_scene,
)
from regopack.verification import verify
from regopack.voids import void_metrics

__all__ = [
    "DEFAULT_METRICS",
    "Experiment",
    "ExperimentProgress",
    "ExperimentResult",
    "RunResult",
    "RunSpec",
    "check_runs",
    "default_experiment_dir",
    "expand",
    "experiment_from_dict",
    "load_experiment",
    "run_experiment",
    "verify_metrics",
]

DEFAULT_METRICS: tuple[str, ...] = (
    "tried",
    "placed",
    "phi_domain",
    "phi_interior",
    "wall_time_s",
    "insert_time_s",
    "candidate_analyses",
)
"""Summary keys collected when an experiment lists no ``metrics``.

The scalar results of the analyses a scene lists are added as
``analyses.<name>.<key>``.
"""

RESULTS_CSV = "results.csv"
"""Name of the table of results in the experiment's output directory."""

EXPERIMENT_JSON = "experiment.json"
"""Name of the file describing the resolved grid in the output directory."""

ERROR_TXT = "error.txt"
"""Name of the file a failed run leaves in its folder."""

SCENE_JSON = "scene.json"
"""Name of the file holding a run's resolved scene, in its folder.

A finished run is reused only when this file matches the run's current scene.
"""

MAX_RUNS = 10_000
"""Default of an experiment's ``max_runs``: the largest number of runs a sweep may expand to.

A grid with more runs is refused before it is expanded (a typo such as
``seed = "1..1000000"`` would otherwise list and validate a million scenes);
set ``max_runs`` in the experiment file to allow more.
"""

_RANGE = re.compile(r"^\s*(-?\d+)\s*\.\.\s*(-?\d+)\s*(?:\.\.\s*(\d+)\s*)?$")
_UNSAFE = re.compile(r"[^A-Za-z0-9._=,+-]+")
_MAX_ID = 120


# ---------------------------------------------------------------------------
# the experiment file


def _values(value: Any) -> Any:
    """Turn an integer range ``"a..b"`` (or ``"a..b..step"``) into a list."""
    if isinstance(value, str):
        match = _RANGE.match(value)
        if match is None:
            raise ValueError(
                f"expected a list of values or an integer range like '1..9', not {value!r}"
            )
        start, stop = int(match.group(1)), int(match.group(2))
        step = int(match.group(3) or 1)
        if step < 1:
            raise ValueError(f"range {value!r}: the step must be at least 1")
        if stop < start:
            raise ValueError(f"range {value!r} is empty: its end is below its start")
        return list(range(start, stop + 1, step))
    if not isinstance(value, list):
        raise ValueError(
            f"expected a list of values or an integer range like '1..9', not {value!r}"
        )
    return value


SweepValues = Annotated[list[Any], BeforeValidator(_values), Field(min_length=1)]


def _flatten(table: Mapping[str, Any], prefix: str = "") -> dict[str, Any]:
    """``{"density": {"eta": x}}`` to ``{"density.eta": x}`` (lists are kept whole)."""
    out: dict[str, Any] = {}
    for key, value in table.items():
        dotted = f"{prefix}{key}"
        if isinstance(value, Mapping):
            out.update(_flatten(value, dotted + "."))
        else:
            out[dotted] = value
    return out


def _check_key(key: str) -> str:
    parts = key.split(".")
    if any(not p.strip() or p != p.strip() for p in parts):
        raise ValueError(f"{key!r} is not a dotted scene field like 'density.eta'")
    return key


class Experiment(BaseModel):
    """A sweep over scene fields: a base scene, the values to vary, what to collect.

    Examples
    --------
    >>> exp = Experiment.model_validate(
    ...     {"base": "small", "sweep": {"density.eta": [0, 10], "seed": "1..2"}}
    ... )
    >>> [run.run_id for run in expand(exp)]
    ['eta=0,seed=1', 'eta=0,seed=2', 'eta=10,seed=1', 'eta=10,seed=2']
    """

    model_config = ConfigDict(extra="forbid", populate_by_name=True, strict=True)

    name: str | None = Field(
        None,
        min_length=1,
        description="Name of the experiment (default: the file name without '.toml').",
    )
    base: str = Field(
        min_length=1,
        description=(
            "Scene every run starts from: a built-in scene name or the path of a scene "
            "file, relative to the experiment file."
        ),
    )
    sweep: dict[str, SweepValues] = Field(
        default_factory=dict,
        description=(
            'Dotted scene fields mapped to the values to try, e.g. "density.eta" = [0, 5]; '
            "an integer range '1..9' (ends included) may replace the list. Every "
            "combination is run."
        ),
    )
    zip_groups: list[dict[str, SweepValues]] = Field(
        default_factory=list,
        alias="zip",
        description=(
            "Groups of dotted fields whose values vary together (the i-th values of "
            "every field of a group form one point); all lists of a group have the "
            "same length."
        ),
    )
    metrics: list[Annotated[str, Field(min_length=1)]] | None = Field(
        None,
        description=(
            "Summary keys collected into results.csv, dotted for nested values "
            "(e.g. 'analyses.coordination.z_interior'); default: tried, placed, "
            "phi_domain, phi_interior, wall_time_s, insert_time_s, candidate_analyses and "
            "the scalar results of the scene's analyses."
        ),
    )
    set_: dict[str, Any] = Field(
        default_factory=dict,
        alias="set",
        description="Dotted scene fields set to the same value in every run, e.g. count = 150.",
    )
    figures: bool = Field(
        False, description="Draw the analysis figures of every run (slow for large sweeps)."
    )
    verify: bool = Field(
        False,
        description=(
            "Check every packing (regopack.verification) and add verify.overlap_pairs, "
            "verify.worst_overlap, verify.outside, verify.any_nan and verify.ok to its metrics."
        ),
    )
    max_runs: int = Field(
        MAX_RUNS,
        ge=1,
        description=(
            f"Largest number of runs the grid may expand to (default {MAX_RUNS:,}); a larger "
            "grid is refused before it is expanded."
        ),
    )
    voids: bool = Field(
        False,
        description=(
            "Rasterise the free space of every packing's interior window and add "
            "voids.void_spans (the largest void cluster touches two opposite sides) and "
            "voids.largest_void_fraction to its metrics (see regopack.voids)."
        ),
    )

    _source: str | None = PrivateAttr(default=None)
    _directory: Path | None = PrivateAttr(default=None)

    @model_validator(mode="before")
    @classmethod
    def _flatten_tables(cls, data: Any) -> Any:
        """Accept nested tables (``[sweep.density]``) as dotted keys; refuse too many runs."""
        data = _flatten_input(data)
        _check_grid_size(data)
        return data

    @field_validator("sweep", "set_")
    @classmethod
    def _check_keys(cls, table: dict[str, Any]) -> dict[str, Any]:
        for key in table:
            _check_key(key)
        return table

    @field_validator("zip_groups")
    @classmethod
    def _check_group_keys(cls, groups: list[dict[str, Any]]) -> list[dict[str, Any]]:
        for group in groups:
            for key in group:
                _check_key(key)
        return groups

    @property
    def source(self) -> str | None:
        """File the experiment was read from (for messages), if any."""
        return self._source

    @property
    def label(self) -> str:
        """Name used in messages: the file, or ``experiment``."""
        return self._source or "experiment"

    @property
    def base_ref(self) -> str | Path:
        """The base scene as :func:`regopack.scene_model.load_scene` takes it."""
        if not self.base.endswith(".toml") and self.base in builtin_scenes():
            return self.base
        path = Path(self.base)
        if not path.is_absolute() and self._directory is not None:
            path = self._directory / path
        return path

    @property
    def experiment_name(self) -> str:
        """The experiment's name, or the stem of its file."""
        if self.name:
            return self.name
        return Path(self._source).stem if self._source else "experiment"


def _flatten_input(data: Any) -> Any:
    """Flatten the TOML tables ``sweep``, ``set`` and ``zip`` before validation."""
    if not isinstance(data, dict):
        return data
    out = dict(data)
    for key in ("sweep", "set"):
        if isinstance(out.get(key), Mapping):
            out[key] = _flatten(out[key])
    groups = out.get("zip")
    if isinstance(groups, list):
        out["zip"] = [_flatten(g) if isinstance(g, Mapping) else g for g in groups]
    return out


def _axis_length(values: Any) -> int | None:
    """Count the values of a sweep axis (a list or an integer range) without listing them."""
    if isinstance(values, list):
        return len(values)
    match = _RANGE.match(values) if isinstance(values, str) else None
    if match is None:
        return None
    start, stop, step = int(match.group(1)), int(match.group(2)), int(match.group(3) or 1)
    return max(0, (stop - start) // step + 1) if step >= 1 else None


def _check_grid_size(data: Any) -> None:
    """Refuse a grid of more than ``max_runs`` runs before any range is listed."""
    if not isinstance(data, dict):
        return
    limit = data.get("max_runs", MAX_RUNS)
    if not isinstance(limit, int) or isinstance(limit, bool) or limit < 1:
        return  # the field's own validation reports it
    axes: list[tuple[str, int]] = []
    sweep = data.get("sweep")
    if isinstance(sweep, Mapping):
        axes += [(f"sweep.{k}", n) for k, v in sweep.items() if (n := _axis_length(v))]
    groups = data.get("zip")
    if isinstance(groups, list):
        for i, group in enumerate(groups):
            if isinstance(group, Mapping) and group:
                n = _axis_length(next(iter(group.values())))
                if n:
                    axes.append((f"zip.{i}", n))
    total = math.prod(n for _, n in axes)
    if total > limit:
        shown = ", ".join(f"{where} has {n:,}" for where, n in axes if n > 1)
        raise ValueError(
            f"the sweep expands to {total:,} runs ({shown}), more than max_runs = {limit:,}; "
            "set max_runs in the experiment file to allow more"
        )


_NO_VALUE = frozenset({"value_error", "extra_forbidden", "missing"})
"""Error types whose message says enough without the offending value."""


def _describe(err: ValidationError, source: str) -> str:
    errors = err.errors(include_url=False)
    first = errors[0]
    loc = ".".join(str(p) for p in first["loc"])
    msg = first["msg"].removeprefix("Value error, ")
    value = first.get("input")
    if loc and first["type"] not in _NO_VALUE and isinstance(value, bool | int | float | str):
        loc = f"{loc} = {_toml._value(value)}"
    text = f"{source}: {loc}: {msg}" if loc else f"{source}: {msg}"
    if len(errors) > 1:
        more = len(errors) - 1
        text += f" (and {more} more error{'s' if more > 1 else ''})"
    return " ".join(text.split())


def experiment_from_dict(data: Mapping[str, Any], *, source: str | None = None) -> Experiment:
    """Validate a raw experiment dictionary, with one-line errors.

    Parameters
    ----------
    data
        The experiment as read from TOML.
    source
        File name used in messages and to find a base scene given as a relative path.
    """
    label = source or "experiment"
    try:
        experiment = Experiment.model_validate(dict(data))
    except ValidationError as err:
        raise ConfigError(_describe(err, label)) from err
    experiment._source = source
    experiment._directory = Path(source).parent if source else None
    _check_axes(experiment)
    return experiment


def load_experiment(path: str | Path) -> Experiment:
    """Read and check an experiment file.

    Raises
    ------
    ConfigError
        One line naming the file and the offending key.
    """
    path = Path(path)
    source = str(path)
    data = _toml.parse_toml(_toml.read_text_file(path, "experiment"), source)
    return experiment_from_dict(data, source=source)


def _check_axes(experiment: Experiment) -> None:
    """Every field varies in one place only; the lists of a zip group match."""
    label = experiment.label
    owner: dict[str, str] = {}

    def claim(key: str, where: str) -> None:
        for other, other_where in owner.items():
            if key == other or key.startswith(other + ".") or other.startswith(key + "."):
                raise ConfigError(
                    f"{label}: {where}.{key}: also set in {other_where} ({other}); "
                    "a field can vary or be set in one place only"
                )
        owner[key] = where

    for key in experiment.set_:
        claim(key, "set")
    for key in experiment.sweep:
        claim(key, "sweep")
    for i, group in enumerate(experiment.zip_groups):
        if not group:
            raise ConfigError(f"{label}: zip.{i}: the group names no field")
        lengths = {k: len(v) for k, v in group.items()}
        if len(set(lengths.values())) > 1:
            sizes = ", ".join(f"{k} has {n}" for k, n in lengths.items())
            raise ConfigError(
                f"{label}: zip.{i}: the lists of a zip group must have the same length ({sizes})"
            )
        for key in group:
            claim(key, f"zip.{i}")


# ---------------------------------------------------------------------------
# the grid


@dataclass(frozen=True)
class RunSpec:
    """One run of an experiment.

    Attributes
    ----------
    index
        Position in the grid (0-based).
    run_id
        Stable name of the run, safe as a folder name (e.g. ``eta=10,seed=3``).
    params
        The varied fields (dotted keys) and their values in this run.
    overrides
        ``key=value`` strings applied to the base scene (the experiment's ``set``,
        then the varied fields), as :func:`regopack.scene_model.load_scene` takes them.
    """

    index: int
    run_id: str
    params: dict[str, Any]
    overrides: tuple[str, ...]

    def to_dict(self) -> dict[str, Any]:
        """Return the run as plain data."""
        return {
            "index": self.index,
            "id": self.run_id,
            "params": dict(self.params),
            "overrides": list(self.overrides),
        }


def _override(key: str, value: Any) -> str:
    return f"{key}={_toml._value(value)}"


def _format_value(value: Any) -> str:
    if isinstance(value, bool):
        return "true" if value else "false"
    if isinstance(value, int | float):
        return repr(value)
    if isinstance(value, str):
        return value
    return _toml._value(value)


def _short_names(keys: Sequence[str]) -> dict[str, str]:
    """Last part of each dotted key, or the whole key where that part is shared."""
    last = [k.rsplit(".", 1)[-1] for k in keys]
    return {k: (s if last.count(s) == 1 else k) for k, s in zip(keys, last, strict=True)}


def _sanitise(text: str) -> str:
    safe = _UNSAFE.sub("_", text).strip("._") or "run"
    if len(safe) > _MAX_ID:
        digest = hashlib.sha1(text.encode("utf-8")).hexdigest()[:10]
        safe = f"{safe[: _MAX_ID - 11]}~{digest}"
    return safe


def expand(experiment: Experiment) -> list[RunSpec]:
    """List the runs of an experiment's grid, in a deterministic order.

    The axes are the ``sweep`` fields in file order, then the ``zip`` groups;
    the grid is their product with the last axis varying fastest. A run's id
    joins ``name=value`` for every varied field (the last part of the dotted
    key, or the whole key when two fields share it), with characters unsafe in
    file names replaced by ``_``. Without any varied field there is one run,
    ``base``.

    Raises
    ------
    ConfigError
        When two runs get the same id (a value repeated in a list).

    Examples
    --------
    >>> exp = Experiment.model_validate(
    ...     {"base": "small", "sweep": {"seed": [1, 2]},
    ...      "zip": [{"domain.width": [100, 200], "domain.height": [50, 100]}]}
    ... )
    >>> [run.run_id for run in expand(exp)]
    ['seed=1,width=100,height=50', 'seed=1,width=200,height=100', 'seed=2,width=100,height=50', 'seed=2,width=200,height=100']
    >>> expand(exp)[0].overrides
    ('seed=1', 'domain.width=100', 'domain.height=50')
    """  # noqa: E501
    _check_axes(experiment)
    axes: list[list[dict[str, Any]]] = [
        [{key: v} for v in values] for key, values in experiment.sweep.items()
    ]
    for group in experiment.zip_groups:
        keys = list(group)
        n = len(group[keys[0]])
        axes.append([{k: group[k][i] for k in keys} for i in range(n)])
    keys = [*experiment.sweep, *(k for g in experiment.zip_groups for k in g)]
    short = _short_names(keys)
    fixed = tuple(_override(k, v) for k, v in experiment.set_.items())
    runs: list[RunSpec] = []
    seen: dict[str, RunSpec] = {}
    for index, point in enumerate(itertools.product(*axes)):
        params: dict[str, Any] = {}
        for part in point:
            params.update(part)
        raw_id = ",".join(f"{short[k]}={_format_value(v)}" for k, v in params.items())
        run_id = _sanitise(raw_id) if params else "base"
        other = seen.get(name_key(run_id))
        if other is not None:
            if other.run_id == run_id:
                raise ConfigError(
                    f"{experiment.label}: runs {other.index} and {index} get the same id "
                    f"{run_id!r}; is a value repeated in a list?"
                )
            raise ConfigError(
                f"{experiment.label}: runs {other.index} ({other.run_id!r}) and {index} "
                f"({run_id!r}) would write the same folder on a case-insensitive file "
                "system; make the values differ by more than case"
            )
        overrides = fixed + tuple(_override(k, v) for k, v in params.items())
        run = RunSpec(index, run_id, params, overrides)
        seen[name_key(run_id)] = run
        runs.append(run)
    return runs


def _origin(experiment: Experiment, loc: str) -> str:
    """Where in the experiment file the scene field ``loc`` was set."""
    places: list[tuple[str, str]] = [(k, "set") for k in experiment.set_]
    places += [(k, "sweep") for k in experiment.sweep]
    places += [(k, f"zip.{i}") for i, g in enumerate(experiment.zip_groups) for k in g]
    for key, where in places:
        if loc == key or loc.startswith(key + ".") or key.startswith(loc + "."):
            return where
    return "set"


def _scene_error(experiment: Experiment, run: RunSpec, err: ConfigError) -> ConfigError:
    """Reword a scene error of one run so that it names the experiment file."""
    text = str(err)
    for prefix in ("--set: ", "--set "):
        if text.startswith(prefix):
            rest = text[len(prefix) :]
            loc = re.split(r"[\s:=]", rest, maxsplit=1)[0]
            where = _origin(experiment, loc)
            return ConfigError(f"{experiment.label}: {where}.{rest} (run {run.run_id})")
    return ConfigError(f"{experiment.label}: base scene: {text}")


def _analysis_names(resolved: ResolvedScene) -> set[str]:
    return {a.kind for a in resolved.analyses}


def _check_sweep_files(experiment: Experiment, run: RunSpec, resolved: ResolvedScene) -> None:
    """Refuse a run output that is one of the files the sweep keeps in the run folder."""
    reserved = {name_key(SCENE_JSON): SCENE_JSON, name_key(ERROR_TXT): ERROR_TXT}
    for loc, names in output_files(resolved).items():
        for name in names:
            if name_key(name) in reserved:
                where = _origin(experiment, loc) if _sets(experiment, loc) else None
                prefix = f"{where}.{loc}" if where else f"base scene: {loc}"
                raise ConfigError(
                    f"{experiment.label}: {prefix}: writes {name}, the same file as the "
                    f"sweep's {reserved[name_key(name)]} in every run folder; give it "
                    f"another name (run {run.run_id})"
                )


def _sets(experiment: Experiment, loc: str) -> bool:
    """Whether the experiment sets or varies the scene field ``loc`` (or a table holding it)."""
    keys = [*experiment.set_, *experiment.sweep, *(k for g in experiment.zip_groups for k in g)]
    return any(loc == k or loc.startswith(k + ".") or k.startswith(loc + ".") for k in keys)


def check_runs(
    experiment: Experiment,
    runs: Sequence[RunSpec] | None = None,
    registry: Registry | None = None,
) -> list[ResolvedScene]:
    """Validate the scene of every run (both steps) before anything runs.

    Returns
    -------
    list of ResolvedScene
        The resolved scene of each run, in grid order.

    Raises
    ------
    ConfigError
        One line naming the experiment file, where the field was set
        (``sweep``, ``zip.<i>`` or ``set``), the dotted field and the run.
    """
    runs = expand(experiment) if runs is None else runs
    registry = default_registry() if registry is None else registry
    resolved: list[ResolvedScene] = []
    for run in runs:
        try:
            scene = load_scene(experiment.base_ref, run.overrides)
            resolved.append(resolve_scene(scene, registry))
        except ConfigError as err:
            raise _scene_error(experiment, run, err) from err
    for run, resolved_scene in zip(runs, resolved, strict=True):
        _check_sweep_files(experiment, run, resolved_scene)
    for metric in experiment.metrics or ():
        parts = metric.split(".")
        if parts[0] == "analyses" and len(parts) > 1:
            for run, resolved_scene in zip(runs, resolved, strict=True):
                if parts[1] not in _analysis_names(resolved_scene):
                    raise ConfigError(
                        f"{experiment.label}: metrics: {metric!r} needs the analysis "
                        f"{parts[1]!r} in the scene's outputs.analyses (run {run.run_id})"
                    )
    return resolved


# ---------------------------------------------------------------------------
# results


@dataclass(frozen=True)
class RunResult:
    """What one run of an experiment gave.

    Attributes
    ----------
    spec
        The run.
    status
        ``"done"`` or ``"failed"``.
    out_dir
        The run's folder.
    metrics
        The collected metrics (``None`` where the summary has no such value).
    error
        One-line error message of a failed run.
    reused
        True when the run had finished before (its summary existed) and was not run again.
    """

    spec: RunSpec
    status: Literal["done", "failed"]
    out_dir: Path
    metrics: dict[str, Any] = field(default_factory=dict)
    error: str | None = None
    reused: bool = False

    @property
    def run_id(self) -> str:
        """The run's id."""
        return self.spec.run_id

    @property
    def ok(self) -> bool:
        """True when the run finished without error."""
        return self.status == "done"


ExperimentProgress = Callable[[RunResult, int, int], None]
"""Called as ``progress(result, finished, total)`` each time a run ends (or is reused)."""


@dataclass(frozen=True)
class ExperimentResult:
    """Outcome of :func:`run_experiment`.

    Attributes
    ----------
    experiment
        The experiment.
    out_dir
        Its output directory.
    runs
        One result per run, in grid order.
    metrics
        The metric columns of ``results.csv``.
    results_path, json_path
        ``results.csv`` and ``experiment.json``.
    """

    experiment: Experiment
    out_dir: Path
    runs: tuple[RunResult, ...]
    metrics: tuple[str, ...]
    results_path: Path
    json_path: Path

    @property
    def failed(self) -> tuple[RunResult, ...]:
        """The runs that raised."""
        return tuple(r for r in self.runs if not r.ok)

    @property
    def ok(self) -> bool:
        """True when every run finished."""
        return not self.failed


def _lookup(summary: Mapping[str, Any], dotted: str) -> Any:
    node: Any = summary
    for part in dotted.split("."):
        if isinstance(node, Mapping) and part in node:
            node = node[part]
        else:
            return None
    return node


def _is_scalar(value: Any) -> bool:
    return isinstance(value, bool | int | float | str) or (
        hasattr(value, "item") and getattr(value, "ndim", 1) == 0
    )


def _collect(summary: Mapping[str, Any], metrics: Sequence[str] | None) -> dict[str, Any]:
    if metrics is not None:
        return {m: _lookup(summary, m) for m in metrics}
    out = {m: summary.get(m) for m in DEFAULT_METRICS}
    for group in ("verify", "voids"):
        values = summary.get(group)
        if isinstance(values, Mapping):
            for key, value in values.items():
                if _is_scalar(value):
                    out[f"{group}.{key}"] = value
    analyses = summary.get("analyses")
    if isinstance(analyses, Mapping):
        for name, results in analyses.items():
            if isinstance(results, Mapping):
                for key, value in results.items():
                    if _is_scalar(value):
                        out[f"analyses.{name}.{key}"] = value
    return out


def _cell(value: Any) -> str:
    if value is None:
        return ""
    if hasattr(value, "item") and getattr(value, "ndim", 1) == 0:
        value = value.item()
    if isinstance(value, bool):
        return "true" if value else "false"
    if isinstance(value, float):
        return "" if math.isnan(value) else repr(value)
    if isinstance(value, int | str):
        return str(value)
    return json.dumps(value, default=str)


def _metric_columns(experiment: Experiment, results: Sequence[RunResult]) -> list[str]:
    if experiment.metrics is not None:
        return list(experiment.metrics)
    extra = sorted({k for r in results for k in r.metrics} - set(DEFAULT_METRICS))
    return [*DEFAULT_METRICS, *extra]


def _param_columns(experiment: Experiment) -> list[str]:
    return [*experiment.sweep, *(k for g in experiment.zip_groups for k in g)]


def _write_csv(path: Path, experiment: Experiment, results: Sequence[RunResult]) -> list[str]:
    """Write the finished runs (grid order) as CSV, atomically; return the metric columns."""
    params = _param_columns(experiment)
    metrics = _metric_columns(experiment, results)
    buffer = io.StringIO()
    writer = csv.writer(buffer, lineterminator="\n")
    writer.writerow(["run_id", *params, "status", "error", *metrics])
    for r in sorted(results, key=lambda r: r.spec.index):
        writer.writerow(
            [
                r.run_id,
                *(_cell(r.spec.params.get(p)) for p in params),
                r.status,
                r.error or "",
                *(_cell(r.metrics.get(m)) for m in metrics),
            ]
        )
    with _atomic_file(path) as fh:
        fh.write(buffer.getvalue().encode("utf-8"))
    return metrics


# ---------------------------------------------------------------------------
# running


@dataclass(frozen=True)
class _Job:
    """What a worker needs to run one scene (plain, picklable data)."""

    run_id: str
    base: str
    overrides: tuple[str, ...]
    out_dir: str
    figures: bool
    verify: bool = False
    voids: bool = False
    scene_text: str = ""


def verify_metrics(packing: Packing) -> dict[str, Any]:
    """Compute the ``verify`` metrics of one packing.

    ``overlap_pairs`` and ``outside`` count the overlapping pairs and the
    particles leaving the domain, ``worst_overlap`` is the largest overlap as a
    fraction of the smaller area (0 when none), ``any_nan`` tells whether a
    placed particle has a NaN centre or outline, and ``ok`` sums it up.
    """
    placed = packing.placed
    any_nan = bool(
        np.isnan(packing.centre[placed]).any()
        or np.isnan(packing.vertices).any()
        or np.isnan(packing.radius).any()
    )
    report = verify(packing)
    worst = report.worst_overlap[2] if report.worst_overlap is not None else 0.0
    return {
        "overlap_pairs": report.n_overlapping_pairs,
        "worst_overlap": float(worst),
        "outside": report.n_outside,
        "any_nan": any_nan,
        "ok": bool(report.ok and not any_nan),
    }


def _one_line(exc: BaseException) -> str:
    text = str(exc)
    if not isinstance(exc, RegopackError):
        text = f"{type(exc).__name__}: {text}" if text else type(exc).__name__
    return " ".join(text.split())


def _run_job(job: _Job) -> tuple[dict[str, Any] | None, str | None]:
    """Run one scene; return ``(summary, None)`` or ``(None, error message)``.

    The run folder is written as a whole (see :func:`regopack.run.run_scene`),
    with the run's ``scene.json`` and the ``verify`` and ``voids`` metrics in
    its summary.
    """

    def extras(packing: Packing) -> dict[str, Any]:
        out: dict[str, Any] = {}
        if job.verify:
            out["verify"] = verify_metrics(packing)
        if job.voids:
            out["voids"] = void_metrics(packing)
        return out

    try:
        scene = load_scene(job.base, job.overrides)
        resolved = resolve_scene(scene, default_registry())
        outcome = run_scene(
            resolved,
            job.out_dir,
            figures=job.figures,
            summary_extras=extras,
            extra_files={SCENE_JSON: job.scene_text},
        )
    except Exception as exc:  # a failed run is recorded; the others go on
        return None, _one_line(exc)
    return outcome.summary, None


def _init_worker() -> None:
    """Start a worker process: Ctrl-C goes to the main process, which stops the workers.

    SIGTERM keeps its default action (the process ends at once); the main
    process removes what a stopped worker left.
    """
    signal.signal(signal.SIGINT, signal.SIG_IGN)
    signal.signal(signal.SIGTERM, signal.SIG_DFL)
    parent = os.getppid()
    threading.Thread(target=_exit_with_parent, args=(parent,), daemon=True).start()


PARENT_POLL_S = 0.5
"""How often a worker process checks that the sweep that started it is still alive."""


def _exit_with_parent(parent: int) -> None:
    """End this worker as soon as its parent is gone (e.g. killed with SIGKILL).

    A worker whose parent died is re-parented and would otherwise go on taking
    runs; its half-written run folder stays a temporary that the next sweep
    removes.
    """
    while os.getppid() == parent:
        time.sleep(PARENT_POLL_S)
    os._exit(1)


def _stop_workers(pool: ProcessPoolExecutor) -> None:
    """End the pool's worker processes now (SIGTERM), and wait until they are gone."""
    # no public way before Python 3.14 (ProcessPoolExecutor.terminate_workers)
    processes = list((getattr(pool, "_processes", None) or {}).values())
    for process in processes:
        if process.is_alive():
            process.terminate()
    for process in processes:
        process.join(timeout=10)
        if process.is_alive():
            process.kill()
            process.join(timeout=10)
    pool.shutdown(wait=True, cancel_futures=True)


def _submit_local(
    jobs: Sequence[_Job], workers: int
) -> Iterator[tuple[_Job, tuple[dict[str, Any] | None, str | None]]]:
    if workers == 1:
        for job in jobs:
            yield job, _run_job(job)
        return
    import multiprocessing

    context = multiprocessing.get_context("spawn")
    with ProcessPoolExecutor(
        max_workers=workers, mp_context=context, initializer=_init_worker
    ) as pool:
        pending: dict[Future[tuple[dict[str, Any] | None, str | None]], _Job] = {
            pool.submit(_run_job, job): job for job in jobs
        }
        try:
            while pending:
                done, _ = wait(pending, return_when=FIRST_COMPLETED)
                for future in sorted(done, key=lambda f: pending[f].run_id):
                    job = pending.pop(future)
                    try:
                        outcome = future.result()
                    except BrokenProcessPool as exc:
                        outcome = (None, f"worker process died: {_one_line(exc)}")
                    yield job, outcome
        except BaseException:  # Ctrl-C, SIGTERM, or the caller stopped early
            _stop_workers(pool)
            raise


def _dask(scheduler: str) -> Any:
    """Import ``distributed``, with a one-line error when it is missing."""
    try:
        import distributed
    except ImportError as err:
        raise ConfigError(
            f"--scheduler {scheduler}: Dask is not installed; "
            "install it with: pip install 'regopack[dask]'"
        ) from err
    return distributed


def _submit_dask(
    jobs: Sequence[_Job], scheduler: str
) -> Iterator[tuple[_Job, tuple[dict[str, Any] | None, str | None]]]:
    distributed = _dask(scheduler)
    try:
        client = distributed.Client(scheduler, timeout="20s")
    except (OSError, TimeoutError, ValueError) as err:
        raise ConfigError(
            f"--scheduler {scheduler}: cannot connect to the Dask scheduler: {_one_line(err)}"
        ) from err
    futures: dict[Any, _Job] = {}
    try:
        futures = {
            client.submit(
                _run_job, job, pure=False, key=f"regopack-{job.run_id}-{uuid.uuid4().hex}"
            ): job
            for job in jobs
        }
        for future in distributed.as_completed(list(futures)):
            job = futures[future]
            try:
                outcome = future.result()
            except Exception as exc:  # the worker was lost, or the task was cancelled
                outcome = (None, f"Dask task failed: {_one_line(exc)}")
            yield job, outcome
    except BaseException:
        client.cancel(list(futures))  # a task already running finishes its run folder
        raise
    finally:
        client.close()


def _scene_text(scene: ResolvedScene) -> str:
    return json.dumps(scene.to_dict(), indent=2, sort_keys=True, default=str) + "\n"


def _read_text(path: Path) -> str | None:
    try:
        return path.read_text(encoding="utf-8")
    except (OSError, UnicodeDecodeError):
        return None


def _write_failed_run(run_dir: Path, scene_text: str, message: str) -> str:
    """Replace the run folder by the record of a failed run: its scene and its error.

    Returns the message to record: ``message``, plus why the record could not
    be written when the folder is not writable. That run fails alone; the
    sweep goes on with the others.
    """
    try:
        with replace_folder(run_dir, RUN_FOLDER) as tmp:
            (tmp / SCENE_JSON).write_text(scene_text, encoding="utf-8")
            (tmp / ERROR_TXT).write_text(message + "\n", encoding="utf-8")
    except (OSError, ConfigError) as err:
        return f"{message} (and {run_dir / ERROR_TXT} could not be written: {_one_line(err)})"
    return message


def _read_summary(path: Path) -> dict[str, Any] | None:
    try:
        data = json.loads(path.read_text(encoding="utf-8"))
    except (OSError, UnicodeDecodeError, json.JSONDecodeError):
        return None
    return data if isinstance(data, dict) else None


def default_experiment_dir(experiment: Experiment) -> Path:
    """``runs/<experiment name>`` (relative to the working directory)."""
    return Path("runs") / _sanitise(experiment.experiment_name)


def run_experiment(
    experiment_path: str | Path,
    out_dir: str | Path | None = None,
    workers: int | None = None,
    progress: ExperimentProgress | None = None,
    *,
    scheduler: str | None = None,
) -> ExperimentResult:
    """Run every run of an experiment and collect the results.

    Parameters
    ----------
    experiment_path
        The experiment file (TOML).
    out_dir
        Output directory (default: ``runs/<experiment name>``). Each run writes
        into ``<out_dir>/<run id>/``; ``results.csv`` and ``experiment.json`` go
        into ``out_dir``.
    workers
        Number of local worker processes (default: ``os.cpu_count()``); ``1``
        runs everything in this process.
    progress
        Called as ``progress(result, finished, total)`` after each run.
    scheduler
        Address of a Dask scheduler (``tcp://host:port``); the runs are then
        submitted to that cluster through ``distributed.Client`` (install the
        ``dask`` extra). The workers must see ``out_dir``. ``workers`` and
        ``scheduler`` exclude each other.

    Returns
    -------
    ExperimentResult
        One result per run, in grid order.

    Notes
    -----
    Every run's scene, and every run folder, is checked before anything
    runs. Each run folder is written as a whole (see
    :func:`regopack.run.run_scene`): it holds the run's ``scene.json``,
    packing and summary, or, for a run that raised, ``scene.json`` and
    ``error.txt`` with its message, never a mix of two runs. A run whose
    summary file exists, and whose ``scene.json`` matches its current
    resolved scene, is not run again, so restarting an interrupted sweep
    loses nothing (a run whose scene changed, e.g. through the experiment's
    ``set``, runs again). A failed run is also listed in ``results.csv``;
    the other runs go on. ``results.csv`` is rewritten (atomically) after
    every finished run.

    When the sweep is interrupted (``KeyboardInterrupt``, or
    :class:`~regopack.errors.Terminated` for SIGTERM), the local worker
    processes are stopped and the temporary folders of their unfinished runs
    removed; the finished runs stay in ``results.csv`` and are reused when
    the sweep is started again.

    Raises
    ------
    ConfigError
        A bad experiment file, a bad scene in any run, bad options, or an
        output directory that cannot be written.
    """
    experiment = load_experiment(experiment_path)
    if workers is not None and workers < 1:
        raise ConfigError(f"--workers {workers}: must be at least 1")
    if scheduler is not None and workers is not None:
        raise ConfigError("--workers and --scheduler exclude each other")
    if scheduler is not None:
        _dask(scheduler)
    runs = expand(experiment)
    resolved = check_runs(experiment, runs)
    out = Path(out_dir) if out_dir is not None else default_experiment_dir(experiment)
    for run in runs:
        try:
            check_replaceable(out / run.run_id, RUN_FOLDER)
        except ConfigError as err:
            raise ConfigError(f"{experiment.label}: run {run.run_id}: {err}") from err
    try:
        out.mkdir(parents=True, exist_ok=True)
    except OSError as err:
        raise ConfigError(f"cannot create the output directory {out}: {err}") from err
    results_path = out / RESULTS_CSV
    experiment_json = out / EXPERIMENT_JSON
    write_json_atomic(
        experiment_json,
        {
            "name": experiment.experiment_name,
            "experiment": str(Path(experiment_path).resolve()),
            "base": str(experiment.base_ref),
            "parameters": _param_columns(experiment),
            "metrics": list(experiment.metrics) if experiment.metrics is not None else None,
            "runs": [
                {**run.to_dict(), "scene": scene.to_dict()}
                for run, scene in zip(runs, resolved, strict=True)
            ],
        },
    )

    total = len(runs)
    finished: list[RunResult] = []

    def record(result: RunResult, *, write: bool = True) -> None:
        finished.append(result)
        if write:
            _write_csv(results_path, experiment, finished)
        if progress is not None:
            progress(result, len(finished), total)

    by_id = {run.run_id: run for run in runs}
    jobs: list[_Job] = []
    for run, scene in zip(runs, resolved, strict=True):
        run_dir = out / run.run_id
        scene_text = _scene_text(scene)
        summary = _read_summary(run_dir / scene.scene.outputs.summary)
        if summary is not None and _read_text(run_dir / SCENE_JSON) == scene_text:
            metrics = _collect(summary, experiment.metrics)
            record(RunResult(run, "done", run_dir, metrics, reused=True), write=False)
            continue
        # an older run in the folder stays until this one replaces it as a whole;
        # its scene.json does not match, so it is never taken for this run
        jobs.append(
            _Job(
                run_id=run.run_id,
                base=str(experiment.base_ref),
                overrides=run.overrides,
                out_dir=str(run_dir.resolve()),
                figures=experiment.figures,
                verify=experiment.verify,
                voids=experiment.voids,
                scene_text=scene_text,
            )
        )
    _write_csv(results_path, experiment, finished)
    stream: Iterator[tuple[_Job, tuple[dict[str, Any] | None, str | None]]]
    if not jobs:
        stream = iter(())
    elif scheduler is not None:
        stream = _submit_dask(jobs, scheduler)
    else:
        count = (os.cpu_count() or 1) if workers is None else workers
        stream = _submit_local(jobs, max(1, min(count, len(jobs))))
    unfinished = {job.run_id: job for job in jobs}
    try:
        for job, (summary, error) in stream:
            run = by_id[job.run_id]
            run_dir = out / run.run_id
            if error is None and summary is not None:
                record(RunResult(run, "done", run_dir, _collect(summary, experiment.metrics)))
            else:
                message = _write_failed_run(
                    run_dir, job.scene_text, error or "the run returned no summary"
                )
                record(RunResult(run, "failed", run_dir, error=message))
            del unfinished[job.run_id]
    except BaseException:
        close = getattr(stream, "close", None)
        if close is not None:
            close()  # stops the workers now, not when the generator is collected
        if scheduler is None:
            for job in unfinished.values():
                remove_leftovers(job.out_dir)
        raise
    ordered = tuple(sorted(finished, key=lambda r: r.spec.index))
    columns = _metric_columns(experiment, ordered)
    return ExperimentResult(
        experiment=experiment,
        out_dir=out,
        runs=ordered,
        metrics=tuple(columns),
        results_path=results_path,
        json_path=experiment_json,
    )
