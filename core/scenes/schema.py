"""JSON Schema of regopack's input files, including the installed plugins' parameters.

Editors use the schema to complete and check scene files as they are typed
(for TOML files, e.g. with Taplo's ``#:schema`` directive). The schema follows
JSON Schema draft 2020-12. Every plugin section of a scene (``size``,
``phases[].shape``, ``insertion``, ``density`` and the items of
``outputs.analyses``) is a ``oneOf`` over the plugins registered for that kind,
told apart by the constant ``kind``; each branch holds the properties of that
plugin's ``config_model``.

Only scenes exist so far. Each kind of input file is one entry of
:data:`DOCUMENTS`; a later kind of file (e.g. experiments) is added there and
then appears in :func:`json_schema`.

The schema checks what JSON Schema can express: types, ranges, required and
unknown keys. A few checks remain to regopack itself, e.g. that phase
fractions sum to 1 or that ``d_max`` exceeds ``d_min``.
"""

from __future__ import annotations

import copy
import json
from collections.abc import Callable, Iterator, Mapping
from typing import Any

from pydantic import BaseModel

from regopack._version import __version__
from regopack.registry.manager import Registry
from regopack.registry.plugin_types import KINDS
from regopack.scenes.model import Scene

__all__ = [
    "DOCUMENTS",
    "JSON_SCHEMA_DIALECT",
    "describe_plugins",
    "dumps",
    "json_schema",
    "plugin_branch",
    "scene_schema",
]

JSON_SCHEMA_DIALECT = "https://json-schema.org/draft/2020-12/schema"
"""The ``$schema`` of every schema regopack writes."""

JsonObject = dict[str, Any]

SECTION_TITLES: dict[str, str] = {
    "size": "size distribution",
    "shape": "shape generator",
    "insertion": "insertion strategy",
    "density": "density controller",
    "analysis": "analyzer",
    "export": "exporter",
}
"""Words for each plugin kind, used in titles and descriptions."""


def _pointer(name: str) -> str:
    """Escape ``name`` for use as one token of a JSON pointer (RFC 6901)."""
    return name.replace("~", "~0").replace("/", "~1")


def _def_name(kind: str, name: str) -> str:
    return f"{kind}.{name}"


def _summary(text: str | None) -> str | None:
    """First paragraph of a docstring, on one line."""
    if not text:
        return None
    first = text.strip().split("\n\n", 1)[0]
    return " ".join(first.split())


def _walk(node: Any) -> Iterator[JsonObject]:
    """Every JSON object in ``node``, outermost first."""
    if isinstance(node, dict):
        yield node
        for value in node.values():
            yield from _walk(value)
    elif isinstance(node, list):
        for value in node:
            yield from _walk(value)


def _model_schema(model: type[BaseModel], prefix: str) -> tuple[JsonObject, JsonObject]:
    """``model``'s validation schema and its ``$defs``, renamed to ``<prefix>.<name>``.

    The references inside both point to the renamed definitions under the root
    ``$defs`` of the document they are merged into.
    """
    schema = copy.deepcopy(model.model_json_schema(mode="validation"))
    local = schema.pop("$defs", {})
    renamed = {name: f"{prefix}.{name}" for name in local}
    defs = {renamed[name]: body for name, body in local.items()}
    for node in _walk([schema, defs]):
        ref = node.get("$ref")
        if isinstance(ref, str) and ref.startswith("#/$defs/"):
            target = ref.removeprefix("#/$defs/")
            if target in renamed:
                node["$ref"] = f"#/$defs/{_pointer(renamed[target])}"
    for body in defs.values():
        if "properties" in body and "description" in body:
            body["description"] = _summary(body["description"])
    return schema, defs


def plugin_branch(kind: str, name: str, registry: Registry) -> tuple[JsonObject, JsonObject]:
    """Build the schema of one plugin selection: its ``kind`` constant and its parameters.

    Parameters
    ----------
    kind
        Plugin kind (a key of :data:`regopack.registry.plugin_types.KINDS`).
    name
        Name of the implementation.
    registry
        Where the implementation is registered.

    Returns
    -------
    branch, defs
        The branch (an object schema whose ``kind`` is the constant ``name``)
        and the definitions it refers to, to be merged into the root ``$defs``.

    Examples
    --------
    >>> from regopack.registry.manager import default_registry
    >>> branch, _ = plugin_branch("density", "eta", default_registry(autoload=False))
    >>> branch["properties"]["kind"]["const"], branch["properties"]["eta"]["minimum"]
    ('eta', 0)
    """
    spec = registry.get(kind, name)
    info = registry.info(kind, name)
    schema, defs = _model_schema(spec.config_model, _def_name(kind, name))
    description = spec.description or _summary(schema.get("description")) or ""
    source = f"from {info.module} ({info.package})"
    properties = {
        "kind": {
            "const": name,
            "description": f"Selects the {SECTION_TITLES[kind]} {name!r}.",
        },
        **{key: value for key, value in schema.get("properties", {}).items() if key != "kind"},
    }
    branch: JsonObject = {
        "title": f"{name} ({SECTION_TITLES[kind]})",
        "description": f"{description} [{source}]".strip(),
        "type": "object",
        "properties": properties,
        "required": ["kind", *(r for r in schema.get("required", []) if r != "kind")],
    }
    if "additionalProperties" in schema:
        branch["additionalProperties"] = schema["additionalProperties"]
    return branch, defs


