"""The polyhedron shape plugin: contract, limits, draw order and registration."""

from __future__ import annotations

import math

import numpy as np
import pydantic
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from regopack.geometry.solids import sphere_volume
from regopack.plugins.shapes.polyhedra.generator import random_polyhedra
from regopack.plugins.shapes.polyhedra.shape import PolyhedronConfig, RandomPolyhedron
from regopack.registry.manager import default_registry
from regopack.testing import check_solid_generator


@pytest.mark.parametrize(
    "params",
    [
        {},
        {"psi": 0.01, "a": 1.0},
        {"psi": 1000.0, "a": 0.05},
        {"directions": "cube"},
        {"directions": "rhombic-dodecahedron", "psi": 0.25},
        {"directions": "fibonacci", "m": 8},
    ],
)
def test_the_contract_holds(params: dict[str, object]) -> None:
    check_solid_generator(RandomPolyhedron(PolyhedronConfig(**params)))


@settings(max_examples=25, deadline=None)
@given(
    psi=st.floats(0.01, 1000.0),
    a=st.floats(0.05, 1.0),
    scale=st.sampled_from([1e-6, 1.0, 1e6]),
    seed=st.integers(0, 2**32 - 1),
)
def test_volumes_are_exact_at_every_scale(psi: float, a: float, scale: float, seed: int) -> None:
    r = np.array([1.0, 10.0, 1000.0]) * scale  # a size ratio of 10^3
    batch = RandomPolyhedron(PolyhedronConfig(psi=psi, a=a)).generate(
        r, np.random.default_rng(seed)
    )
    assert batch.volume == pytest.approx(sphere_volume(r), rel=1e-9)
    assert np.all(np.diff(batch.face_offsets) <= 14)


def test_psi_to_infinity_gives_the_archimedean_truncated_octahedron() -> None:
    batch = RandomPolyhedron(PolyhedronConfig(psi=1e6, a=1 / 3)).generate(
        np.ones(20), np.random.default_rng(3)
    )
    for j in range(len(batch)):
        verts, loops = batch.solid(j)
        if len(loops) != 14 or verts.shape[0] != 24:
            continue  # xi within 1e-6 of 0 or 1 keeps a trace of the perturbation
        edges = [np.linalg.norm(verts[lp] - verts[np.roll(lp, -1)], axis=1) for lp in loops]
        lengths = np.concatenate(edges)
        assert lengths.max() / lengths.min() == pytest.approx(1.0, abs=1e-6)  # all edges equal
        sizes = sorted(len(lp) for lp in loops)
        assert sizes == [4] * 6 + [6] * 8
        # edge length of the Archimedean solid of volume 4/3 pi: V = 8 sqrt(2) e^3
        assert lengths.mean() == pytest.approx((4 / 3 * math.pi / (8 * math.sqrt(2))) ** (1 / 3))
        return
    pytest.fail("no particle reached the regular limit")


def test_with_equal_base_it_draws_what_random_polyhedra_draws() -> None:
    """The plugin keeps the generator's draw order: signs, xi, quaternions."""
    r = np.array([1.0, 2.0, 3.0])
    shape = RandomPolyhedron(PolyhedronConfig(directions="cube", psi=0.5))
    ours = shape.generate(r, np.random.default_rng(11))
    theirs = random_polyhedra(
        np.random.default_rng(11), r, psi=0.5, a=1 / 3, directions=shape.directions
    )
    assert np.array_equal(ours.vertices, theirs.vertices)
    assert np.array_equal(ours.face_vertices, theirs.face_vertices)


def test_rotations_are_the_stored_quaternions() -> None:
    shape = RandomPolyhedron(PolyhedronConfig(psi=1e6, directions="cube"))
    batch = shape.generate(np.ones(5), np.random.default_rng(2))
    for j in range(5):
        w, x, y, z = batch.rotation[j]
        # the cube's face normals are the rotated axes
        rot = np.array(
            [
                [1 - 2 * (y * y + z * z), 2 * (x * y - w * z), 2 * (x * z + w * y)],
                [2 * (x * y + w * z), 1 - 2 * (x * x + z * z), 2 * (y * z - w * x)],
                [2 * (x * z - w * y), 2 * (y * z + w * x), 1 - 2 * (x * x + y * y)],
            ]
        )
        f0, f1 = batch.face_offsets[j], batch.face_offsets[j + 1]
        normals = batch.normals[f0:f1]
        axes = np.concatenate([rot.T, -rot.T])
        assert np.abs(normals @ axes.T).max(axis=1) == pytest.approx(np.ones(6), abs=1e-9)


def test_m_only_with_fibonacci_and_registered_as_3d() -> None:
    with pytest.raises(pydantic.ValidationError, match="m applies only"):
        PolyhedronConfig(m=10)
    spec = default_registry().get("shape", "polyhedron")
    assert getattr(spec, "dimension", 2) == 3
    assert spec.build({"psi": 2.0}).config.psi == 2.0


def test_the_resolved_parameters_validate_again() -> None:
    """Every default filled in (as a resolved scene writes them) is valid input."""
    again = PolyhedronConfig.model_validate(PolyhedronConfig().model_dump())
    assert again == PolyhedronConfig()
    fib = PolyhedronConfig(directions="fibonacci")
    assert fib.m is None and len(RandomPolyhedron(fib).directions) == 20
    assert len(RandomPolyhedron(PolyhedronConfig(directions="fibonacci", m=9)).directions) == 9


@pytest.mark.parametrize(
    ("mutate", "message"),
    [
        (lambda fv: np.where(fv == 0, -1, fv), "index outside"),
        (lambda fv: np.concatenate([fv[:1], fv[:1], fv[2:]]), "repeats a vertex|not a planar"),
        (lambda fv: np.concatenate([fv[:3][::-1], fv[3:]]), "closed surface|counter-clockwise"),
    ],
)
def test_the_contract_check_catches_broken_face_loops(mutate, message) -> None:  # type: ignore[no-untyped-def]
    from dataclasses import replace

    class Broken(RandomPolyhedron):
        def generate(self, radius, rng):  # type: ignore[no-untyped-def]
            batch = super().generate(radius, rng)
            if len(batch) == 0:
                return batch
            return replace(batch, face_vertices=mutate(batch.face_vertices))

    with pytest.raises(AssertionError, match=message):
        check_solid_generator(Broken(PolyhedronConfig(directions="cube")), radii=[1.0, 2.0])
