"""Error lines name where the bad value came from and suggest the field that was meant."""

from __future__ import annotations

import pytest
from cli_helpers import one_error_line

from regopack.base.messages import closest, fields_at
from regopack.cli import main
from regopack.packing.core import save
from regopack.registry.manager import default_registry
from regopack.scenes.model import Domain, Scene
from regopack.testing import packing_from_polygons

SCENE_FIELDS = (
    "name, seed, count, length_unit, domain, size, phases, insertion, density, outputs, tiles"
)


def test_a_misspelt_section_in_set_names_set_and_the_closest_field(capsys):
    assert main(["config", "small", "--set", "domian.width=300"]) == 2
    assert one_error_line(capsys) == (
        "regopack: error: --set: domian: unknown field; did you mean 'domain'? "
        f"allowed: {SCENE_FIELDS}"
    )


@pytest.mark.parametrize(
    ("override", "expected"),
    [
        ("domain.hieght=3", "--set: domain.hieght = 3: unknown field; did you mean 'height'?"),
        ("size.d_minn=5", "--set: size.d_minn = 5: unknown field; did you mean 'd_min'? "
         "allowed: kind, d_min, d_max, d0, alpha"),
        ("phases.0.shape.psii=3", "--set: phases.0.shape.psii = 3: unknown field; "
         "did you mean 'psi'? allowed: kind, psi, a, m"),
        ("phases.0.nme=3", "--set: phases.0.nme = 3: unknown field; did you mean 'name'?"),
        ("density.foo=3", "--set: density.foo = 3: unknown field; allowed: kind, eta"),
        ("size.kind=chang5", "--set: size.kind: unknown size kind 'chang5'; "
         "did you mean 'change5'?"),
    ],
)  # fmt: skip
def test_misspelt_fields_get_a_suggestion(capsys, override, expected):
    assert main(["config", "small", "--set", override]) == 2
    assert one_error_line(capsys).startswith(f"regopack: error: {expected}")


def test_a_value_that_set_makes_inconsistent_names_set_not_the_file(capsys):
    assert main(["config", "small", "--set", "size.d_min=50"]) == 2
    line = one_error_line(capsys)
    assert line.startswith("regopack: error: --set: size: ")
    assert "d_min (50.0)" in line and "small.toml" not in line


def test_a_mistake_of_the_file_names_the_file_beside_an_unrelated_set(tmp_path, capsys):
    text = main_scene_text().replace("d_max = 40.0", "d_max = 1.0")
    (tmp_path / "bad.toml").write_text(text, encoding="utf-8")
    assert main(["config", str(tmp_path / "bad.toml"), "--set", "density.eta=5"]) == 2
    line = one_error_line(capsys)
    assert line.startswith(f"regopack: error: {tmp_path / 'bad.toml'}: size: ")


def main_scene_text() -> str:
    from importlib import resources

    return resources.files("regopack.scenes").joinpath("small.toml").read_text(encoding="utf-8")


def test_a_bad_exporter_parameter_names_the_exporter_and_its_parameters(tmp_path, capsys):
    path = tmp_path / "p.npz"
    save(packing_from_polygons([[(0, 0), (1, 0), (1, 1), (0, 1)]]), path)
    assert main(["export", str(path), "--to", "lammps", "--set", "stiffnes=1"]) == 2
    line = one_error_line(capsys)
    assert line.startswith(
        "regopack: error: --set: exporter 'lammps': stiffnes = 1: unknown field; "
        "did you mean 'stiffness'? allowed: units, length_scale, density, "
    )
    assert not list(tmp_path.glob("p.*data"))


def test_the_exporter_names_the_source_of_its_parameters():
    from regopack.base.errors import ConfigError
    from regopack.exports.pipeline import build_exporter

    with pytest.raises(ConfigError) as info:
        build_exporter(default_registry(), "svg", {"width_px": -1}, source="--set")
    assert str(info.value).startswith("--set: exporter 'svg': width_px = -1: ")


