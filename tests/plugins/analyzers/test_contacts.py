"""Contact detection and the bow model against shapely."""

from __future__ import annotations

import numpy as np
import pytest
import shapely

from regopack.geometry.domain import Rectangle
from regopack.plugins.analyzers import Contacts, ContactsConfig, Coordination, Network
from regopack.plugins.analyzers.contact_kernel import edge_normals_and_mitres
from regopack.testing import packing_from_polygons


def _grown(outline: np.ndarray, s: float) -> shapely.Polygon:
    """Mitred offset by s with the same edge directions (independent construction)."""
    poly = shapely.Polygon(outline)
    return poly.buffer(s, join_style="mitre", mitre_limit=1e6)


def _grown_octagon(outline: np.ndarray, theta0: float, s: float, m: int = 8) -> shapely.Polygon:
    """Half-plane construction from the octagon's m edge normals at theta0 + 2 pi k / m."""
    centre = outline.mean(axis=0)
    big = 100.0 * (np.abs(outline - centre).max() + s + 1.0)
    poly = shapely.box(*(centre - big), *(centre + big))
    for k in range(m):
        phi = theta0 + 2 * np.pi * k / m
        n = np.array([np.cos(phi), np.sin(phi)])
        t = np.array([-n[1], n[0]])
        h = (outline @ n).max() + s
        base = h * n
        half = shapely.Polygon(
            [
                base + big * t,
                base - big * t,
                base - big * t - 2 * big * n,
                base + big * t - 2 * big * n,
            ]
        )
        poly = poly.intersection(half)
    return poly


def _square(x: float, y: float, h: float = 1.0, rot: float = 0.0) -> np.ndarray:
    c, s = np.cos(rot), np.sin(rot)
    pts = np.array([(-h, -h), (h, -h), (h, h), (-h, h)])
    return pts @ np.array([[c, s], [-s, c]]) + (x, y)


def test_face_to_face_contact_area_and_depth() -> None:
    # two unit squares (side 2) with a gap of 0.01, tol 0.05: overlap strip 0.04 x 2
    packing = packing_from_polygons([_square(0, 0), _square(2.01, 0)], domain=(-5, 5, -5, 5))
    c = Contacts(ContactsConfig(tol=0.05, margin=0.0)).compute(packing, {})
    assert len(c.area) == 1
    assert c.width[0] == pytest.approx(np.hypot(2.05, 0.04), rel=1e-9)
    assert c.area[0] == pytest.approx(0.04 * 2.05, rel=1e-9)
    # a thin strip of thickness t has the depth of a flat segment, 3 A / (2 b) = 1.5 t
    assert c.depth[0] == pytest.approx(1.5 * c.area[0] / c.width[0], rel=2e-3)
    assert np.allclose(np.abs(c.normal[0]), [1.0, 0.02 / 1.0], atol=0.05)
    assert c.threshold[0] == pytest.approx(0.01, rel=1e-9)


@pytest.mark.parametrize("gap", [0.02, 0.03, 0.045])
def test_face_to_face_near_contacts_are_shallower_than_tol(gap: float) -> None:
    """Parallel faces closer than tol: delta = 1.5 (tol - gap), below tol for gap > tol / 3."""
    packing = packing_from_polygons([_square(0, 0), _square(2.0 + gap, 0)], domain=(-5, 5, -5, 5))
    c = Contacts(ContactsConfig(tol=0.05, margin=0.0)).compute(packing, {})
    assert len(c.depth) == 1
    assert 0 < c.depth[0] < 0.05
    assert c.depth[0] == pytest.approx(1.5 * (0.05 - gap), rel=5e-3)


def test_threshold_and_area_match_shapely_for_random_octagons() -> None:
    from regopack.registry.manager import default_registry
    from regopack.run.pipeline import run_scene
    from regopack.scenes.model import load_scene, resolve_scene

    resolved = resolve_scene(
        load_scene("small", ["count=400", "seed=2"]), default_registry(autoload=False)
    )
    packing = run_scene(resolved, None).packing
    tol = 0.2
    c = Contacts(ContactsConfig(tol=tol, tol_max=0.5)).compute(packing, {})
    assert len(c.area) > 100
    for k in range(0, len(c.area), 3):
        i, j = c.i[k], c.j[k]
        a = _grown_octagon(packing.polygon(i), packing.orientation[i], tol / 2)
        b = _grown_octagon(packing.polygon(j), packing.orientation[j], tol / 2)
        inter = a.intersection(b)
        assert c.area[k] == pytest.approx(inter.area, rel=1e-6, abs=1e-12)
        hull = np.asarray(inter.exterior.coords)
        d = np.sqrt(((hull[:, None, :] - hull[None, :, :]) ** 2).sum(-1)).max()
        assert c.width[k] == pytest.approx(d, rel=1e-6)
    # pairs not in contact at tol do not overlap once grown by tol / 2
    geoms = packing.to_shapely()
    placed = np.flatnonzero(packing.placed)
    grown = [_grown_octagon(packing.polygon(p), packing.orientation[p], tol / 2) for p in placed]
    tree = shapely.STRtree(grown)
    a_idx, b_idx = tree.query(grown, predicate="intersects")
    keep = a_idx < b_idx
    found = set(zip(c.i.tolist(), c.j.tolist(), strict=True))
    for a_, b_ in zip(a_idx[keep], b_idx[keep], strict=True):
        pair = (int(placed[a_]), int(placed[b_]))
        area = grown[a_].intersection(grown[b_]).area
        if area > 1e-9:
            assert pair in found, f"missed contact {pair} of area {area}"
    del geoms


