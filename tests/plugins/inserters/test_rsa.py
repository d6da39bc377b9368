"""Random sequential addition: exact overlap test, valid packings, determinism, scenes."""

from __future__ import annotations

import numpy as np
import pytest
import shapely
from hypothesis import given, settings
from hypothesis import strategies as st

from regopack.base.errors import ConfigError
from regopack.geometry.domain import Rectangle
from regopack.geometry.population import Population, ShapeBatch, concat_shapes
from regopack.packing.core import Packing
from regopack.plugins.density.eta import EtaConfig, EtaController
from regopack.plugins.inserters.rsa import (
    RandomSequentialAddition,
    RsaConfig,
    convex_polygons_overlap,
)
from regopack.plugins.shapes.octagon import OctagonConfig, RandomPolygon
from regopack.registry.interfaces import InsertionResult
from regopack.registry.manager import default_registry
from regopack.run.pipeline import run_scene
from regopack.scenes.model import load_scene, resolve_scene
from regopack.verification.polygons import verify

IDENTITY = EtaController(EtaConfig(eta=0.0))


@pytest.fixture(scope="module")
def registry():
    return default_registry(autoload=False)


def population(radius: np.ndarray, rng: np.random.Generator, psis=(0.25, 1.0, 15.0)) -> Population:
    """Random octagons with the given radii, one phase per ``psi``."""
    n = len(radius)
    mineral = rng.integers(0, len(psis), size=n).astype(np.int64)
    parts: list[tuple[np.ndarray, ShapeBatch]] = []
    for p, psi in enumerate(psis):
        idx = np.flatnonzero(mineral == p)
        parts.append((idx, RandomPolygon(OctagonConfig(psi=psi)).generate(radius[idx], rng)))
    names = tuple(f"p{p}" for p in range(len(psis)))
    return Population(radius, mineral, names, concat_shapes(parts, n))


def scene(seed: int, n: int = 60, ratio: float = 5.0, scale: float = 1.0, phi: float = 0.6):
    """A population with radii log-uniform in [scale, ratio * scale] and a domain of area
    fraction ``phi`` (at least large enough for the biggest particle), off the origin."""
    rng = np.random.default_rng(seed)
    radius = scale * np.exp(rng.uniform(0.0, np.log(ratio), n))
    pop = population(radius, rng)
    side = max(np.sqrt(np.pi * np.sum(radius**2) / phi), 3.0 * pop.circumradius.max())
    domain = Rectangle.centred(side, 0.8 * side, center=(7.0 * side, -3.0 * side))
    return pop, domain


def pack(pop, domain, seed=0, controller=IDENTITY, progress=None, **config) -> InsertionResult:
    inserter = RandomSequentialAddition(RsaConfig(**config))
    return inserter.pack(pop, domain, controller, np.random.default_rng(seed), progress)


def packing(pop, result, domain) -> Packing:
    return Packing.from_parts(pop, result, domain, {}, 0)


# ---------------------------------------------------------------------------
# the overlap test


def random_convex(rng: np.random.Generator, size: float) -> np.ndarray:
    points = rng.normal(size=(int(rng.integers(3, 12)), 2)) * size
    hull = shapely.convex_hull(shapely.multipoints(points))
    if hull.geom_type != "Polygon":
        return random_convex(rng, size)
    coords = np.asarray(hull.exterior.coords)[:-1]
    return coords if rng.random() < 0.5 else coords[::-1]


@given(
    seed=st.integers(0, 2**32 - 1),
    ratio=st.floats(1.0, 1e3),
    scale=st.sampled_from([1e-6, 1.0, 1e6]),
)
@settings(max_examples=300, deadline=None)
def test_overlap_matches_shapely(seed: int, ratio: float, scale: float) -> None:
    rng = np.random.default_rng(seed)
    a = random_convex(rng, scale)
    b = random_convex(rng, scale * ratio)
    reach = np.abs(a).max() + np.abs(b).max()
    shift = rng.uniform(-0.9, 0.9, 2) * reach
    origin = rng.uniform(-10, 10, 2) * scale * ratio
    pa = shapely.Polygon(a + origin)
    pb = shapely.Polygon(b + shift + origin)
    expected = bool(shapely.relate_pattern(pa, pb, "T********"))
    assert convex_polygons_overlap(a + origin, b + origin, (shift[0], shift[1])) is expected


