from __future__ import annotations

import math
import tomllib
from pathlib import Path

import numpy as np
import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st
from pydantic import BaseModel

from regopack.base import toml as _toml
from regopack.base.errors import ConfigError
from regopack.scenes.model import (
    DEFAULT_SCENE,
    Domain,
    Outputs,
    Phase,
    PluginRef,
    Scene,
    apply_overrides,
    builtin_scenes,
    load_scene,
    resolve_scene,
    scene_from_dict,
)

TABLE1_PHASES = [
    ("pyroxene", 0.343, 0.25),
    ("feldspar", 0.315, 0.5),
    ("glass", 0.161, 1.0),
    ("olivine", 0.091, 2.0),
    ("ilmenite", 0.052, 15.0),
    ("others", 0.038, 0.8),
]


@pytest.fixture
def scene_file(tmp_path, monkeypatch):
    """Write a variant of the small scene as ./scene.toml and return a writer."""
    monkeypatch.chdir(tmp_path)
    base = load_builtin_text("small")

    def write(old: str, new: str) -> str:
        assert old in base
        Path("scene.toml").write_text(base.replace(old, new, 1), encoding="utf-8")
        return "scene.toml"

    return write


def load_builtin_text(name: str) -> str:
    from importlib.resources import files

    return files("regopack.scenes").joinpath(f"{name}.toml").read_text(encoding="utf-8")


def error_of(path_or_name, registry, overrides=(), seed=None) -> str:
    with pytest.raises(ConfigError) as info:
        resolve_scene(load_scene(path_or_name, overrides, seed=seed), registry)
    msg = str(info.value)
    assert "\n" not in msg
    return msg


# -- built-in scenes -----------------------------------------------------------


def test_builtin_scenes_have_descriptions():
    scenes = builtin_scenes()
    assert set(scenes) == {"table1", "small", "dem", "table1-3d", "dem3d"}
    assert all(desc and "\n" not in desc for desc in scenes.values())
    assert DEFAULT_SCENE == "table1"


def test_default_scene_is_table1():
    scene = load_scene(None)
    assert scene.name == "table1"
    assert scene.seed == 1
    assert scene.count == "auto"
    assert scene.domain == Domain(width=800, height=800, center=(0, 0))
    assert scene.size.kind == "change5"
    assert scene.size.params == {"d_min": 2.0, "d_max": 40.0, "d0": 16.0, "alpha": 6.9}
    got = [(p.name, p.fraction, p.shape.params["psi"]) for p in scene.phases]
    assert got == TABLE1_PHASES
    for p in scene.phases:
        assert p.shape.kind == "octagon"
        assert p.shape.params["a"] == pytest.approx(1 / 3, abs=1e-15)
        assert p.shape.params["m"] == 8
    assert scene.insertion.kind == "available-arc"
    assert scene.insertion.params == {
        "t": 0.999,
        "interference": "exact",
        "tau": 0.65,
        "first": "center",
        "search": "indexed",
    }
    assert scene.density.kind == "eta"
    assert scene.density.params == {"eta": 0.0}
    assert scene.outputs == Outputs()


def test_small_differs_from_table1_only_in_name_and_domain():
    small = load_scene("small").model_dump()
    table1 = load_scene("table1").model_dump()
    assert small.pop("name") == "small"
    assert table1.pop("name") == "table1"
    assert small.pop("domain")["width"] == 200
    table1.pop("domain")
    assert small == table1


def test_fractions_are_normalised():
    scene = load_scene("table1", ["phases.0.fraction=0.3435"])
    f = scene.fractions
    assert math.isclose(f.sum(), 1.0, rel_tol=0, abs_tol=1e-15)
    assert f[0] / f[1] == pytest.approx(0.3435 / 0.315)


def test_scene_file_by_path(scene_file, registry):
    path = scene_file('name = "small"', 'name = "mine"')
    assert load_scene(path).name == "mine"
    assert load_scene(Path(path)).name == "mine"


def test_builtin_name_with_toml_suffix_is_a_path(tmp_path, monkeypatch):
    monkeypatch.chdir(tmp_path)
    with pytest.raises(ConfigError, match=r"small.toml: no such scene file"):
        load_scene("small.toml")


