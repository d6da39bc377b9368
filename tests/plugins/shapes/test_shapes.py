"""Regular, random convex and template polygons."""

from __future__ import annotations

import json
import math
import warnings
from pathlib import Path

import numpy as np
import pytest
import shapely
from hypothesis import given, settings
from hypothesis import strategies as st
from pydantic import ValidationError
from shapely import affinity

from regopack.base.errors import ConfigError
from regopack.geometry.population import ShapeBatch
from regopack.plugins.shapes.polygons import (
    RandomConvexPolygon,
    RandomPolygonConfig,
    RegularConfig,
    RegularPolygon,
    TemplateConfig,
    TemplateError,
    TemplatePolygon,
    TemplateWarning,
    read_templates,
)
from regopack.registry.manager import default_registry
from regopack.run.pipeline import run_scene
from regopack.scenes.model import load_scene, resolve_scene
from regopack.testing import assert_valid_packing

# an L-shaped (not convex) outline, a clockwise square and a triangle
L_SHAPE = [(0, 0), (2, 0), (2, 1), (1, 1), (1, 2), (0, 2)]
CW_SQUARE = [(0, 0), (0, 1), (1, 1), (1, 0)]
TRIANGLE = [(0, 0), (3, 0), (0, 1)]


def regular(m: int = 6) -> RegularPolygon:
    return RegularPolygon(RegularConfig(m=m))


def random_polygon(m: int = 8, jitter: float = 0.0) -> RandomConvexPolygon:
    return RandomConvexPolygon(RandomPolygonConfig(m=m, jitter=jitter))


def template(path: Path | str, choice: str = "random") -> TemplatePolygon:
    return TemplatePolygon(TemplateConfig(path=str(path), choice=choice))


def write_csv(path: Path, outlines: dict[str, list[tuple[float, float]]]) -> Path:
    rows = ["id,x,y"] + [f"{i},{x!r},{y!r}" for i, pts in outlines.items() for x, y in pts]
    path.write_text("\n".join(rows) + "\n", encoding="utf-8")
    return path


def write_json(path: Path, outlines: list[list[tuple[float, float]]]) -> Path:
    path.write_text(json.dumps([[list(p) for p in o] for o in outlines]), encoding="utf-8")
    return path


def check_batch(batch: ShapeBatch, radius: np.ndarray) -> None:
    """Area pi r^2, convex, counter-clockwise, no repeated vertices, centre strictly inside."""
    assert len(batch) == len(radius)
    assert batch.orientation.shape == (len(radius),)
    assert np.all(np.isfinite(batch.vertices))
    for j, r in enumerate(radius):
        outline = batch.outline(j)
        assert len(outline) >= 3
        poly = shapely.Polygon(outline)
        assert poly.is_valid
        assert poly.area == pytest.approx(math.pi * r * r, rel=1e-9)
        assert poly.convex_hull.area == pytest.approx(poly.area, rel=1e-9)
        x, y = outline[:, 0], outline[:, 1]
        assert np.sum(x * np.roll(y, -1) - np.roll(x, -1) * y) > 0  # counter-clockwise
        edge = np.hypot(*(np.roll(outline, -1, axis=0) - outline).T)
        assert edge.min() > 0  # no repeated consecutive vertices
        # every turn is to the left (or straight within rounding)
        e = np.roll(outline, -1, axis=0) - outline
        turn = e[:, 0] * np.roll(e[:, 1], -1) - e[:, 1] * np.roll(e[:, 0], -1)
        assert np.all(turn >= -1e-9 * edge * np.roll(edge, -1))
        assert shapely.contains_xy(poly, 0.0, 0.0)
        assert poly.exterior.distance(shapely.Point(0.0, 0.0)) > 1e-12 * r


# ---------------------------------------------------------------------------
# regular


@given(
    m=st.integers(3, 256),
    r=st.floats(1e-6, 1e6),
    seed=st.integers(0, 2**32 - 1),
)
@settings(max_examples=60, deadline=None)
def test_regular_outlines(m: int, r: float, seed: int) -> None:
    radius = np.full(3, r)
    batch = regular(m).generate(radius, np.random.default_rng(seed))
    check_batch(batch, radius)
    for j in range(3):
        outline = batch.outline(j)
        assert len(outline) == m
        d = np.hypot(*outline.T)
        assert d.max() / d.min() == pytest.approx(1.0, abs=1e-12)
        first = math.atan2(outline[0, 1], outline[0, 0]) % (2 * math.pi)
        assert first == pytest.approx(batch.orientation[j], abs=1e-9)