SQUARE = np.array([[0.0, 0.0], [1.0, 0.0], [1.0, 1.0], [0.0, 1.0]])


@pytest.mark.parametrize("scale", [1e-6, 1.0, 1e6])
@pytest.mark.parametrize(
    ("shift", "expected"),
    [
        ((1.0, 0.0), False),  # sharing an edge
        ((0.0, -1.0), False),
        ((1.0, 1.0), False),  # sharing a corner
        ((-1.0, 0.5), False),  # sharing part of an edge
        ((1.0, 0.25), False),
        ((1.5, 0.0), False),
        ((0.0, 0.0), True),  # the same square
        ((0.5, 0.5), True),
        ((1.0 - 2**-20, 0.0), True),
        ((0.999, 0.999), True),
    ],
)
def test_touching_squares_do_not_overlap(scale, shift, expected) -> None:
    a = SQUARE * scale
    s = (shift[0] * scale, shift[1] * scale)
    assert convex_polygons_overlap(a, a, s) is expected
    want = bool(shapely.relate_pattern(shapely.Polygon(a), shapely.Polygon(a + s), "T********"))
    assert want is expected


def test_small_square_inside_a_large_one_overlaps() -> None:
    assert convex_polygons_overlap(SQUARE * 1000, SQUARE, (500.0, 500.0))
    assert not convex_polygons_overlap(SQUARE * 1000, SQUARE, (1000.0, 500.0))


# ---------------------------------------------------------------------------
# packings


@given(
    seed=st.integers(0, 2**32 - 1),
    ratio=st.floats(1.0, 1e3),
    scale=st.sampled_from([1e-6, 1.0, 1e6]),
)
@settings(max_examples=40, deadline=None)
def test_packings_are_valid(seed: int, ratio: float, scale: float) -> None:
    pop, domain = scene(seed, n=50, ratio=ratio, scale=scale)
    result = pack(pop, domain, seed=seed, max_attempts=200)
    report = verify(packing(pop, result, domain))
    assert report.ok, str(report)
    placed = result.placed
    assert placed.any()
    assert np.isnan(result.centre[~placed]).all()
    # population order: insertion indices count up along the population
    assert np.array_equal(result.insertion_index[placed], np.arange(placed.sum()))


def test_dense_scene_is_valid_and_jammed() -> None:
    pop, domain = scene(3, n=400, ratio=8.0, phi=0.9)
    result = pack(pop, domain, max_attempts=500)
    assert verify(packing(pop, result, domain)).ok
    assert 0 < result.placed.sum() < len(pop)
    assert result.stats["attempts"] > result.stats["rejected_attempts"] > 0
    assert result.stats["attempts"] - result.stats["rejected_attempts"] == result.placed.sum()


def test_same_population_and_seed_give_identical_results() -> None:
    pop, domain = scene(5, n=300, phi=0.7)
    one = pack(pop, domain, seed=11)
    two = pack(pop, domain, seed=11)
    assert one.centre.tobytes() == two.centre.tobytes()
    assert np.array_equal(one.insertion_index, two.insertion_index)
    other = pack(pop, domain, seed=12)
    assert other.centre.tobytes() != one.centre.tobytes()


def test_a_single_attempt_places_fewer_particles() -> None:
    pop, domain = scene(6, n=400, phi=0.7)
    once = pack(pop, domain, max_attempts=1)
    many = pack(pop, domain, max_attempts=1000)
    assert once.stats["attempts"] == len(pop)
    assert once.placed.sum() < many.placed.sum()