def test_missing_scene_file_lists_builtins(tmp_path):
    with pytest.raises(ConfigError) as info:
        load_scene(tmp_path / "nope.toml")
    msg = str(info.value)
    assert "no such scene file" in msg
    assert "small, table1" in msg


def test_directory_is_not_a_scene(tmp_path):
    with pytest.raises(ConfigError, match="is a directory"):
        load_scene(tmp_path)


# -- overrides -----------------------------------------------------------------


def test_overrides(registry):
    scene = load_scene(
        "table1",
        [
            "density.eta=10",
            "insertion.t=0.99",
            "count=2000",
            "domain.width=200",
            "phases.0.shape.psi=3",
            "insertion.first=random",
            "name=my run",
        ],
        seed=5,
    )
    assert scene.count == 2000
    assert scene.domain.width == 200.0
    assert scene.seed == 5
    assert scene.name == "my run"
    resolved = resolve_scene(scene, registry)
    assert resolved.density.config.eta == 10.0
    assert resolved.insertion.config.t == 0.99
    assert resolved.insertion.config.first == "random"
    assert resolved.phases[0].shape.config.psi == 3.0
    assert resolved.phases[1].shape.config.psi == 0.5


def test_override_values_are_toml():
    data: dict = {"phases": [{"shape": {}}]}
    keys = apply_overrides(
        data,
        ["a.b=1", "a.c=1.5", "a.d=true", 'a.e="x=y"', "a.f=[1, 2]", "a.g=plain text", " h = 3 "],
    )
    assert keys == ["a.b", "a.c", "a.d", "a.e", "a.f", "a.g", "h"]
    assert data["a"] == {"b": 1, "c": 1.5, "d": True, "e": "x=y", "f": [1, 2], "g": "plain text"}
    assert data["h"] == 3


@pytest.mark.parametrize(
    ("override", "message"),
    [
        ("density", "expected key=value"),
        ("=3", "expected key=value"),
        ("a..b=1", "empty part"),
        ("phases.9.shape.psi=1", "phases.9 is not an item of a list of 6 items"),
        ("phases.x.shape.psi=1", "phases.x is not an item of a list"),
        ("name.x=1", "name is a value, not a table"),
    ],
)
def test_bad_overrides(override, message):
    with pytest.raises(ConfigError, match=message):
        load_scene("table1", [override])


# -- one-line errors -------------------------------------------------------------


@pytest.mark.parametrize(
    ("old", "new", "expected"),
    [
        (
            "eta = 0.0",
            "eta = -3",
            "scene.toml: density.eta = -3: Input should be greater than or equal to 0",
        ),
        (
            "width = 200.0",
            "width = -1",
            "scene.toml: domain.width = -1: Input should be greater than 0",
        ),
        (
            "psi = 1.0,",
            "psi = -1,",
            "scene.toml: phases.2.shape.psi = -1: Input should be greater than 0",
        ),
        (
            'kind = "change5"',
            'kind = "chang5"',
            "scene.toml: size.kind: unknown size kind 'chang5'; did you mean 'change5'? "
            "known kinds: change5",
        ),
        (
            'shape = { kind = "octagon", psi = 2.0',
            'shape = { kind = "octagn", psi = 2.0',
            "scene.toml: phases.3.shape.kind: unknown shape kind 'octagn'; "
            "did you mean 'octagon'? known kinds: octagon",
        ),
        (
            "eta = 0.0",
            "etta = 1",
            "scene.toml: density.etta = 1: unknown field; did you mean 'eta'? allowed: kind, eta",
        ),
        (
            "fraction = 0.343",
            "fraction = 0.243",
            "scene.toml: phases: phase fractions sum to 0.9; they must sum to 1 (within 0.001)",
        ),
        (
            'name = "glass"',
            'name = "olivine"',
            "scene.toml: phases: phase names must be unique; repeated: olivine",
        ),
        (
            'count = "auto"',
            "count = 0",
            'scene.toml: count = 0: must be "auto" or a whole number >= 1',
        ),
        (
            'count = "auto"',
            'count = "many"',
            'scene.toml: count = "many": must be "auto" or a whole number >= 1',
        ),
        ("seed = 1", "seed = 1.5", "scene.toml: seed = 1.5: Input should be a valid integer"),
        (
            'kind = "rectangle"',
            'kind = "hexagon"',
            "scene.toml: domain.kind = \"hexagon\": Input should be 'rectangle', 'periodic', "
            "'polygon', 'circle', 'box', 'periodic-box' or 'cylinder'",
        ),
        (
            "center = [0.0, 0.0]",
            "center = [0.0, nan]",
            "scene.toml: domain.center.1 = nan: Input should be a finite number",
        ),
        (
            'interference = "exact"',
            'interference = "exakt"',
            "scene.toml: insertion.interference = \"exakt\": Input should be 'exact' or 'tau'",
        ),
        (
            "analyses = []",
            'analyses = ["rdf"]',
            "scene.toml: outputs.analyses.0: unknown analysis kind 'rdf'; known kinds: (none)",
        ),
        (
            'count = "auto"',
            "count = ",
            "scene.toml: invalid TOML: Invalid value (at line 4, column 9)",
        ),
    ],
)
def test_bad_scene_values_give_one_line(scene_file, registry, old, new, expected):
    assert error_of(scene_file(old, new), registry) == expected


