"""Experiment files: the model of a sweep and how it is read and checked.

:func:`load_experiment` reads a TOML experiment file (see
:mod:`regopack.experiments` for its layout) and :func:`experiment_from_dict`
validates one already parsed; both return an :class:`Experiment`, with
one-line errors that name the file and the offending key.
"""

from __future__ import annotations

import math
import re
from collections.abc import Mapping
from pathlib import Path
from typing import Annotated, Any

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

from regopack.base import toml as _toml
from regopack.base.errors import ConfigError
from regopack.base.limits import format_bytes, memory_limit
from regopack.scenes.model import builtin_scenes

__all__ = [
    "MAX_RUNS",
    "MAX_RUNS_BOUND",
    "RUN_BYTES",
    "Experiment",
    "experiment_from_dict",
    "load_experiment",
]

MAX_RUNS = 10_000
"""Default of an experiment's ``max_runs``: the largest number of runs a sweep may expand to.

A grid with more runs is refused before it is expanded (a typo such as
``seed = "1..1000000"`` would otherwise list and validate a million scenes);
set ``max_runs`` in the experiment file to allow more.
"""

MAX_RUNS_BOUND = 1_000_000
"""Largest ``max_runs`` an experiment may set: the most runs any sweep may expand to.

Every run's scene is checked and held before the first run starts (about
12 ms and 41 kB a run for ``small``), so a million runs already take hours
and tens of gigabytes before any packing; a larger ``max_runs`` (e.g.
``10**17``) is refused in one line instead of letting a typo in a range
expand without bound.
"""

RUN_BYTES = 64_000
"""Memory the checked scene of one run of a sweep holds, in bytes (measured 41 kB, rounded up).

A grid whose runs times this exceeds :func:`regopack.base.limits.memory_limit` is
refused before any range is listed.
"""

_RANGE = re.compile(r"^\s*(-?\d+)\s*\.\.\s*(-?\d+)\s*(?:\.\.\s*(\d+)\s*)?$")


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
    >>> from regopack.experiments.grid import expand
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
            "Check every packing (regopack.verification.polygons) and add verify.overlap_pairs, "
            "verify.worst_overlap, verify.outside, verify.any_nan and verify.ok to its metrics."
        ),
    )
    max_runs: int = Field(
        MAX_RUNS,
        ge=1,
        description=(
            f"Largest number of runs the grid may expand to (default {MAX_RUNS:,}, at most "
            f"{MAX_RUNS_BOUND:,}); a larger grid is refused before it is expanded."
        ),
    )
    voids: bool = Field(
        False,
        description=(
            "Rasterise the free space of every packing's interior window and add "
            "voids.void_spans (the largest void cluster touches two opposite sides) and "
            "voids.largest_void_fraction to its metrics (see regopack.packing.voids)."
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
        """The base scene as :func:`regopack.scenes.model.load_scene` takes it."""
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
    if limit > MAX_RUNS_BOUND:
        shown_limit = f"{limit}" if limit < 10**15 else f"{limit:.3g}"
        raise ValueError(
            f"max_runs = {shown_limit}: at most {MAX_RUNS_BOUND:,} runs (every run's scene "
            "is checked and held before the first run starts); split the sweep into "
            "several experiments"
        )
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
    limit_memory = memory_limit()
    if limit_memory is not None and total * RUN_BYTES > limit_memory[0]:
        raise ValueError(
            f"the sweep expands to {total:,} runs, whose scenes (about {RUN_BYTES:,} bytes a "
            f"run, checked before the first run starts) need about "
            f"{format_bytes(total * RUN_BYTES)} of memory; this machine's {limit_memory[1]} is "
            f"{format_bytes(limit_memory[0])}; split the sweep into several experiments"
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
