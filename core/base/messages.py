"""One-line messages for validation errors: where a value came from, and what is allowed.

A scene value comes from a file or from a command-line option (``--set``,
``--seed``); a message names that source, the dotted field, the value and
what is allowed. An unknown field is answered with the closest known one and
the list of the fields that exist there, e.g.::

    --set: domian: unknown field; did you mean 'domain'? allowed: name, seed, ...
"""

from __future__ import annotations

import difflib
import re
import types
import typing
from collections.abc import Mapping, Sequence
from typing import Any

from pydantic import BaseModel, ValidationError

from regopack.base import toml as _toml

__all__ = [
    "closest",
    "describe_validation_error",
    "dotted",
    "fields_at",
    "format_value",
    "install_hint",
    "where",
]


def install_hint(extra: str) -> str:
    """How to install the optional dependencies of regopack's ``extra``, from a clone too.

    An extra named as ``regopack[gsd]`` installs only from a package index
    that holds regopack, so a copy installed from its source folder cannot
    use it. The hint names the
    extra's own requirements (from regopack's installed metadata, so it
    follows ``pyproject.toml``), which install anywhere, and the extra as it
    installs from the source folder.

    Examples
    --------
    >>> install_hint("gsd")
    "pip install 'gsd>=3.0', or pip install '.[gsd]' in regopack's source folder"
    """
    from importlib import metadata

    marker = f'extra == "{extra}"'
    try:
        requires = metadata.requires("regopack") or []
    except metadata.PackageNotFoundError:
        requires = []
    wanted = [r.split(";")[0].strip() for r in requires if marker in r.replace("'", '"')]
    packages = " ".join(f"'{r}'" for r in wanted) or extra
    return f"pip install {packages}, or pip install '.[{extra}]' in regopack's source folder"


def format_value(value: Any) -> str | None:
    """Return a scalar as TOML text; ``None`` for a table or a list (not shown).

    Examples
    --------
    >>> format_value(3.5), format_value("x"), format_value([1, 2])
    ('3.5', '"x"', None)
    """
    if isinstance(value, Mapping) or (
        isinstance(value, Sequence) and not isinstance(value, str | bytes)
    ):
        return None
    if isinstance(value, bool | int | float | str):
        return _toml._value(value)
    return repr(value)


def dotted(loc: Sequence[int | str]) -> str:
    """``("phases", 0, "shape")`` as ``"phases.0.shape"``."""
    return ".".join(str(p) for p in loc)


def where(
    loc: str, source: str | None, overridden: Mapping[str, str], message: str | None = None
) -> str | None:
    """Where the value at the dotted field ``loc`` came from: an option or the file.

    An option that set ``loc`` or a table holding it is named. An option that
    set a field inside ``loc`` (an error of a whole table, such as two of its
    fields that disagree) is named only when ``message`` is not given or
    names that field; otherwise ``source``.

    Examples
    --------
    >>> where("size", "small.toml", {"size.d_min": "--set"})
    '--set'
    >>> where("size", "small.toml", {"size.alpha": "--set"}, "d_max must exceed d_min")
    'small.toml'
    >>> where("density.eta", "small.toml", {"size.d_min": "--set"})
    'small.toml'
    >>> where("phases", "small.toml", {"phases.2.fraction": "--set"}, "fractions sum to 4")
    '--set'
    """
    for key, label in overridden.items():
        if loc == key or loc.startswith(key + "."):
            return label
        if key.startswith(loc + "."):
            # the field inside loc: past a list index (phases.2.fraction: "fraction"),
            # also in the plural ("phase fractions sum to 0.9")
            parts = key[len(loc) + 1 :].split(".")
            field = next((p for p in parts if not p.isdigit()), parts[0])
            if message is None or re.search(rf"\b{re.escape(field)}s?\b", message):
                return label
    return source


