"""End-to-end checks with the built-in plugins (skipped while they are missing)."""

from __future__ import annotations

import json
import tomllib

import pytest

pytest.importorskip("regopack.plugins.available_arc")

from regopack.cli import main
from regopack.manager import default_registry
from regopack.packing import load
from regopack.scene import load_scene, resolve_scene
from regopack.testing import assert_valid_packing


def test_default_registry_has_the_builtins():
    reg = default_registry(autoload=False)
    assert reg.names("size") == ["change5"]
    assert reg.names("shape") == ["octagon"]
    assert reg.names("insertion") == ["available-arc"]
    assert reg.names("density") == ["eta"]
    assert reg.origin("shape", "octagon") == "regopack.plugins.octagon"
    assert default_registry(autoload=False) is not reg


def test_builtin_scenes_resolve():
    reg = default_registry(autoload=False)
    for name in ("table1", "small"):
        resolve_scene(load_scene(name), reg)


def test_config_prints_the_default_scene(capsys):
    assert main(["config"]) == 0
    data = tomllib.loads(capsys.readouterr().out)
    expected = resolve_scene(load_scene(None), default_registry()).to_dict()
    assert data == expected


def test_run_small_end_to_end(tmp_path, capsys):
    out = tmp_path / "out"
    assert main(["run", "small", "--set", "count=300", "--out", str(out), "--quiet"]) == 0
    packing = load(out / "packing.npz")
    summary = json.loads((out / "summary.json").read_text())
    assert summary["tried"] == 300
    assert summary["placed"] == packing.n_placed > 0
    assert_valid_packing(packing)
    assert main(["verify", str(out / "packing.npz")]) == 0