def test_regular_orientation_range() -> None:
    batch = regular(6).generate(np.ones(2000), np.random.default_rng(0))
    assert batch.orientation.min() >= 0.0
    assert batch.orientation.max() < 2 * math.pi / 6
    assert batch.orientation.max() > 0.9 * 2 * math.pi / 6


def test_regular_default_is_hexagon() -> None:
    batch = RegularPolygon(RegularConfig()).generate(np.ones(2), np.random.default_rng(0))
    assert np.diff(batch.offsets).tolist() == [6, 6]


# ---------------------------------------------------------------------------
# random convex polygon


@given(
    m=st.integers(3, 256),
    r=st.floats(1e-6, 1e6),
    jitter=st.one_of(st.just(0.0), st.floats(0.0, 0.999999)),
    seed=st.integers(0, 2**32 - 1),
)
@settings(max_examples=80, deadline=None)
def test_random_polygon_outlines(m: int, r: float, jitter: float, seed: int) -> None:
    radius = np.full(4, r)
    batch = random_polygon(m, jitter).generate(radius, np.random.default_rng(seed))
    check_batch(batch, radius)
    assert np.all(np.diff(batch.offsets) == m)


@pytest.mark.parametrize("m", [3, 256])
@pytest.mark.parametrize("jitter", [0.0, 0.9])
def test_random_polygon_extreme_vertex_counts(m: int, jitter: float) -> None:
    radius = np.geomspace(1e-6, 1e6, 200)
    batch = random_polygon(m, jitter).generate(radius, np.random.default_rng(3))
    check_batch(batch, radius)
    assert np.all(np.diff(batch.offsets) == m)
    # every angular gap between consecutive vertices is below pi
    for j in range(len(batch)):
        ang = np.arctan2(*batch.outline(j)[:, ::-1].T)
        gap = np.diff(np.concatenate([ang, ang[:1]])) % (2 * math.pi)
        assert gap.max() < math.pi
        assert gap.sum() == pytest.approx(2 * math.pi)


def test_random_polygon_without_jitter_lies_on_a_circle() -> None:
    batch = random_polygon(7).generate(np.ones(50), np.random.default_rng(4))
    for j in range(50):
        d = np.hypot(*batch.outline(j).T)
        assert d.max() / d.min() == pytest.approx(1.0, abs=1e-12)


def test_random_polygon_jitter_moves_vertices_inwards() -> None:
    batch = random_polygon(12, 0.9).generate(np.ones(200), np.random.default_rng(5))
    spread = [np.ptp(np.hypot(*batch.outline(j).T)) for j in range(200)]
    assert np.mean(spread) > 0.05


def test_random_polygon_orientation_range() -> None:
    batch = random_polygon(5).generate(np.ones(2000), np.random.default_rng(0))
    assert batch.orientation.min() >= 0.0
    assert batch.orientation.max() < 2 * math.pi
    assert np.ptp(batch.orientation) > 0.9 * 2 * math.pi
    first = np.arctan2(*batch.vertices[batch.offsets[:-1]][:, ::-1].T) % (2 * math.pi)
    diff = (first - batch.orientation + math.pi) % (2 * math.pi) - math.pi
    assert np.allclose(diff, 0.0, atol=1e-9)


# ---------------------------------------------------------------------------
# determinism, empty batches, configs


@pytest.fixture
def mixed_templates(tmp_path: Path) -> Path:
    return write_csv(tmp_path / "t.csv", {"a": TRIANGLE, "b": CW_SQUARE})


@pytest.mark.parametrize("kind", ["regular", "random-polygon", "template"])
def test_same_seed_same_shapes(kind: str, mixed_templates: Path) -> None:
    def make():
        if kind == "regular":
            return regular(5)
        if kind == "random-polygon":
            return random_polygon(3, 0.5)
        return template(mixed_templates)

    radius = np.linspace(1.0, 2.0, 300)
    a = make().generate(radius, np.random.default_rng(9))
    b = make().generate(radius, np.random.default_rng(9))
    c = make().generate(radius, np.random.default_rng(10))
    assert np.array_equal(a.vertices, b.vertices)
    assert np.array_equal(a.offsets, b.offsets)
    assert np.array_equal(a.orientation, b.orientation)
    assert not np.array_equal(a.orientation, c.orientation)


