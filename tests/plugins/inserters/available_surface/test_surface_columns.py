"""The 3D sweep's column choice: the lowest open zone top, turns among full columns."""

from __future__ import annotations

import numpy as np
import pytest

from regopack.geometry.solids import SolidBatch
from regopack.plugins.inserters.available_surface.state import SurfaceState
from regopack.plugins.inserters.available_surface.sweep import SurfaceSweep


def _listed_choice(sw: SurfaceSweep, tried: set[int]) -> int:
    """The choice by listing every column (the rule the sweep's heap must give)."""
    zones = sw.zones
    best = -1
    for k, z in enumerate(zones):
        if z.seeded and not z.closed and k not in tried:
            if best < 0 or z.hi < zones[best].hi:
                best = k
    if best >= 0 and len(zones) > 1 and zones[best].full and sw.cur >= 0:
        for d in range(1, len(zones) + 1):
            k = (sw.cur + d) % len(zones)
            z = zones[k]
            if z.seeded and not z.closed and k not in tried and z.full:
                if z.hi == zones[best].hi:
                    return k
    return best


def _sweep() -> SurfaceSweep:
    radius = np.full(40, 0.5)
    lo, hi = np.array([0.0, 0.0, 0.0]), np.array([24.0, 24.0, 6.0])
    st = SurfaceState(SolidBatch.of_spheres(radius), radius, lo, hi)
    sw = SurfaceSweep(st, 0.999, 1.0, "paced", strip=2.0)
    assert len(sw.zones) == 144
    return sw


@pytest.mark.parametrize("seed", range(6))
def test_the_column_choice_matches_a_listing_of_every_column(seed: int) -> None:
    """Random seeding, rises, roll-backs, full and closed columns, tried sets."""
    rng = np.random.default_rng(seed)
    sw = _sweep()
    zones = sw.zones
    checked = 0
    for _ in range(3000):
        k = int(rng.integers(len(zones)))
        z = zones[k]
        op = rng.random()
        if not z.seeded:
            if op < 0.3:
                z.seeded = True
                z.hi = int(rng.integers(0, 3))
                z.lo = max(0, z.hi - sw.nzone + 1)
                sw._moved(z)
        elif not z.closed:
            if op < 0.45:
                if not sw._raise(z) and not z.full:
                    sw._set_full(z)
            elif op < 0.55 and z.hi > z.lo:
                lo0, hi0 = z.lo, max(z.lo, z.hi - int(rng.integers(1, 3)))
                sw._roll_back(z, lo0, hi0, 0)
            elif op < 0.58 and not z.full:
                while sw._raise(z):
                    pass
                sw._set_full(z)
            elif op < 0.60:
                sw._close(z)
        sw.cur = int(rng.integers(-1, len(zones)))
        tried = {int(t) for t in rng.integers(len(zones), size=int(rng.integers(0, 4)))}
        if rng.random() < 0.3:
            # the current lowest columns tried already, as when a particle moves on
            for _ in range(int(rng.integers(1, 4))):
                best = _listed_choice(sw, tried)
                if best >= 0:
                    tried.add(best)
        assert sw._choose(tried) == _listed_choice(sw, tried)
        checked += 1
    assert checked == 3000
    assert any(z.full and not z.closed for z in zones)
    assert any(z.closed for z in zones)


@pytest.mark.parametrize("seed", range(3))
def test_full_columns_take_turns_after_the_current_one(seed: int) -> None:
    """Once every open column is at the top, the turn passes on after ``cur``, cyclically."""
    rng = np.random.default_rng(seed)
    sw = _sweep()
    zones = sw.zones
    for z in zones:
        if rng.random() < 0.9:
            z.seeded = True
            sw._moved(z)
            while sw._raise(z):
                pass
            sw._set_full(z)
    turns = 0
    for _ in range(400):
        sw.cur = int(rng.integers(-1, len(zones)))
        tried = {int(t) for t in rng.integers(len(zones), size=int(rng.integers(0, 3)))}
        chosen = sw._choose(tried)
        assert chosen == _listed_choice(sw, tried)
        if chosen >= 0 and zones[chosen].full and chosen != sw.cur:
            turns += 1
        if rng.random() < 0.05:
            open_ = [k for k, z in enumerate(zones) if z.seeded and not z.closed]
            if open_:
                sw._close(zones[int(rng.choice(open_))])
    assert turns > 100
