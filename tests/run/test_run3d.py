"""The 3D run path: draw, insert (a lattice stand-in), measure, verify and write the folder."""

from __future__ import annotations

import json
import math
from collections.abc import Iterable

import numpy as np
import pydantic
import pytest
from fakes import PythonDensity

import regopack
from regopack.base.errors import ConfigError
from regopack.geometry.domain import Box
from regopack.packing.core import Packing, load
from regopack.packing.solid_fraction import phi_in_box
from regopack.registry.hookspecs import hookimpl
from regopack.registry.interfaces import InsertionResult, InsertionStrategy
from regopack.registry.plugin_types import InserterSpec
from regopack.testing import make_registry

SCENE = {
    "name": "lattice3d",
    "seed": 4,
    "count": 40,
    "domain": {"kind": "box", "width": 60.0, "height": 40.0, "depth": 50.0},
    "size": {"kind": "uniform", "d_min": 4.0, "d_max": 8.0},
    "phases": [
        {"name": "pyroxene", "fraction": 0.6, "shape": {"kind": "polyhedron", "psi": 0.5}},
        {"name": "glass", "fraction": 0.4, "shape": {"kind": "polyhedron", "directions": "cube"}},
    ],
    "insertion": {"kind": "lattice3d"},
    "density": {"kind": "eta"},
}


class _Config(pydantic.BaseModel):
    model_config = pydantic.ConfigDict(extra="forbid")
    spacing: float = pydantic.Field(0.0, description="lattice spacing (0: touching spheres)")


