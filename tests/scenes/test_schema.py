"""The JSON Schema of scenes: structure, plugin parameters, and validation of real scenes.

Validation itself uses the ``jsonschema`` package when it is installed (it is
not a dependency of regopack); the structure is checked either way.
"""

from __future__ import annotations

import copy
import importlib.util
import json
import sys
import tomllib
from importlib import resources
from pathlib import Path
from typing import Any

import pytest

from regopack.registry.manager import default_registry
from regopack.registry.plugin_types import KINDS
from regopack.scenes.model import builtin_scenes
from regopack.scenes.schema import (
    DOCUMENTS,
    JSON_SCHEMA_DIALECT,
    describe_plugins,
    json_schema,
    plugin_branch,
    scene_schema,
)
from regopack.testing import make_registry

EXAMPLE = Path(__file__).resolve().parents[2] / "docs" / "examples" / "regopack-example-plugin"
HAVE_JSONSCHEMA = importlib.util.find_spec("jsonschema") is not None
needs_jsonschema = pytest.mark.skipif(
    not HAVE_JSONSCHEMA, reason="jsonschema is not installed (it is optional for regopack)"
)


@pytest.fixture(scope="module")
def registry():
    return default_registry(autoload=False)


@pytest.fixture(scope="module")
def schema(registry):
    return scene_schema(registry)


def builtin_scene_data() -> dict[str, dict[str, Any]]:
    return {
        name: tomllib.loads(
            resources.files("regopack.scenes").joinpath(f"{name}.toml").read_text("utf-8")
        )
        for name in builtin_scenes()
    }


def resolve(schema: dict[str, Any], node: dict[str, Any]) -> dict[str, Any]:
    while "$ref" in node:
        ref = node["$ref"].removeprefix("#/$defs/").replace("~1", "/").replace("~0", "~")
        node = schema["$defs"][ref]
    return node


def sections(schema: dict[str, Any]) -> dict[str, dict[str, Any]]:
    """The schema of every plugin section, by plugin kind."""
    defs = schema["$defs"]
    return {
        "size": schema["properties"]["size"],
        "shape": defs["Phase"]["properties"]["shape"],
        "insertion": schema["properties"]["insertion"],
        "density": schema["properties"]["density"],
        "analysis": defs["Outputs"]["properties"]["analyses"]["items"]["anyOf"][1],
    }


# ---------------------------------------------------------------------------
# structure (always checked)


def test_header(schema):
    assert (
        schema["$schema"] == JSON_SCHEMA_DIALECT == ("https://json-schema.org/draft/2020-12/schema")
    )
    assert schema["title"] == "regopack scene"
    assert schema["description"]
    assert schema["type"] == "object"
    assert schema["additionalProperties"] is False
    assert set(schema["required"]) == {"size", "phases", "insertion", "density"}
    json.dumps(schema, allow_nan=False)  # plain JSON


def test_every_plugin_section_is_a_one_of_over_the_registered_plugins(schema, registry):
    for kind, section in sections(schema).items():
        names = [*registry.names(kind), *registry.aliases(kind)]
        assert section["required"] == ["kind"]
        assert section["properties"]["kind"]["enum"] == names
        branches = [resolve(schema, b) for b in section["oneOf"]]
        assert [b["properties"]["kind"]["const"] for b in branches] == names, kind
        for name, branch in zip(names, branches, strict=True):
            model = registry.get(kind, registry.canonical(kind, name)).config_model
            assert set(branch["properties"]) == {"kind", *model.model_fields}
            assert branch["required"][0] == "kind"
            assert branch["additionalProperties"] is False
            assert branch["description"]
            for field, prop in branch["properties"].items():
                assert prop.get("description"), f"{kind} {name}: {field} has no description"


