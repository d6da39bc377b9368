"""The sphere shape: exact volume, no random numbers, registered as a 3D shape."""

from __future__ import annotations

import numpy as np
import pytest

from regopack.geometry.solids import sphere_volume
from regopack.plugins.shapes.sphere import Sphere
from regopack.registry.manager import default_registry


@pytest.mark.parametrize("scale", [1e-6, 1.0, 1e6])
def test_spheres_have_the_volume_of_their_radius(scale: float) -> None:
    r = np.array([0.5, 1.0, 7.0]) * scale
    rng = np.random.default_rng(1)
    state = rng.bit_generator.state
    batch = Sphere().generate(r, rng)
    assert rng.bit_generator.state == state  # draws nothing
    assert batch.volume.tolist() == pytest.approx(sphere_volume(r).tolist(), rel=1e-15)
    assert batch.circumradius.tolist() == r.tolist()
    assert len(batch) == 3 and batch.normals.shape == (0, 3)


def test_sphere_is_registered_as_a_3d_shape() -> None:
    spec = default_registry().get("shape", "sphere")
    assert getattr(spec, "dimension", 2) == 3


def test_radii_must_be_one_dimensional() -> None:
    with pytest.raises(ValueError, match="one-dimensional"):
        Sphere().generate(np.ones((2, 2)), np.random.default_rng(0))
