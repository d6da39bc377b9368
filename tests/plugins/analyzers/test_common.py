"""Shared analysis helpers: periodic ghost images keep every per-particle array aligned."""

from __future__ import annotations

import numpy as np
import pytest

import regopack
from regopack.plugins.analyzers.common import periodic_images


@pytest.fixture(scope="module")
def periodic_disks():
    return regopack.pack(
        "small",
        domain__kind="periodic",
        domain__width=80.0,
        domain__height=80.0,
        count=150,
        **{"phases.0.shape": {"kind": "disk"}},
    )


def test_ghosts_copy_the_rounding_of_their_particle(periodic_disks):
    p = periodic_disks
    assert p.rounded
    ext, origin = periodic_images(p, 10.0)
    assert ext.n_particles > p.n_particles
    np.testing.assert_array_equal(ext.rounding, p.rounding[origin])
    np.testing.assert_array_equal(ext.radius, p.radius[origin])
    np.testing.assert_allclose(ext.area(), p.area()[origin])


def test_every_analysis_runs_on_a_periodic_packing_with_disks(periodic_disks):
    res = regopack.analyze(periodic_disks, ["density", "coordination", "rdf", "local_fraction"])
    assert res["rdf"]["n_points"] == periodic_disks.n_placed
    assert res["coordination"]["z_domain"] > 0