class Lattice3D(InsertionStrategy):
    """Places solids on a cubic lattice of cells wide enough for the largest one."""

    def __init__(self, config: _Config) -> None:
        self.spacing = config.spacing

    def pack(self, population, domain, controller, rng, progress=None):  # type: ignore[no-untyped-def]
        n = len(population)
        cell = self.spacing or 2.0 * float(population.shapes.circumradius.max())
        counts = [int(s // cell) for s in domain.size]
        centre = np.full((n, 3), np.nan)
        index = np.full(n, -1, dtype=np.int64)
        lo = np.array([domain.xmin, domain.ymin, domain.zmin])
        for i in range(min(n, math.prod(counts))):
            cx, rest = divmod(i, counts[1] * counts[2])
            cy, cz = divmod(rest, counts[2])
            centre[i] = lo + (np.array([cx, cy, cz]) + 0.5) * cell
            index[i] = i
        return InsertionResult(centre, index, {"cells": float(math.prod(counts))})


class _Plugin:
    @hookimpl
    def regopack_inserters(self) -> Iterable[InserterSpec]:
        return [
            InserterSpec(name="lattice3d", config_model=_Config, factory=Lattice3D, dimensions=(3,))
        ]


@pytest.fixture
def registry():  # type: ignore[no-untyped-def]
    return make_registry(_Plugin())


def test_a_3d_scene_runs_and_writes_a_version_3_packing(tmp_path, registry) -> None:  # type: ignore[no-untyped-def]
    scene = regopack.scene(SCENE, registry=registry)
    outcome = regopack.pack_and_summarise(scene, out=tmp_path / "run", verify=True)
    packing = outcome.packing
    assert packing.dimension == 3
    summary = json.loads((tmp_path / "run" / "summary.json").read_text())
    assert summary["dimension"] == 3 and summary["tried"] == 40
    assert summary["placed"] == packing.n_placed > 0
    assert summary["phi_domain"] == pytest.approx(packing.phi)
    assert summary["verify"] == {"ok": True, "overlap_pairs": 0, "worst_overlap": 0.0, "outside": 0}
    rows = summary.get("not_placed_by_class", [])
    assert sum(r["not_placed"] for r in rows) == summary["not_placed"]
    assert all(r["d_lo"] < r["d_hi"] and r["placed"] + r["not_placed"] == r["drawn"] for r in rows)
    back = load(tmp_path / "run" / "packing.npz")
    assert back.dimension == 3
    assert np.array_equal(back.vertices, packing.vertices)
    # same scene and seed: the same solids, bit for bit
    again = regopack.pack(scene)
    assert again.dimension == 3
    assert np.array_equal(again.vertices, packing.vertices)
    assert np.array_equal(again.rotation, packing.rotation)


def test_overlaps_are_reported_by_the_oracle(registry) -> None:  # type: ignore[no-untyped-def]
    scene = regopack.scene(SCENE, registry=registry, insertion__spacing=3.0)
    outcome = regopack.pack_and_summarise(scene, verify=True)
    assert outcome.summary["verify"]["ok"] is False
    assert outcome.summary["verify"]["overlap_pairs"] > 0


def test_count_auto_uses_the_mean_volume(registry) -> None:  # type: ignore[no-untyped-def]
    scene = regopack.scene(SCENE, registry=registry, count="auto")
    packing = regopack.pack(scene, verify=False)
    mean = math.pi / 6 * (8.0**4 - 4.0**4) / (4 * 4.0)  # E[d^3] of the uniform 4..8
    assert packing.n_particles == round(60.0 * 40.0 * 50.0 / mean)


def test_a_2d_analyzer_in_a_3d_scene_is_refused_before_packing(registry) -> None:  # type: ignore[no-untyped-def]
    analyses = {"analyses": ["local_fraction"]}
    scene = regopack.scene({**SCENE, "outputs": analyses}, registry=registry)
    with pytest.raises(ConfigError) as err:
        regopack.pack(scene)
    text = str(err.value)
    assert text.startswith(
        "scene dictionary: outputs.analyses: analyzer 'local_fraction' analyses 2D"
    )
    assert "density" in text and "contacts" in text and "\n" not in text
    assert "density3d" not in text  # the old names are not listed


def test_config_refuses_what_run_refuses(capsys) -> None:  # type: ignore[no-untyped-def]
    # `regopack config` runs every check of `regopack run`, the analyzers' dimension too
    from regopack.cli import main

    argv = ["config", "table1-3d", "--set", 'outputs.analyses=["local_fraction"]']
    assert main(argv) == 2
    err = capsys.readouterr().err.strip()
    assert err.startswith(
        "regopack: error: --set: outputs.analyses: analyzer 'local_fraction' analyses 2D packings"
    )
    assert "\n" not in err


def _cube_packing(centres: list[list[float]], half: float) -> Packing:
    from packings3d import cube_packing

    return cube_packing(centres, half)


def test_phi_in_a_window_clips_exactly() -> None:
    # a unit cube at the centre of a 10-box, a window cutting it in half and in a quarter
    p = _cube_packing([[5.0, 5.0, 5.0]], 0.5)
    assert phi_in_box(p, Box(0, 10, 0, 10, 0, 10)) == pytest.approx(1e-3)
    assert phi_in_box(p, Box(5, 10, 0, 10, 0, 10)) == pytest.approx(0.5 / 500)
    assert phi_in_box(p, Box(5, 10, 5, 10, 0, 10)) == pytest.approx(0.25 / 250)
    assert phi_in_box(p, Box(5.25, 10, 5, 10, 4.75, 5.75)) == pytest.approx(
        (0.25 * 0.5 * 0.75) / (4.75 * 5 * 1.0)
    )
    assert phi_in_box(p, Box(6, 10, 0, 10, 0, 10)) == 0.0


def test_phi_of_rotated_polyhedra_cut_by_a_window_corner_matches_sampling() -> None:
    from packings3d import cube_packing

    from regopack.plugins.shapes.polyhedra.shape import PolyhedronConfig, RandomPolyhedron

    batch = RandomPolyhedron(PolyhedronConfig(psi=0.3)).generate(
        np.array([1.0, 1.3]), np.random.default_rng(8)
    )
    base = cube_packing([[0, 0, 0], [0, 0, 0]], 0.5)
    centres = np.array([[5.0, 5.0, 5.0], [2.0, 7.5, 5.2]])
    p = Packing(
        **{
            **{k: getattr(base, k) for k in ("radius", "mineral", "mineral_names", "domain")},
            "vertices": batch.vertices,
            "offsets": batch.offsets,
            "face_vertices": batch.face_vertices,
            "face_vertex_offsets": batch.face_vertex_offsets,
            "face_offsets": batch.face_offsets,
            "normals": batch.normals,
            "support": batch.support,
            "rotation": batch.rotation,
            "centre": centres,
            "insertion_index": np.array([0, 1]),
        }
    )
    window = Box(4.6, 9.0, 1.0, 5.3, 4.8, 9.0)
    rng = np.random.default_rng(0)
    pts = rng.uniform([4.6, 1.0, 4.8], [9.0, 5.3, 9.0], size=(400_000, 3))
    inside = np.zeros(len(pts), dtype=bool)
    for j in range(2):
        f0, f1 = batch.face_offsets[j], batch.face_offsets[j + 1]
        rel = pts - centres[j]
        inside |= np.all(rel @ batch.normals[f0:f1].T <= batch.support[f0:f1], axis=1)
    frac = inside.mean()
    se = math.sqrt(frac * (1 - frac) / len(pts))
    assert 0.0 < frac and abs(phi_in_box(p, window) - frac) < 5 * se


def test_regopack_verify_checks_3d_packing_files(tmp_path, capsys) -> None:  # type: ignore[no-untyped-def]
    from packings3d import cube_packing

    from regopack.cli.commands import EXIT_OK, EXIT_VIOLATED, main
    from regopack.packing.core import save

    save(cube_packing([[1, 1, 1], [2, 1, 1]], 0.5), tmp_path / "ok.npz")
    assert main(["verify", str(tmp_path / "ok.npz")]) == EXIT_OK
    save(cube_packing([[1, 1, 1], [1.9, 1, 1]], 0.5), tmp_path / "bad.npz")
    assert main(["verify", str(tmp_path / "bad.npz")]) == EXIT_VIOLATED
    text = capsys.readouterr().out
    assert "overlap" in text
    report = regopack.verify(tmp_path / "bad.npz")
    assert not report and report.worst_overlap_fraction == pytest.approx(0.1)


SURFACE_SCENE = """\
name = "s3"
seed = 1
count = 10
[domain]
kind = "box"
width = 40.0
height = 40.0
depth = 40.0
[size]
kind = "monodisperse"
d = 4.0
[[phases]]
name = "glass"
fraction = 1.0
shape = { kind = "polyhedron" }
[insertion]
kind = "available-surface"
[density]
kind = "eta"
"""


@pytest.mark.parametrize(
    ("d", "message"), [(1e-110, "underflows 64-bit floats"), (1e110, "overflows 64-bit floats")]
)
def test_sizes_beyond_64_bit_volumes_are_refused_in_one_line(
    tmp_path, d: float, message: str
) -> None:  # type: ignore[no-untyped-def]
    (tmp_path / "s3.toml").write_text(SURFACE_SCENE, encoding="utf-8")
    with pytest.raises(ConfigError, match=message) as err:
        regopack.pack(tmp_path / "s3.toml", size={"kind": "monodisperse", "d": d})
    assert "\n" not in str(err.value)


def test_a_sweep_of_a_3d_scene_is_refused_before_it_runs(tmp_path, monkeypatch) -> None:  # type: ignore[no-untyped-def]
    from regopack.experiments import check_runs, load_experiment

    monkeypatch.chdir(tmp_path)
    (tmp_path / "s3.toml").write_text(SURFACE_SCENE, encoding="utf-8")
    (tmp_path / "exp.toml").write_text(
        'base = "s3.toml"\n[sweep]\nseed = [1, 2]\n', encoding="utf-8"
    )
    with pytest.raises(ConfigError, match=r"the scene is 3D .* sweeps run 2D scenes only"):
        check_runs(load_experiment("exp.toml"))


def test_a_real_3d_scene_runs_from_the_command_line(tmp_path, capsys) -> None:  # type: ignore[no-untyped-def]
    from regopack.cli.commands import EXIT_OK, main

    (tmp_path / "s3.toml").write_text(SURFACE_SCENE, encoding="utf-8")
    assert (
        main(["run", str(tmp_path / "s3.toml"), "--out", str(tmp_path / "run"), "--quiet"])
        == EXIT_OK
    )
    summary = json.loads((tmp_path / "run" / "summary.json").read_text())
    assert summary["placed"] == 10 and summary["verify"]["ok"] is True
    assert main(["verify", str(tmp_path / "run" / "packing.npz")]) == EXIT_OK


def test_what_available_surface_cannot_pack_is_refused_before_drawing(tmp_path) -> None:  # type: ignore[no-untyped-def]
    (tmp_path / "s3.toml").write_text(SURFACE_SCENE, encoding="utf-8")
    registry = make_registry(PythonDensity())
    base = regopack.scene(tmp_path / "s3.toml", registry=registry)
    with pytest.raises(ConfigError) as err:
        regopack.pack(regopack.scene(base, density={"kind": "half"}, registry=registry))
    assert str(err.value).endswith(
        "density.kind: 'half' is not the built-in 'eta' density controller, which "
        "insertion 'available-surface' needs"
    )
    phases = [
        {"name": "glass", "fraction": 0.5, "shape": {"kind": "polyhedron"}},
        {"name": "beads", "fraction": 0.5, "shape": {"kind": "sphere"}},
    ]
    with pytest.raises(ConfigError) as err:
        regopack.pack(regopack.scene(base, phases=phases, registry=registry))
    text = str(err.value)
    assert "phases.1.shape.kind: 'sphere' beside 'polyhedron' in phase 0" in text
    assert "\n" not in text


@pytest.mark.parametrize(
    ("old", "new"),
    [
        ("run_scene3d", "run_scene"),
        ("RunOutcome3D", "RunOutcome"),
        ("check_scene3d", "check_scene"),
        ("draw_population3d", "draw_population"),
    ],
)
def test_the_former_3d_run_names_give_the_run_of_both_dimensions(old: str, new: str) -> None:
    import regopack.run.pipeline as pipeline

    with pytest.warns(DeprecationWarning, match=f"pipeline.{old} is deprecated.*pipeline.{new}"):
        assert getattr(pipeline, old) is getattr(pipeline, new)
    with pytest.raises(AttributeError, match="has no attribute 'run_scene4d'"):
        pipeline.run_scene4d  # noqa: B018