@pytest.mark.parametrize("kind", ["regular", "random-polygon", "template"])
def test_empty_batch(kind: str, mixed_templates: Path) -> None:
    gen = {
        "regular": regular(),
        "random-polygon": random_polygon(),
        "template": template(mixed_templates),
    }[kind]
    batch = gen.generate(np.zeros(0), np.random.default_rng(0))
    assert len(batch) == 0 and batch.vertices.shape == (0, 2)
    assert batch.offsets.tolist() == [0]


@pytest.mark.parametrize(
    ("model", "params"),
    [
        (RegularConfig, {"m": 2}),
        (RegularConfig, {"m": 257}),
        (RegularConfig, {"n": 6}),
        (RandomPolygonConfig, {"m": 2}),
        (RandomPolygonConfig, {"jitter": 1.0}),
        (RandomPolygonConfig, {"jitter": -0.1}),
        (RandomPolygonConfig, {"jitter": float("nan")}),
        (TemplateConfig, {}),
        (TemplateConfig, {"path": ""}),
        (TemplateConfig, {"path": "a.csv", "choice": "first"}),
        (TemplateConfig, {"path": "a.csv", "scale": 1.0}),
    ],
)
def test_bad_configs(model, params) -> None:
    with pytest.raises(ValidationError):
        model.model_validate(params)


def test_shapes_are_registered() -> None:
    names = default_registry(autoload=False).names("shape")
    assert {"regular", "random-polygon", "template"} <= set(names)


# ---------------------------------------------------------------------------
# templates


def test_template_csv(tmp_path: Path) -> None:
    path = write_csv(tmp_path / "t.csv", {"tri": TRIANGLE, "sq": CW_SQUARE})
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        tpl = read_templates(path)
    assert tpl.ids == ("tri", "sq") and tpl.n_convexified == 0
    assert [len(tpl.outline(j)) for j in range(2)] == [3, 4]
    for j in range(2):
        poly = shapely.Polygon(tpl.outline(j))
        assert poly.area == pytest.approx(1.0, rel=1e-12)  # signed: counter-clockwise
        assert shapely.Polygon(tpl.outline(j)).exterior.is_ccw
        c = poly.centroid
        assert abs(c.x) < 1e-12 and abs(c.y) < 1e-12


def test_template_json(tmp_path: Path) -> None:
    path = write_json(tmp_path / "t.json", [TRIANGLE, CW_SQUARE, [(5, 5), (6, 5), (5, 7)]])
    tpl = read_templates(path)
    assert tpl.ids == ("0", "1", "2")
    assert [len(tpl.outline(j)) for j in range(3)] == [3, 4, 3]


def test_template_csv_ignores_blank_lines_and_header_case(tmp_path: Path) -> None:
    path = tmp_path / "t.csv"
    path.write_text("ID, X, Y\n\n7,0,0\n7,1,0\n\n7,0,1\n", encoding="utf-8")
    assert read_templates(path).ids == ("7",)


def test_template_drops_repeated_and_collinear_points(tmp_path: Path) -> None:
    square = [(0, 0), (0.5, 0), (1, 0), (1, 0), (1, 1), (0, 1), (0, 0)]
    path = write_json(tmp_path / "t.json", [square])
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        tpl = read_templates(path)
    assert len(tpl.outline(0)) == 4


def test_non_convex_template_warns_and_is_convexified(tmp_path: Path) -> None:
    path = write_csv(
        tmp_path / "t.csv", {"L": L_SHAPE, "sq": CW_SQUARE, "bow": [(0, 0), (1, 1), (1, 0), (0, 1)]}
    )
    with pytest.warns(TemplateWarning, match=r"t\.csv: 2 of 3 template outlines were not convex"):
        tpl = read_templates(path)
    assert tpl.n_convexified == 2
    hull = shapely.Polygon(L_SHAPE).convex_hull
    got = shapely.Polygon(tpl.outline(0))
    assert len(tpl.outline(0)) == 5  # the reflex corner is gone
    assert got.area == pytest.approx(1.0)
    # same shape as the hull of the input, up to translation and scale
    scale = math.sqrt(hull.area)
    moved = affinity.translate(hull, -hull.centroid.x, -hull.centroid.y)
    moved = affinity.scale(moved, 1 / scale, 1 / scale, origin=(0, 0))
    assert moved.symmetric_difference(got).area < 1e-12