def closest(name: str, choices: Sequence[str]) -> str | None:
    """Return the choice most like ``name`` (:func:`difflib.get_close_matches`), if close.

    Examples
    --------
    >>> closest("domian", ["name", "domain", "density"])
    'domain'
    >>> closest("xyz", ["name", "domain"]) is None
    True
    """
    match = difflib.get_close_matches(name, list(choices), n=1, cutoff=0.75)
    if match:
        return match[0]
    folded = {c.lower(): c for c in choices}
    return folded.get(name.lower())


def _model_in(annotation: Any) -> type[BaseModel] | None:
    """Return the pydantic model inside a field type (through lists, unions, Annotated)."""
    if isinstance(annotation, type) and issubclass(annotation, BaseModel):
        return annotation
    origin = typing.get_origin(annotation)
    if origin is None:
        return None
    args = typing.get_args(annotation)
    if origin is typing.Annotated:
        args = args[:1]
    elif origin not in (list, tuple, typing.Union, types.UnionType, dict):
        return None
    for arg in args:
        found = _model_in(arg)
        if found is not None:
            return found
    return None


def fields_at(model: type[BaseModel], loc: Sequence[int | str]) -> list[str] | None:
    """Return the names of the fields of the model at ``loc`` inside ``model``, if known.

    List indices in ``loc`` are skipped; ``None`` when ``loc`` leads to no
    model (e.g. into a section whose fields a plugin defines).
    """
    node: type[BaseModel] | None = model
    for part in loc:
        if isinstance(part, int) or (isinstance(part, str) and part.isdigit()):
            continue
        if node is None:
            return None
        field = node.model_fields.get(str(part))
        if field is None:
            return None
        node = _model_in(field.annotation)
    if node is None:
        return None
    return [field.alias or name for name, field in node.model_fields.items()]


def _unknown_field(name: str, allowed: Sequence[str] | None) -> str:
    """``unknown field; did you mean 'x'? allowed: a, b`` for an extra key ``name``."""
    if allowed is None:
        return "unknown field"
    if not allowed:
        return "unknown field; this section takes no fields"
    guess = closest(name, allowed)
    listed = ", ".join(allowed)
    if guess is None:
        return f"unknown field; allowed: {listed}"
    return f"unknown field; did you mean {guess!r}? allowed: {listed}"


def describe_validation_error(
    err: ValidationError,
    *,
    source: str | None,
    prefix: Sequence[int | str] = (),
    overridden: Mapping[str, str] | None = None,
    model: type[BaseModel] | None = None,
    also: Sequence[str] = (),
) -> str:
    """One line describing the first error of ``err``.

    Parameters
    ----------
    err
        The error of validating a dictionary with a pydantic model.
    source
        File the values came from (for the message), if any.
    prefix
        Dotted location of the validated dictionary inside the scene, e.g.
        ``("phases", 2, "shape")``.
    overridden
        Dotted keys set on the command line, mapped to the option that set
        them; an error in them names the option instead of ``source``.
    model
        The model that was validated; an unknown field is then answered with
        the closest field that exists and the list of those fields.
    also
        Further keys allowed beside the model's fields (e.g. ``kind`` of a
        plugin section), listed first.
    """
    errors = err.errors(include_url=False)
    first = errors[0]
    loc = dotted([*prefix, *first["loc"]])
    msg = first["msg"].removeprefix("Value error, ")
    if first["type"] == "extra_forbidden" and first["loc"]:
        allowed = fields_at(model, first["loc"][:-1]) if model is not None else None
        if allowed is not None and len(first["loc"]) == 1:
            allowed = [*also, *allowed]
        msg = _unknown_field(str(first["loc"][-1]), allowed)
    value = None if first["type"] == "missing" else format_value(first.get("input"))
    text = f"{loc} = {value}: {msg}" if value is not None else f"{loc}: {msg}"
    # an unknown table named by an option is that option's; a whole-table error is
    # blamed on an option inside it only when it names the option's field
    about = None if first["type"] == "extra_forbidden" else msg
    origin = where(loc, source, overridden or {}, about)
    if origin:
        text = f"{origin}: {text}"
    if len(errors) > 1:
        more = len(errors) - 1
        text += f" (and {more} more error{'s' if more > 1 else ''})"
    return " ".join(text.split())