def _section(kind: str, registry: Registry, defs: JsonObject) -> JsonObject:
    """Build a ``oneOf`` over the plugins of ``kind``; add their branches to ``defs``."""
    names = registry.names(kind)
    what = SECTION_TITLES[kind]
    if not names:
        return {
            "description": f"No {what} plugin is installed.",
            "not": {},
        }
    branches = []
    for name in names:
        branch, extra = plugin_branch(kind, name, registry)
        defs.update(extra)
        defs[_def_name(kind, name)] = branch
        branches.append({"$ref": f"#/$defs/{_pointer(_def_name(kind, name))}"})
    for old, name in registry.aliases(kind).items():  # old names: the same branch, deprecated
        branch = copy.deepcopy(defs[_def_name(kind, name)])
        branch["properties"]["kind"]["const"] = old
        branch.update(title=f"{old} (old name of {name})", deprecated=True)
        defs[_def_name(kind, old)] = branch
        branches.append({"$ref": f"#/$defs/{_pointer(_def_name(kind, old))}"})
    names = [*names, *registry.aliases(kind)]
    return {
        "title": f"{what} plugin",
        "description": (
            f"A {what}: `kind` names the plugin ({', '.join(names)}); the other keys are its "
            "parameters."
        ),
        "type": "object",
        "required": ["kind"],
        "properties": {"kind": {"enum": names, "description": f"Name of the {what}."}},
        "oneOf": branches,
    }


def _described(section: JsonObject, field: JsonObject) -> JsonObject:
    """``section`` with the scene field's description in front of its own."""
    text = " ".join(t for t in (field.get("description"), section.get("description")) if t)
    return {**section, "description": text}


def _describe_models(schema: JsonObject) -> None:
    """Shorten the models' descriptions (their docstrings) to the first paragraph."""
    for body in [schema, *schema.get("$defs", {}).values()]:
        if "properties" in body and "description" in body:
            body["description"] = _summary(body["description"])


def scene_schema(registry: Registry) -> JsonObject:
    """JSON Schema of a scene file, with the parameters of the plugins in ``registry``.

    Parameters
    ----------
    registry
        The plugins whose parameters the schema describes; see
        :func:`regopack.registry.manager.default_registry`.

    Returns
    -------
    dict
        The schema (draft 2020-12), as plain JSON data.

    Examples
    --------
    >>> from regopack.registry.manager import default_registry
    >>> schema = scene_schema(default_registry(autoload=False))
    >>> schema["$schema"]
    'https://json-schema.org/draft/2020-12/schema'
    >>> [b["$ref"] for b in schema["properties"]["density"]["oneOf"]]
    ['#/$defs/density.eta', '#/$defs/density.target']
    """
    schema = copy.deepcopy(Scene.model_json_schema(mode="validation"))
    defs: JsonObject = schema.setdefault("$defs", {})
    defs.pop("PluginRef", None)
    _describe_models(schema)
    sections = {kind: _section(kind, registry, defs) for kind in KINDS}

    props = schema["properties"]
    for key in ("size", "insertion", "density"):
        props[key] = _described(sections[key], props[key])
    phase = defs["Phase"]["properties"]
    phase["shape"] = _described(sections["shape"], phase["shape"])
    analyses = defs["Outputs"]["properties"]["analyses"]
    names = [*registry.names("analysis"), *registry.aliases("analysis")]
    by_name: JsonObject = {
        "type": "string",
        "description": "Name of an analyzer, run with its default parameters.",
    }
    by_name["enum"] = names
    analyses["items"] = {"anyOf": [by_name, sections["analysis"]]}
    exports = defs["Outputs"]["properties"]["exports"]
    exporter_by_name: JsonObject = {
        "type": "string",
        "description": "Name of an exporter, run with its default parameters.",
        "enum": [*registry.names("export"), *registry.aliases("export")],
    }
    exports["items"] = {"anyOf": [exporter_by_name, sections["export"]]}

    leftover = [n for n in _walk(schema) if n.get("$ref") == "#/$defs/PluginRef"]
    if leftover:  # pragma: no cover - a new plugin section must be handled above
        raise RuntimeError("scene_schema: a plugin section of Scene is not handled")

    plugins = ", ".join(f"{kind}: {', '.join(registry.names(kind)) or '(none)'}" for kind in KINDS)
    header: JsonObject = {
        "$schema": JSON_SCHEMA_DIALECT,
        "title": "regopack scene",
        "description": (
            f"A regopack scene file (TOML), as read by regopack {__version__}. "
            f"Plugins described: {plugins}."
        ),
    }
    body = {k: v for k, v in schema.items() if k not in ("title", "description", "$defs")}
    return {**header, **body, "$defs": defs}