def test_template_warns_once_per_file(tmp_path: Path) -> None:
    path = write_csv(tmp_path / "t.csv", {"L": L_SHAPE})
    gen = template(path)
    with pytest.warns(TemplateWarning) as record:
        for _ in range(3):
            gen.generate(np.ones(5), np.random.default_rng(0))
    assert len(record) == 1


@pytest.mark.parametrize("scale", [1e-6, 1.0, 1e6])
def test_template_scale_of_the_file_does_not_matter(tmp_path: Path, scale: float) -> None:
    outline = [(scale * (x + 3.0), scale * (y - 2.0)) for x, y in L_SHAPE]
    with pytest.warns(TemplateWarning):
        tpl = read_templates(write_json(tmp_path / "t.json", [outline]))
    with pytest.warns(TemplateWarning):
        ref = read_templates(write_json(tmp_path / "r.json", [L_SHAPE]))
    assert np.allclose(tpl.vertices, ref.vertices, atol=1e-9)


@pytest.fixture(scope="module")
def template_generator(tmp_path_factory: pytest.TempPathFactory) -> TemplatePolygon:
    folder = tmp_path_factory.mktemp("templates")
    thin = [(0, 0), (10, 0), (10, 0.01)]
    return template(write_json(folder / "t.json", [TRIANGLE, CW_SQUARE, thin]))


@given(r=st.floats(1e-6, 1e6), seed=st.integers(0, 2**32 - 1))
@settings(max_examples=30, deadline=None)
def test_template_outlines(template_generator: TemplatePolygon, r: float, seed: int) -> None:
    radius = np.full(6, r)
    batch = template_generator.generate(radius, np.random.default_rng(seed))
    check_batch(batch, radius)


def test_template_reference_point_is_the_centroid(mixed_templates: Path) -> None:
    batch = template(mixed_templates).generate(np.full(20, 3.0), np.random.default_rng(1))
    for j in range(20):
        c = shapely.Polygon(batch.outline(j)).centroid
        assert abs(c.x) < 1e-12 and abs(c.y) < 1e-12
    assert batch.orientation.min() >= 0.0 and batch.orientation.max() < 2 * math.pi


def test_template_choice(mixed_templates: Path) -> None:
    cycle = template(mixed_templates, "cycle").generate(np.ones(7), np.random.default_rng(0))
    assert np.diff(cycle.offsets).tolist() == [3, 4, 3, 4, 3, 4, 3]
    rand = template(mixed_templates, "random").generate(np.ones(400), np.random.default_rng(0))
    counts = np.diff(rand.offsets)
    assert set(counts.tolist()) == {3, 4}
    assert 150 < np.sum(counts == 3) < 250


def test_template_cache_and_relative_path(tmp_path: Path, monkeypatch: pytest.MonkeyPatch) -> None:
    monkeypatch.chdir(tmp_path)
    write_csv(tmp_path / "t.csv", {"a": TRIANGLE})
    gen = template("t.csv")
    first = gen.generate(np.ones(3), np.random.default_rng(0))
    (tmp_path / "t.csv").unlink()  # parsed once: later batches need no file
    again = gen.generate(np.ones(3), np.random.default_rng(0))
    assert np.array_equal(first.vertices, again.vertices)
    with pytest.raises(TemplateError, match="relative to the current directory"):
        template("t.csv").generate(np.ones(3), np.random.default_rng(0))