def test_analyses_accept_a_name_or_a_table(schema, registry):
    items = schema["$defs"]["Outputs"]["properties"]["analyses"]["items"]["anyOf"]
    assert items[0]["type"] == "string"
    assert items[0]["enum"] == [*registry.names("analysis"), *registry.aliases("analysis")]


def test_an_old_name_is_accepted_and_marked_deprecated(schema, registry):
    import jsonschema

    branch = schema["$defs"]["analysis.contacts3d"]
    assert branch["deprecated"] is True and branch["title"] == "contacts3d (old name of contacts)"
    assert branch["properties"]["kind"]["const"] == "contacts3d"
    outputs = {"analyses": ["density3d", {"kind": "contacts3d", "tol": 0.1}]}
    jsonschema.validate(outputs, {**schema["$defs"]["Outputs"], "$defs": schema["$defs"]})


def test_every_property_of_the_core_models_is_described(schema):
    for owner in [schema, *(schema["$defs"][n] for n in ("Domain", "Phase", "Outputs"))]:
        assert owner["description"]
        for name, prop in owner["properties"].items():
            assert prop.get("description"), name
    assert "PluginRef" not in schema["$defs"]
    assert '"#/$defs/PluginRef"' not in json.dumps(schema)


def test_references_all_resolve(schema):
    text = json.dumps(schema)
    for ref in set(text.split('"$ref": ')[1:]):
        target = json.loads(ref.split(",")[0].split("}")[0])
        resolve(schema, {"$ref": target})


def test_plugin_branch_keeps_ranges():
    registry = default_registry(autoload=False)
    branch, defs = plugin_branch("shape", "octagon", registry)
    assert defs == {}
    assert branch["properties"]["psi"]["exclusiveMinimum"] == 0
    assert branch["properties"]["m"]["minimum"] == 3
    assert branch["properties"]["kind"] == {
        "const": "octagon",
        "description": "Selects the shape generator 'octagon'.",
    }
    assert "regopack.plugins.shapes.octagon (regopack " in branch["description"]


def test_nested_definitions_of_a_plugin_are_renamed(schema):
    # every definition of a plugin model lives under its own prefix
    for name in schema["$defs"]:
        assert name in {"Domain", "Phase", "Outputs", "Tiles"} or name.split(".")[0] in KINDS, name


def test_builtin_scenes_fit_the_structure(schema, registry):
    """Without jsonschema: every plugin section of the built-in scenes names a branch and
    only uses keys of that branch."""
    for name, data in builtin_scene_data().items():
        refs = [("size", data["size"]), ("insertion", data["insertion"])]
        refs += [("density", data["density"])]
        refs += [("shape", p["shape"]) for p in data["phases"]]
        for kind, ref in refs:
            branches = {
                b["properties"]["kind"]["const"]: b
                for b in (resolve(schema, x) for x in sections(schema)[kind]["oneOf"])
            }
            assert ref["kind"] in branches, (name, kind)
            assert set(ref) <= set(branches[ref["kind"]]["properties"]), (name, kind)
        assert set(data) <= set(schema["properties"]), name


def test_with_no_plugins_of_a_kind_nothing_validates():
    schema = scene_schema(make_registry(builtins=()))
    assert schema["properties"]["size"]["not"] == {}
    assert "No size distribution plugin" in schema["properties"]["size"]["description"]


def test_documents():
    assert list(DOCUMENTS) == ["scene"]
    registry = default_registry(autoload=False)
    assert json_schema(registry) == scene_schema(registry)
    with pytest.raises(KeyError):
        json_schema(registry, "experiment")


def test_describe_plugins(registry):
    entries = describe_plugins(registry)
    assert [(e["kind"], e["name"]) for e in entries] == [
        (kind, name) for kind in KINDS for name in registry.names(kind)
    ]
    octagon = next(e for e in entries if e["name"] == "octagon")
    assert octagon["module"] == "regopack.plugins.shapes.octagon"
    assert octagon["distribution"] == "regopack"
    psi = octagon["fields"][0]
    assert psi["name"] == "psi"
    assert psi["type"].startswith("number, > 0")
    assert psi["default"] == 1.0
    assert psi["required"] is False
    assert psi["description"]
    assert describe_plugins(registry, "density")[0]["name"] == "eta"