def test_stop_after_failures_ends_the_run_early() -> None:
    pop, domain = scene(7, n=500, phi=1.2)
    full = pack(pop, domain, max_attempts=20)
    cut = pack(pop, domain, max_attempts=20, stop_after_failures=3)
    not_tried = int(cut.stats["not_tried"])
    assert not_tried > 0
    stop = len(pop) - not_tried
    assert not cut.placed[stop - 3 : stop].any()
    assert not cut.placed[stop:].any()
    assert cut.placed[: stop - 3].any()
    # the same draws up to the stop
    assert np.array_equal(cut.centre[:stop], full.centre[:stop], equal_nan=True)
    assert verify(packing(pop, cut, domain)).ok


def test_particle_larger_than_the_domain_is_not_placed() -> None:
    pop, _ = scene(8, n=5, ratio=1.0)
    tiny = Rectangle(0.0, 0.5, 0.0, 0.5)
    result = pack(pop, tiny)
    assert not result.placed.any()
    assert result.stats["attempts"] == 0


def test_empty_population() -> None:
    _, domain = scene(9, n=5)
    empty = Population(
        np.zeros(0),
        np.zeros(0, dtype=np.int64),
        ("m",),
        ShapeBatch(np.zeros((0, 2)), np.zeros(1, dtype=np.int64), np.zeros(0)),
    )
    result = pack(empty, domain)
    assert result.centre.shape == (0, 2)
    assert result.insertion_index.shape == (0,)


def test_the_density_controller_is_ignored() -> None:
    pop, domain = scene(10, n=200, phi=0.7)
    plain = pack(pop, domain, seed=3)
    eta = pack(pop, domain, seed=3, controller=EtaController(EtaConfig(eta=20.0)))
    assert eta.centre.tobytes() == plain.centre.tobytes()
    assert eta.stats["controller_ignored"] == 1.0
    assert "controller_ignored" not in plain.stats


def test_progress_is_reported_every_256_particles() -> None:
    pop, domain = scene(11, n=600, phi=0.5)
    calls: list[tuple[int, int, int]] = []
    result = pack(pop, domain, progress=lambda *a: calls.append(a))
    assert [c[0] for c in calls] == [0, 256, 512, 600]
    assert calls[0] == (0, 0, 600)
    assert calls[-1] == (600, int(result.placed.sum()), 600)
    assert all(c[1] <= c[0] for c in calls)


@pytest.mark.parametrize(
    "params", [{"max_attempts": 0}, {"max_attempts": 10**7 + 1}, {"stop_after_failures": 0}]
)
def test_bad_parameters_are_rejected(registry, params) -> None:
    spec = registry.get("insertion", "rsa")
    with pytest.raises(ValueError, match=r"greater than|less than"):
        spec.build(params)


# ---------------------------------------------------------------------------
# scenes


def test_available_arc_parameters_do_not_apply(registry) -> None:
    with pytest.raises(ConfigError, match=r"insertion\.t = 0\.999: unknown field; allowed: kind, "):
        resolve_scene(load_scene("small", ["count=300", 'insertion.kind="rsa"']), registry)


@pytest.fixture(scope="module")
def rsa_small(registry):
    overrides = ['insertion={kind="rsa", max_attempts=2000}']
    resolved = resolve_scene(load_scene("small", overrides), registry)
    return resolved, run_scene(resolved)


def test_small_scene_end_to_end(rsa_small, tmp_path) -> None:
    resolved, outcome = rsa_small
    assert resolved.insertion.to_dict() == {
        "kind": "rsa",
        "max_attempts": 2000,
        "stop_after_failures": None,
    }
    report = verify(outcome.packing)
    assert report.ok, str(report)
    summary = outcome.summary
    assert 0 < summary["placed"] < summary["tried"]
    assert summary["attempts"] >= summary["placed"]
    assert outcome.packing.scene["insertion"]["kind"] == "rsa"


def test_rsa_is_looser_than_available_arc(rsa_small, registry) -> None:
    _, rsa = rsa_small
    arc = run_scene(resolve_scene(load_scene("small"), registry))
    phi_rsa = rsa.summary["phi_domain"]
    phi_arc = arc.summary["phi_domain"]
    assert 0.4 < phi_rsa < 0.65
    assert phi_rsa < phi_arc - 0.1