@pytest.mark.parametrize(
    ("name", "content", "message"),
    [
        ("a.csv", "", "empty template file"),
        ("a.csv", "x,y\n0,0\n", "expected the header id,x,y"),
        ("a.csv", "id,x,y\n1,0\n", "row 2: expected 3 fields"),
        ("a.csv", "id,x,y\n1,0,zero\n", "row 2: x and y must be finite numbers"),
        ("a.csv", "id,x,y\n1,0,inf\n", "row 2: x and y must be finite numbers"),
        ("a.csv", "id,x,y\n", "holds no outlines"),
        ("a.csv", "id,x,y\np,0,0\np,1,0\n", "outline 'p': degenerate outline"),
        ("a.csv", "id,x,y\nq,0,0\nq,1,1\nq,2,2\nq,3,3\n", "outline 'q': degenerate outline"),
        ("a.csv", "id,x,y\nr,1,1\nr,1,1\nr,1,1\n", "outline 'r': degenerate outline"),
        ("a.json", "[[[0, 0], [1, 0]", "invalid JSON"),
        ("a.json", '{"a": 1}', "expected a JSON list of outlines"),
        ("a.json", "[[[0, 0], [1, 0], [0, 1]], 3]", "outline 1: expected a list"),
        ("a.json", '[[[0, 0], [1, 0], [0, "1"]]]', "outline 0: every point must be a pair"),
        ("a.json", "[[[0, 0], [1, 0], [0, 1, 2]]]", "outline 0: every point must be a pair"),
        ("a.json", "[[[0, 0], [1, 0], [0, 1e999]]]", "outline 0: every point must be a pair"),
        ("a.json", "[[[0, 0], [1, 0], [0, true]]]", "outline 0: every point must be a pair"),
        ("a.json", "[]", "holds no outlines"),
        ("a.json", "[[[0, 0], [1, 0], [0, 1]], [[0, 0], [1, 0], [2, 0]]]", "outline '1'"),
        ("a.txt", "id,x,y\n", "unsupported template file type"),
    ],
)
def test_bad_template_files(tmp_path: Path, name: str, content: str, message: str) -> None:
    path = tmp_path / name
    path.write_text(content, encoding="utf-8")
    with pytest.raises(TemplateError, match=message) as info:
        template(path).generate(np.ones(2), np.random.default_rng(0))
    text = str(info.value)
    assert "\n" not in text and text.startswith(str(path))
    assert isinstance(info.value, ValueError) and isinstance(info.value, ConfigError)


def test_an_stl_file_points_to_the_3d_template(tmp_path: Path) -> None:
    path = tmp_path / "grain.stl"
    path.write_bytes(b"solid grain\nendsolid grain\n")
    with pytest.raises(TemplateError, match=r"\(use \.csv or \.json; STL meshes are the 3D shape"):
        read_templates(path)


def test_missing_template_file(tmp_path: Path) -> None:
    with pytest.raises(ValueError, match=r"missing\.json: no such template file"):
        read_templates(tmp_path / "missing.json")


# ---------------------------------------------------------------------------
# end to end


def test_mixed_scene_packs_without_overlap(tmp_path: Path) -> None:
    outlines = write_json(tmp_path / "grains.json", [TRIANGLE, CW_SQUARE, L_SHAPE])
    scene = tmp_path / "mixed.toml"
    scene.write_text(
        f"""
name = "mixed"
seed = 3
count = 300

[domain]
width = 100.0
height = 100.0

[size]
kind = "change5"
d_min = 2.0
d_max = 10.0

[[phases]]
name = "octagons"
fraction = 0.25
shape = {{ kind = "octagon", psi = 1.0 }}

[[phases]]
name = "hexagons"
fraction = 0.25
shape = {{ kind = "regular", m = 6 }}

[[phases]]
name = "random"
fraction = 0.25
shape = {{ kind = "random-polygon", m = 5, jitter = 0.3 }}

[[phases]]
name = "grains"
fraction = 0.25
shape = {{ kind = "template", path = {json.dumps(str(outlines))}, choice = "cycle" }}

[insertion]
kind = "available-arc"

[density]
kind = "eta"
eta = 0.0
""",
        encoding="utf-8",
    )
    resolved = resolve_scene(load_scene(scene), default_registry(autoload=False))
    with pytest.warns(TemplateWarning, match="1 of 3"):
        outcome = run_scene(resolved, None)
    packing = outcome.packing
    assert_valid_packing(packing)
    counts = np.diff(packing.offsets)
    assert {3, 4, 5, 6, 8} <= set(counts[packing.placed].tolist())
    assert packing.n_placed > 250