def test_missing_section_is_named(scene_file, registry):
    msg = error_of(scene_file("[density]\nkind", "[densities]\nkind"), registry)
    assert msg.startswith("scene.toml: density: Field required (and 1 more error")


def test_override_errors_name_the_option(registry):
    assert (
        error_of("small", registry, ["density.eta=-3"])
        == "--set: density.eta = -3: Input should be greater than or equal to 0"
    )
    assert (
        error_of("small", registry, ["phases.2.shape.psi=0"])
        == "--set: phases.2.shape.psi = 0: Input should be greater than 0"
    )
    assert (
        error_of("small", registry, ["size.kind=chang5"])
        == "--set: size.kind: unknown size kind 'chang5'; did you mean 'change5'? "
        "known kinds: change5"
    )
    assert (
        error_of("small", registry, seed=-1)
        == "--seed: seed = -1: Input should be greater than or equal to 0"
    )


PLAIN = (
    "an output is a plain file name inside the run folder (not empty, no '/', '\\' or ':', "
    "not '.' or '..', no control characters)"
)


@pytest.mark.parametrize(
    ("value", "problem"),
    [
        ('"../x.npz"', "contains '/'"),
        ('"/tmp/x.npz"', "contains '/'"),
        ('"data/p.npz"', "contains '/'"),
        ('"..\\\\x.npz"', "contains '\\'"),
        ('"C:x.npz"', "contains ':'"),
        ('"."', "is '.'"),
        ('".."', "is '..'"),
        ('"a\\u0000b"', "contains a control character"),
        ('"a\\nb"', "contains a control character"),
    ],
)
@pytest.mark.parametrize("field", ["packing", "summary"])
def test_output_names_are_plain_file_names(registry, field, value, problem):
    assert error_of("small", registry, [f"outputs.{field}={value}"]) == (
        f"--set: outputs.{field} = {value}: {problem}; {PLAIN}"
    )


def test_an_empty_output_name_is_refused(registry):
    assert error_of("small", registry, ['outputs.packing=""']) == (
        '--set: outputs.packing = "": String should have at least 1 character'
    )


def test_a_bad_output_name_in_a_file_names_the_file(scene_file, registry):
    path = scene_file('packing = "packing.npz"', 'packing = "../../x.npz"')
    assert error_of(path, registry) == (
        f"scene.toml: outputs.packing = \"../../x.npz\": contains '/'; {PLAIN}"
    )


@pytest.mark.parametrize(
    ("value", "problem"),
    [
        ('"../../X"', "contains '/'"),
        ('".."', "is '..'"),
        ('"a\\tb"', "contains a control character"),
    ],
)
def test_scene_names_are_plain_folder_names(registry, value, problem):
    msg = error_of("small", registry, [f"name={value}"])
    assert msg.startswith(f"--set: name = {value}: ")
    assert f"{problem}; the scene name is used in the output folder runs/<name>-seed<seed>" in msg