def _type_of(prop: Mapping[str, Any], defs: Mapping[str, Any]) -> str:
    """Short type text of a JSON Schema property, with its bounds: ``number > 0, ≤ 1``."""
    if "$ref" in prop:
        target = defs.get(
            str(prop["$ref"]).rsplit("/", 1)[-1].replace("~1", "/").replace("~0", "~")
        )
        text = _type_of(target, defs) if isinstance(target, Mapping) else "object"
    elif "const" in prop:
        text = json.dumps(prop["const"], ensure_ascii=False)
    elif "enum" in prop:
        text = " | ".join(json.dumps(v, ensure_ascii=False) for v in prop["enum"])
    elif "anyOf" in prop or "oneOf" in prop:
        text = " | ".join(_type_of(p, defs) for p in prop.get("anyOf", prop.get("oneOf", [])))
    elif prop.get("type") == "array":
        if "prefixItems" in prop:
            text = "[" + ", ".join(_type_of(p, defs) for p in prop["prefixItems"]) + "]"
        elif "items" in prop:
            text = f"array of {_type_of(prop['items'], defs)}"
        else:
            text = "array"
    elif isinstance(prop.get("type"), list):
        text = " | ".join(str(t) for t in prop["type"])
    else:
        text = str(prop.get("type", "any"))
    bounds = [
        f"{sign} {prop[key]}" if isinstance(prop[key], int) else f"{sign} {prop[key]:g}"
        for key, sign in (
            ("exclusiveMinimum", ">"),
            ("minimum", "≥"),
            ("exclusiveMaximum", "<"),
            ("maximum", "≤"),
        )
        if isinstance(prop.get(key), int | float)
    ]
    return ", ".join([text, *bounds])


def _default_of(info: Any) -> tuple[bool, Any]:
    """Return ``(required, default)`` of a pydantic field, the default as JSON data."""
    if info.is_required():
        return True, None
    value = info.get_default(call_default_factory=True)
    if isinstance(value, BaseModel):
        value = value.model_dump(mode="json")
    try:
        json.dumps(value, allow_nan=False)
    except (TypeError, ValueError):
        value = repr(value)
    if isinstance(value, tuple):
        value = list(value)
    return False, value


def describe_plugins(registry: Registry, kind: str | None = None) -> list[JsonObject]:
    """Every registered plugin with its origin and parameters, as plain JSON data.

    Parameters
    ----------
    registry
        The plugins to describe.
    kind
        Describe only this plugin kind (a key of :data:`regopack.registry.plugin_types.KINDS`).

    Returns
    -------
    list of dict
        One entry per plugin, in the order of the kinds and then by name, with the
        keys ``kind``, ``name``, ``description``, ``plugin``, ``module``,
        ``distribution``, ``version`` and ``fields``; each field has ``name``,
        ``type``, ``required``, ``default``, ``description`` and ``schema`` (its
        JSON Schema).

    Examples
    --------
    >>> from regopack.registry.manager import default_registry
    >>> entry = describe_plugins(default_registry(autoload=False), "density")[0]
    >>> entry["name"], entry["distribution"], [f["name"] for f in entry["fields"]]
    ('eta', 'regopack', ['eta'])
    >>> entry["fields"][0]["type"], entry["fields"][0]["default"]
    ('number, ≥ 0, ≤ 1000', 0.0)
    """
    kinds = list(KINDS) if kind is None else [kind]
    out: list[JsonObject] = []
    for k in kinds:
        for name in registry.names(k):
            spec = registry.get(k, name)
            info = registry.info(k, name)
            model = spec.config_model
            schema = model.model_json_schema(mode="validation")
            props = schema.get("properties", {})
            defs = schema.get("$defs", {})
            fields = []
            for field_name, field in model.model_fields.items():
                key = field.alias or field_name
                prop = props.get(key, {})
                required, default = _default_of(field)
                fields.append(
                    {
                        "name": key,
                        "type": _type_of(prop, defs),
                        "required": required,
                        "default": default,
                        "description": field.description or "",
                        "schema": prop,
                    }
                )
            out.append(
                {
                    "kind": k,
                    "name": name,
                    "description": spec.description or _summary(model.__doc__) or "",
                    "plugin": info.plugin,
                    "module": info.module,
                    "distribution": info.distribution,
                    "version": info.version,
                    "fields": fields,
                }
            )
    return out


DOCUMENTS: dict[str, Callable[[Registry], JsonObject]] = {"scene": scene_schema}
"""Kinds of input file and the function that builds each one's schema."""


def json_schema(registry: Registry, document: str = "scene") -> JsonObject:
    """JSON Schema of one kind of input file (see :data:`DOCUMENTS`).

    Raises
    ------
    KeyError
        If ``document`` is not a key of :data:`DOCUMENTS`.
    """
    return DOCUMENTS[document](registry)


def dumps(schema: Mapping[str, Any]) -> str:
    """Return ``schema`` as indented JSON text ending with a newline."""
    return json.dumps(schema, indent=2, ensure_ascii=False) + "\n"