def test_closest():
    assert closest("domian", ["name", "domain", "density"]) == "domain"
    assert closest("ETA", ["eta", "kind"]) == "eta"
    assert closest("zzz", ["eta", "kind"]) is None


def test_fields_at_walks_lists_and_sections():
    assert fields_at(Scene, ()) == SCENE_FIELDS.split(", ")
    assert fields_at(Scene, ("domain",)) == list(Domain.model_fields)
    assert fields_at(Scene, ("phases", 0)) == ["name", "fraction", "shape"]
    assert fields_at(Scene, ("size",)) == ["kind"]  # a plugin's section: its own model
    assert fields_at(Scene, ("nothing",)) is None


def test_a_set_in_the_same_table_is_not_blamed_for_the_file(tmp_path, capsys):
    text = main_scene_text().replace("d_max = 40.0", "d_max = 1.0")
    (tmp_path / "bad.toml").write_text(text, encoding="utf-8")
    assert main(["config", str(tmp_path / "bad.toml"), "--set", "size.alpha=6"]) == 2
    line = one_error_line(capsys)
    assert line.startswith(f"regopack: error: {tmp_path / 'bad.toml'}: size: ")


@pytest.mark.parametrize("extra", ["gsd", "dask"])
def test_install_hints_work_from_a_clone(extra):
    """``pip install regopack[gsd]`` needs regopack on an index; a clone installs '.[gsd]'."""
    from regopack.base.messages import install_hint

    hint = install_hint(extra)
    assert "regopack[" not in hint
    assert hint.endswith(f"pip install '.[{extra}]' in regopack's source folder")
    assert hint.startswith("pip install '") and ">=" in hint  # the extra's own requirement


def test_no_message_names_an_extra_as_if_regopack_were_on_an_index():
    from pathlib import Path

    import regopack

    root = Path(regopack.__file__).parent
    offenders = [
        str(path.relative_to(root))
        for path in root.rglob("*.py")
        if "install regopack[" in path.read_text(encoding="utf-8")
        or "install 'regopack[" in path.read_text(encoding="utf-8")
    ]
    assert offenders == []


SAMPLED_FIELDS = [
    "seed", "count", "domain.width", "domain.center", "size.d_min", "size.d0", "size.alpha",
    "phases.0.name", "phases.2.fraction", "phases.1.shape.psi", "phases.3.shape.m",
    "insertion.t", "insertion.tau", "insertion.zone", "insertion.first", "density.eta",
    "outputs.analyses",
]  # fmt: skip
SAMPLED_VALUES = ["-1", "1e300", '"x"', "3.5", "[]"]


def test_every_sampled_scene_error_names_its_source(tmp_path, monkeypatch, capsys):
    """Bad values over the scene's fields, by --set and in a file: each error names where."""
    import tomllib

    from regopack.base import toml as _toml

    monkeypatch.chdir(tmp_path)
    text = main_scene_text()
    unnamed = []
    for field in SAMPLED_FIELDS:
        for value in SAMPLED_VALUES:
            if main(["config", "small", "--set", f"{field}={value}"]) != 0:
                line = one_error_line(capsys)
                if not line.startswith("regopack: error: --set"):
                    unnamed.append(line)
            capsys.readouterr()
            data = tomllib.loads(text)
            *head, last = field.split(".")
            table = data
            for part in head:
                table = table[int(part)] if isinstance(table, list) else table[part]
            table[last] = tomllib.loads(f"v = {value}")["v"]
            (tmp_path / "s.toml").write_text(_toml.dumps(data), encoding="utf-8")
            if main(["config", "s.toml"]) != 0:
                line = one_error_line(capsys)
                if not line.startswith("regopack: error: s.toml: "):
                    unnamed.append(line)
            capsys.readouterr()
    assert unnamed == []


def test_a_box_set_too_small_names_set_not_the_scene(capsys):
    assert main(["config", "table1-3d", "--set", "domain.width=1e-300"]) == 2
    assert one_error_line(capsys).startswith(
        "regopack: error: --set: domain: the smallest particle (diameter 2, volume 4.18879) is "
        "larger than the domain (volume 2.25e-296)"
    )
