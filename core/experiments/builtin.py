"""Built-in experiments (TOML files), run with ``regopack sweep --builtin NAME``.

Each ``NAME.toml`` here is an experiment file (see :mod:`regopack.experiments`);
files named ``*-scene.toml`` are scenes that the experiments use as their base.
"""

from __future__ import annotations

from importlib import resources
from pathlib import Path

from regopack.base.errors import ConfigError
from regopack.base.toml import first_comment

__all__ = ["builtin_experiment_path", "builtin_experiments"]

_SCENE_SUFFIX = "-scene.toml"


def builtin_experiments() -> dict[str, str]:
    """Built-in experiments: name to one-line description (the file's first comment).

    Examples
    --------
    >>> sorted(builtin_experiments())
    ['eta', 'scaling', 'screening', 'seeds', 'stress']
    """
    out: dict[str, str] = {}
    for entry in sorted(resources.files("regopack.experiments").iterdir(), key=lambda e: e.name):
        name = entry.name
        if not name.endswith(".toml") or name.endswith(_SCENE_SUFFIX):
            continue
        out[name.removesuffix(".toml")] = first_comment(entry.read_text(encoding="utf-8"))
    return out


def builtin_experiment_path(name: str) -> Path:
    """Return the file of the built-in experiment ``name``.

    Raises
    ------
    ConfigError
        One line listing the built-in experiments when ``name`` is not one.
    """
    names = builtin_experiments()
    if name not in names:
        raise ConfigError(
            f"--builtin {name}: no such built-in experiment; choose one of: {', '.join(names)}"
        )
    return Path(str(resources.files("regopack.experiments").joinpath(f"{name}.toml")))