def output_registry():
    """The fake plugins with the built-in exporters and analyzers."""
    from fakes import fake_registry

    import regopack.plugins.analyzers
    import regopack.plugins.exporters

    return fake_registry(regopack.plugins.exporters, regopack.plugins.analyzers)


@pytest.mark.parametrize(
    ("overrides", "expected"),
    [
        (
            ["outputs.summary=packing.npz"],
            '--set: outputs.summary = "packing.npz": the same path as outputs.packing '
            '("packing.npz")',
        ),
        (
            ["outputs.summary=PACKING.npz"],
            '--set: outputs.summary = "PACKING.npz": the same path (on a case-insensitive '
            'file system) as outputs.packing ("packing.npz")',
        ),
        (
            ["outputs.packing=analysis", 'outputs.analyses=["density"]'],
            '--set: outputs.packing = "analysis": the same path as the analysis folder '
            '"analysis" of outputs.analyses',
        ),
        (
            ['outputs.exports=["svg", {kind = "svg", width_px = 400}]'],
            "--set: outputs.exports.1: writes packing.svg, the same path as "
            "outputs.exports.0 (svg), which writes packing.svg",
        ),
        (
            ["outputs.packing=p.vtp", 'outputs.exports=["vtk"]'],
            '--set: outputs.exports.0 = "vtk": writes p.vtp, the same path as outputs.packing '
            '("p.vtp")',
        ),
        (
            ["outputs.summary=packing_meta.json", 'outputs.exports=["csv"]'],
            '--set: outputs.exports.0 = "csv": writes packing_meta.json, the same path as '
            'outputs.summary ("packing_meta.json")',
        ),
        (
            ["outputs.summary=.regopack"],
            '--set: outputs.summary = ".regopack": the same path as regopack\'s marker file '
            ".regopack",
        ),
    ],
)
def test_two_outputs_of_a_run_are_never_one_path(overrides, expected):
    msg = error_of("small", output_registry(), overrides)
    assert msg == expected + "; every output of a run needs its own name"


def test_outputs_with_their_own_names_resolve():
    from regopack.scenes.model import output_files

    resolved = resolve_scene(
        load_scene("small", ['outputs.analyses=["density"]', 'outputs.exports=["csv", "vtk"]']),
        output_registry(),
    )
    assert output_files(resolved) == {
        "outputs.analyses": ["analysis"],
        "outputs.packing": ["packing.npz"],
        "outputs.summary": ["summary.json"],
        "outputs.exports.0": ["packing.csv", "packing_vertices.csv", "packing_meta.json"],
        "outputs.exports.1": ["packing.vtp"],
    }


def test_builtin_errors_name_the_builtin_file(registry):
    # a value the plugin's model rejects, in a built-in scene, via a scene dict
    data = tomllib.loads(load_builtin_text("small"))
    data["phases"][4]["shape"]["m"] = 2
    scene = scene_from_dict(data, source="small.toml")
    with pytest.raises(ConfigError) as info:
        resolve_scene(scene, registry)
    assert str(info.value) == (
        "small.toml: phases.4.shape.m = 2: Input should be greater than or equal to 3"
    )


def test_scene_without_source_has_no_prefix(registry):
    data = tomllib.loads(load_builtin_text("small"))
    data["density"]["eta"] = -1
    with pytest.raises(ConfigError) as info:
        resolve_scene(scene_from_dict(data), registry)
    assert str(info.value) == "density.eta = -1: Input should be greater than or equal to 0"


# -- resolution --------------------------------------------------------------------