def test_threshold_is_where_the_overlap_starts() -> None:
    packing = packing_from_polygons(
        [_square(0, 0), _square(2.3, 0.4, rot=0.3)], domain=(-5, 5, -5, 5)
    )
    c = Contacts(ContactsConfig(tol=0.5, tol_max=1.0, margin=0.0)).compute(packing, {})
    t = c.threshold[0]
    below = _grown(packing.polygon(0), 0.5 * t * 0.999).intersection(
        _grown(packing.polygon(1), 0.5 * t * 0.999)
    )
    above = _grown(packing.polygon(0), 0.5 * t * 1.001).intersection(
        _grown(packing.polygon(1), 0.5 * t * 1.001)
    )
    assert below.area < 1e-12 < above.area


def test_mitres_of_a_square() -> None:
    sq = _square(0, 0)
    _nx, _ny, mx, my, mitre = edge_normals_and_mitres(sq, np.array([0, 4]))
    assert np.allclose(np.abs(mx), 1.0) and np.allclose(np.abs(my), 1.0)
    assert mitre[0] == pytest.approx(np.sqrt(2))


def test_z_of_tol_is_non_decreasing_and_per_mineral_weights_add_up() -> None:
    from regopack.registry.manager import default_registry
    from regopack.run.pipeline import run_scene
    from regopack.scenes.model import load_scene, resolve_scene

    resolved = resolve_scene(
        load_scene("table1", ["domain.width=150", "domain.height=150", "seed=3"]),
        default_registry(autoload=False),
    )
    packing = run_scene(resolved, None).packing
    contacts = Contacts().compute(packing, {})
    coord = Coordination().compute(packing, {"contacts": contacts})
    r = coord.results()
    assert np.all(np.diff(r["z_interior_sweep"]) >= 0)
    assert np.all(np.diff(r["z_domain_sweep"]) >= 0)
    weighted = sum(
        r["z_per_mineral"][m] * r["n_per_mineral"][m]
        for m in r["z_per_mineral"]
        if r["n_per_mineral"][m]
    )
    assert weighted / r["n_interior"] == pytest.approx(r["z_interior"], rel=1e-12)
    assert r["z_interior"] > 2.0
    net = Network().compute(packing, {"contacts": contacts}).results()
    assert net["n_edges"] == len(contacts.area)
    assert 2 * net["n_edges"] / packing.n_placed == pytest.approx(r["z_domain"])


def test_tangent_polygons_are_in_contact_at_any_tolerance() -> None:
    packing = packing_from_polygons(
        [_square(0, 0), _square(2.0, 0.0)], domain=Rectangle(-5, 5, -5, 5)
    )
    c = Contacts(ContactsConfig(tol=1e-9, tol_max=1e-9, margin=0.0)).compute(packing, {})
    assert len(c.area) == 1 and c.depth[0] == pytest.approx(1.5e-9, rel=1e-3)


def test_periodic_contacts_cross_the_sides_like_an_unwrapped_copy() -> None:
    from regopack.geometry.domain import PeriodicRectangle

    sq = np.array([[0.0, 0.0], [1.0, 0.0], [1.0, 1.0], [0.0, 1.0]])
    domain = PeriodicRectangle(0.0, 10.0, 0.0, 10.0)
    # a row of squares through the side x = 0 = 10, and a column through y = 0 = 10
    row = [sq + (x, 4.5) for x in (-0.5, 0.5, 1.5, 8.5)]  # 8.5..9.5 touches -0.5 via the side
    col = [sq + (6.0, y) for y in (9.3, 0.3 + 0.01)]  # 9.3..10.3 and 0.31..1.31, gap 0.01
    polys = row + col
    # the packing stores centres inside the domain, outlines unwrapped about them
    centres = [p.mean(axis=0) for p in polys]
    wrapped = domain.wrap(centres)
    polys = [p - c + w for p, c, w in zip(polys, centres, wrapped, strict=True)]
    packing = packing_from_polygons(polys, domain=domain)
    contacts = Contacts(ContactsConfig(tol=0.05)).compute(packing, {})
    pairs = {tuple(sorted(p)) for p in zip(contacts.i.tolist(), contacts.j.tolist(), strict=True)}
    assert pairs == {(0, 1), (1, 2), (0, 3), (4, 5)}
    k = [tuple(sorted(p)) for p in zip(contacts.i.tolist(), contacts.j.tolist(), strict=True)]
    across = k.index((0, 3))
    assert contacts.width[across] == pytest.approx(np.hypot(1.05, 0.05))  # the diagonal
    assert domain.contains(contacts.point).all()
    assert np.all((contacts.point >= 0.0) & (contacts.point < 10.0))