# ---------------------------------------------------------------------------
# validation (with jsonschema)


def flatten(errors: list[Any]) -> list[Any]:
    """Errors with the errors of every ``oneOf``/``anyOf`` branch they contain."""
    out = []
    for error in errors:
        out.append(error)
        out += flatten(list(error.context or []))
    return out


def validator(schema: dict[str, Any]) -> Any:
    import jsonschema

    jsonschema.Draft202012Validator.check_schema(schema)
    return jsonschema.Draft202012Validator(schema)


@needs_jsonschema
def test_schema_is_a_valid_draft_2020_12_schema(schema):
    validator(schema)


@needs_jsonschema
@pytest.mark.parametrize("name", sorted(builtin_scenes()))
def test_builtin_scenes_validate(schema, name):
    data = builtin_scene_data()[name]
    errors = [e.message for e in validator(schema).iter_errors(data)]
    assert errors == []


@needs_jsonschema
@pytest.mark.parametrize(
    ("change", "path"),
    [
        (lambda d: d["phases"][0]["shape"].update(psi=-1), ["phases", 0, "shape", "psi"]),
        (lambda d: d["phases"][0]["shape"].update(kind="octagn"), ["phases", 0, "shape"]),
        (lambda d: d["phases"][0]["shape"].update(colour="red"), ["phases", 0, "shape"]),
        (lambda d: d["density"].update(eta="high"), ["density", "eta"]),
        (lambda d: d["domain"].update(width=0), ["domain", "width"]),
        (lambda d: d.update(count=0), ["count"]),
        (lambda d: d.update(length_unit="ft"), ["length_unit"]),
        (lambda d: d.pop("size"), []),
        (lambda d: d["outputs"].update(analyses=["nosuch"]), ["outputs", "analyses", 0]),
        (
            lambda d: d["outputs"].update(analyses=[{"kind": "contacts", "tol": -1}]),
            ["outputs", "analyses", 0],
        ),
    ],
    ids=[
        "psi",
        "kind",
        "unknown-key",
        "type",
        "width",
        "count",
        "length_unit",
        "missing",
        "analysis",
        "tol",
    ],
)
def test_bad_scenes_fail_validation(schema, change, path):
    data = copy.deepcopy(builtin_scene_data()["small"])
    change(data)
    errors = list(validator(schema).iter_errors(data))
    assert errors
    # the offending key is named by an error, possibly inside the branch of its plugin
    paths = [list(e.absolute_path) for e in flatten(errors)]
    assert any(p[: len(path)] == path for p in paths), paths


@needs_jsonschema
def test_the_example_scene_validates_against_the_schema_with_the_example_plugin(monkeypatch):
    monkeypatch.syspath_prepend(str(EXAMPLE))
    monkeypatch.delitem(sys.modules, "regopack_example_plugin", raising=False)
    import regopack_example_plugin

    data = tomllib.loads((EXAMPLE / "example.toml").read_text("utf-8"))
    builtin_only = validator(scene_schema(default_registry(autoload=False)))
    assert list(builtin_only.iter_errors(data))  # ellipse-polygon is not a built-in
    with_plugin = validator(scene_schema(make_registry(regopack_example_plugin)))
    assert [e.message for e in with_plugin.iter_errors(data)] == []
    data["phases"][0]["shape"]["aspect"] = 0.5
    assert list(with_plugin.iter_errors(data))


def test_docstring_examples():
    import doctest

    import regopack.scenes.schema

    result = doctest.testmod(regopack.scenes.schema, optionflags=doctest.ELLIPSIS)
    assert result.attempted > 0
    assert result.failed == 0