def test_resolved_dict_has_all_defaults_and_round_trips(registry):
    data = tomllib.loads(load_builtin_text("small"))
    del data["insertion"]["tau"]
    del data["outputs"]
    del data["domain"]
    resolved = resolve_scene(scene_from_dict(data), registry)
    d = resolved.to_dict()
    assert d["insertion"]["tau"] == 0.65
    assert d["insertion"]["fail_after"] is None
    assert d["domain"] == {"kind": "rectangle", "width": 800.0, "height": 800.0, "center": [0, 0]}
    assert d["outputs"] == {
        "packing": "packing.npz",
        "summary": "summary.json",
        "analyses": [],
        "exports": [],
    }
    text = resolved.to_toml()
    back = tomllib.loads(text)
    # None values are left out of TOML; the model default fills them again
    assert "fail_after" not in back["insertion"]
    again = resolve_scene(scene_from_dict(back), registry)
    assert again.to_dict() == d


def test_resolved_scene_properties(registry):
    resolved = resolve_scene(load_scene("small"), registry)
    assert resolved.name == "small"
    assert resolved.seed == 1
    assert resolved.domain.bounds().tolist() == [-100, 100, -100, 100]
    assert resolved.phase_names == tuple(p[0] for p in TABLE1_PHASES)
    np.testing.assert_allclose(resolved.fractions.sum(), 1.0)


def test_plugin_ref_params():
    ref = PluginRef(kind="eta", eta=3, other="x")
    assert ref.params == {"eta": 3, "other": "x"}
    assert PluginRef(kind="eta").params == {}


@pytest.mark.parametrize("model", [Domain, PluginRef, Phase, Outputs, Scene])
def test_every_field_is_described(model: type[BaseModel]):
    for name, field in model.model_fields.items():
        assert field.description, f"{model.__name__}.{name} has no description"


@pytest.mark.parametrize("model", [Domain, Phase, Outputs, Scene])
def test_models_forbid_extra_keys(model: type[BaseModel]):
    assert model.model_config.get("extra") == "forbid"


# -- TOML writer -------------------------------------------------------------------


def test_toml_writer_handles_our_shapes():
    data = {
        "name": 'a "quoted"\tname\u0001\\',
        "n": 3,
        "flag": False,
        "x": 1e-300,
        "big": 1e300,
        "nan": math.nan,
        "inf": -math.inf,
        "empty": [],
        "list": [1, 2.5, "s"],
        "table": {"k": 1, "sub": {"deep": "v"}, "odd key": 2},
        "array": [{"a": 1, "shape": {"kind": "x", "v": [1, 2]}}, {"a": 2, "shape": {}}],
        "after": {"z": True},
        "none": None,
    }
    back = tomllib.loads(_toml.dumps(data))
    assert math.isnan(back.pop("nan"))
    expected = {k: v for k, v in data.items() if k not in ("nan", "none")}
    assert back == expected


scalars = st.one_of(
    st.text(),
    st.integers(min_value=-(2**63), max_value=2**63 - 1),
    st.floats(allow_nan=False),
    st.booleans(),
)
keys = st.text(min_size=1, max_size=8)


@settings(deadline=None, suppress_health_check=[HealthCheck.too_slow])
@given(
    st.dictionaries(
        keys,
        st.one_of(
            scalars,
            st.lists(scalars, max_size=3),
            st.dictionaries(keys, scalars, max_size=3),
            st.lists(
                st.dictionaries(keys, scalars, min_size=1, max_size=3), min_size=1, max_size=2
            ),
        ),
        max_size=5,
    )
)
def test_toml_writer_round_trips(data):
    assert tomllib.loads(_toml.dumps(data)) == data


def test_with_takes_the_seed_and_registry_of_scene():
    """``ResolvedScene.with_`` takes ``seed`` and ``registry`` as :func:`regopack.scene` does."""
    import regopack
    from regopack.registry.manager import default_registry

    base = regopack.scene("small")
    assert base.with_(seed=None).seed == base.seed
    registry = default_registry()
    changed = base.with_(registry=registry, seed=7, count=30)
    assert changed.registry is registry
    assert (changed.seed, changed.scene.count) == (7, 30)
    assert changed.scene.origin("seed") == "scene(seed=...)"
    with pytest.raises(
        ConfigError, match=r"^registry: expected a regopack.registry.manager.Registry"
    ):
        base.with_(registry=3)
