"""The example files of the documentation are the ones the pages show, and they work."""

from __future__ import annotations

import re
from pathlib import Path

import pytest

from regopack.experiments import expand, load_experiment
from regopack.registry.manager import default_registry
from regopack.run.pipeline import default_out_dir, run_scene
from regopack.scenes.model import builtin_scenes, load_scene, resolve_scene

ROOT = Path(__file__).resolve().parents[1]
EXAMPLES = ROOT / "docs" / "examples"
TOML_BLOCK = re.compile(r"^```toml\n(.*?)^```", re.S | re.M)


def toml_blocks(page: Path) -> list[str]:
    return TOML_BLOCK.findall(page.read_text(encoding="utf-8"))


def test_the_readme_scene_is_the_example_file_and_is_valid():
    text = (EXAMPLES / "strip.toml").read_text(encoding="utf-8")
    assert text in toml_blocks(ROOT / "README.md")
    readme = (ROOT / "README.md").read_text(encoding="utf-8")
    assert "docs/examples/strip.toml" in readme and "my-experiment.toml" not in readme
    scene = resolve_scene(load_scene(EXAMPLES / "strip.toml"), default_registry())
    assert scene.name == "strip" and scene.seed == 42


def test_the_sweep_howto_experiment_is_the_example_file():
    text = (EXAMPLES / "eta-seeds.toml").read_text(encoding="utf-8")
    assert text in toml_blocks(ROOT / "docs" / "how-to" / "run-a-sweep.md")
    readme = (ROOT / "README.md").read_text(encoding="utf-8")
    assert "regopack sweep docs/examples/eta-seeds.toml" in readme


def test_the_sweep_example_varies_phi_with_eta_and_n_with_the_size():
    """The particle count is not fixed: φ follows η and N follows the domain."""
    runs = expand(load_experiment(EXAMPLES / "eta-seeds.toml"))
    assert len(runs) == 27
    assert not any(o.startswith("count=") for run in runs for o in run.overrides)
    registry = default_registry()

    def outcome(eta: int, width: int):
        [run] = [
            r
            for r in runs
            if r.params["density.eta"] == eta
            and r.params["seed"] == 1
            and r.params["domain.width"] == width
        ]
        return run_scene(resolve_scene(load_scene("small", list(run.overrides)), registry))

    phi = {eta: outcome(eta, 100).summary["phi_domain"] for eta in (0, 20)}
    assert phi[0] > phi[20] + 0.01
    placed = [outcome(0, width).summary["placed"] for width in (100, 200)]
    assert placed[1] > 3 * placed[0]


def test_the_export_howto_reads_the_folders_that_its_commands_write():
    """`regopack run table1` writes runs/table1-seed<its seed>: the paths must match."""
    page = ROOT / "docs" / "how-to" / "export-to-dem-and-viewers.md"
    text = page.read_text(encoding="utf-8")
    assert "--seed" not in text
    used = set(re.findall(r"runs/([a-z0-9_]+)-seed(\d+)", text))
    assert used
    for name, seed in used:
        assert name in builtin_scenes()
        expected = default_out_dir(resolve_scene(load_scene(name), default_registry()))
        assert Path(f"runs/{name}-seed{seed}") == expected


@pytest.mark.parametrize("page", ["README.md", "docs/tutorial/first-packing.md"])
def test_pages_give_the_default_folder_of_the_default_scene(page):
    default = default_out_dir(resolve_scene(load_scene(None), default_registry()))
    assert default.as_posix() in (ROOT / page).read_text(encoding="utf-8")
