"""The grid of an experiment: its runs, their ids, and the check of their scenes.

:func:`expand` lists the runs (:class:`RunSpec`) of an experiment's grid in a
deterministic order, each with a stable id that is safe as a folder name, and
:func:`check_runs` validates the scene of every run before anything runs.
"""

from __future__ import annotations

import hashlib
import itertools
import re
from collections.abc import Sequence
from dataclasses import dataclass
from typing import Any

from regopack.base import toml as _toml
from regopack.base.errors import ConfigError
from regopack.base.outdir import name_key
from regopack.experiments.file import Experiment, _check_axes
from regopack.registry.manager import Registry, default_registry
from regopack.scenes.model import ResolvedScene, load_scene, output_files, resolve_scene

__all__ = ["ERROR_TXT", "SCENE_JSON", "RunSpec", "check_runs", "expand"]

ERROR_TXT = "error.txt"
"""Name of the file a failed run leaves in its folder."""

SCENE_JSON = "scene.json"
"""Name of the file holding a run's resolved scene, in its folder.

A finished run is reused only when this file matches the run's current scene.
"""

_UNSAFE = re.compile(r"[^A-Za-z0-9._=,+-]+")
_MAX_ID = 120


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
        then the varied fields), as :func:`regopack.scenes.model.load_scene` takes them.
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
        if resolved_scene.scene.domain.dimension == 3:
            raise ConfigError(
                f"{experiment.label}: run {run.run_id}: the scene is 3D (domain.kind = "
                f"{resolved_scene.scene.domain.kind!r}); sweeps run 2D scenes only so far"
            )
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
