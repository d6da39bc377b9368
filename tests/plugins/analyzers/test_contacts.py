"""Contact detection: the bow model against shapely (2D), polyhedra against HiGHS, Qhull and
the separating gap (3D)."""

from __future__ import annotations

import numpy as np
import pytest
import shapely
from lattices3d import cube_lattice
from scipy.optimize import linprog
from scipy.spatial import ConvexHull, HalfspaceIntersection

import regopack
from regopack.base.errors import ConfigError
from regopack.geometry.domain import Rectangle
from regopack.packing.core import Packing
from regopack.plugins.analyzers import Contacts, ContactsConfig, Coordination, Network
from regopack.plugins.analyzers.contact_kernel import edge_normals_and_mitres
from regopack.plugins.analyzers.spherical_cap import equivalent_cap
from regopack.testing import packing_from_polygons
from regopack.verification.polyhedra import overlap_volume, separating_gap


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


GAPS = (1 / 64, 2 / 64, 3 / 64)  # exact in binary, as are the centres
TOL = 1 / 16


def _planes(p: Packing, k: int, grow: float = 0.0) -> tuple[np.ndarray, np.ndarray]:
    f0, f1 = int(p.face_offsets[k]), int(p.face_offsets[k + 1])
    normals = p.normals[f0:f1]
    return normals, p.support[f0:f1] + normals @ p.centre[k] + grow


def _grown_solid(p: Packing, k: int, grow: float) -> np.ndarray:
    """Vertices of particle ``k`` grown by ``grow`` along its face normals (Qhull)."""
    normals, offsets = _planes(p, k, grow)
    hs = HalfspaceIntersection(np.column_stack([normals, -offsets]), p.centre[k])
    return hs.intersections


def _highs_threshold(p: Packing, i: int, j: int) -> float:
    """Twice the smallest growth at which i and j meet: min t, n.x - t <= b, by HiGHS."""
    rows = [_planes(p, i), _planes(p, j)]
    a_ub = np.vstack([np.column_stack([n, -np.ones(len(n))]) for n, _ in rows])
    b_ub = np.concatenate([b for _, b in rows])
    res = linprog([0, 0, 0, 1.0], A_ub=a_ub, b_ub=b_ub, bounds=[(None, None)] * 4)
    assert res.status == 0
    return 2.0 * float(res.fun)


@pytest.fixture(scope="module")
def contacts3d(packing3d: Packing) -> Contacts:
    return Contacts(ContactsConfig(tol=0.05, tol_max=0.5)).compute(packing3d, {})


def test_thresholds_match_an_independent_linear_program(packing3d, contacts3d) -> None:
    assert len(contacts3d.pairs) > 100
    for (i, j), tau in zip(contacts3d.pairs[::3], contacts3d.threshold[::3], strict=True):
        assert tau == pytest.approx(_highs_threshold(packing3d, int(i), int(j)), abs=1e-8)


def test_the_threshold_is_bounded_by_the_euclidean_gap(packing3d, contacts3d) -> None:
    # growing along the face normals covers the ball of the growth and at most the solid
    # scaled about its centre by 1 + s / h: tau <= gap <= tau (R_i / h_i + R_j / h_j) / 2
    circum = packing3d.solids.circumradius
    h = np.minimum.reduceat(packing3d.support, packing3d.face_offsets[:-1])
    touching = 0
    for (i, j), tau in zip(contacts3d.pairs, contacts3d.threshold, strict=True):
        gap = separating_gap(packing3d.world_vertices(i), packing3d.world_vertices(j))
        assert tau <= gap + 1e-9
        assert gap <= max(tau, 0.0) * (circum[i] / h[i] + circum[j] / h[j]) / 2 + 1e-9
        touching += abs(gap) < 1e-9
    assert touching > 50  # the inserter places every particle against others


def test_the_contact_normal_separates_the_two_solids(packing3d, contacts3d) -> None:
    for (i, j), w in zip(contacts3d.pairs, contacts3d.pair_normal, strict=True):
        assert np.linalg.norm(w) == pytest.approx(1.0)
        p, q = packing3d.world_vertices(i) @ w, packing3d.world_vertices(j) @ w
        margin = q.min() - p.max()  # the plane normal to w between i and j
        gap = separating_gap(packing3d.world_vertices(i), packing3d.world_vertices(j))
        assert -1e-9 <= margin <= gap + 1e-9


def test_regions_match_the_intersection_of_the_grown_solids_by_qhull(packing3d, contacts3d) -> None:
    # in contact at tol exactly when the solids grown by tol/2 share volume; the volume,
    # the area projected on the contact plane and the centroid as Qhull measures them
    tol = 0.05
    s = 0.5 * tol
    in_contact = {
        (int(a), int(b)): k for k, (a, b) in enumerate(zip(contacts3d.i, contacts3d.j, strict=True))
    }
    checked = 0
    for (i, j), tau in zip(contacts3d.pairs[:60], contacts3d.threshold[:60], strict=True):
        gi, gj = _grown_solid(packing3d, i, s), _grown_solid(packing3d, j, s)
        shared = overlap_volume(gi, gj)
        k = in_contact.get((int(i), int(j)))
        assert (shared > 0) == (tau < tol) == (k is not None)
        if k is None:
            continue
        assert contacts3d.volume[k] == pytest.approx(shared, rel=1e-7)
        rows = [_planes(packing3d, i, s), _planes(packing3d, j, s)]
        eq = np.vstack([np.column_stack([n, -b]) for n, b in rows])
        corners = HalfspaceIntersection(eq, contacts3d.point[k]).intersections
        w = contacts3d.normal[k]
        e1 = np.cross(w, [1.0, 0, 0] if abs(w[0]) < 0.9 else [0, 1.0, 0])
        e1 /= np.linalg.norm(e1)
        flat = corners @ np.column_stack([e1, np.cross(w, e1)])
        assert contacts3d.area[k] == pytest.approx(ConvexHull(flat).volume, rel=1e-7)
        checked += 1
    assert checked > 20


def test_a_lattice_of_cubes_has_the_known_contacts() -> None:
    p = cube_lattice((2, 2, 2), GAPS)
    tol = TOL
    c = Contacts(ContactsConfig(tol=tol, margin=0.0)).compute(p, {})
    # 12 face, 12 edge and 4 body-diagonal neighbour pairs, each at the largest gap it spans
    assert len(c.i) == 28
    g1, g2, g3 = GAPS
    assert sorted(c.threshold.tolist()) == [g1] * 4 + [g2] * 8 + [g3] * 16
    face = np.isclose(np.abs(c.normal).max(axis=1), 1.0)
    axis = np.abs(c.normal).argmax(axis=1)
    delta = p.centre[c.j] - p.centre[c.i]
    single = (np.abs(delta) > 0.5).sum(axis=1) == 1
    for k in np.flatnonzero(single):  # the face contacts: a slab of the grown faces
        a = axis[k]
        assert face[k] and np.sign(c.normal[k, a]) == np.sign(delta[k, a])
        assert c.area[k] == pytest.approx((1 + tol) ** 2, rel=1e-12)
        assert c.volume[k] == pytest.approx((tol - GAPS[a]) * (1 + tol) ** 2, rel=1e-12)
        assert c.width[k] == pytest.approx(np.sqrt(2) * (1 + tol), rel=1e-12)
        mid = 0.5 * (p.centre[c.i[k]] + p.centre[c.j[k]])
        np.testing.assert_allclose(c.point[k], mid, atol=1e-12)
    # an edge contact along z between x and y neighbours: (tol - gx)(tol - gy)(1 + tol)
    xy = (np.abs(delta[:, 2]) < 0.5) & ~single
    assert xy.sum() == 4
    np.testing.assert_allclose(c.volume[xy], (tol - g1) * (tol - g2) * (1 + tol), rtol=1e-12)
    # the larger gap is the one the grown solids close last: its axis is the normal
    np.testing.assert_allclose(np.abs(c.normal[xy]), [[0, 1, 0]] * 4, atol=1e-12)


def test_the_sweep_counts_each_pair_above_its_threshold() -> None:
    p = cube_lattice((2, 2, 2), GAPS)
    c = Contacts(ContactsConfig(tol=TOL, margin=0.0)).compute(p, {})
    assert c.count_per_particle(0.02).sum() == 2 * 4
    assert c.count_per_particle(0.04).sum() == 2 * (4 + 4 + 4)
    assert c.count_per_particle(GAPS[0]).sum() == 0  # strict: touching at tol is no contact
    assert (c.count_per_particle(TOL) == 7).all()


def test_the_equivalent_cap_has_the_contact_volume_and_base() -> None:
    rng = np.random.default_rng(5)
    area = 10.0 ** rng.uniform(-6, 1, 200)
    volume = area * 10.0 ** rng.uniform(-15, 0.5, 200)
    h, r = equivalent_cap(volume, area)
    a2 = area / np.pi
    np.testing.assert_allclose(np.pi * h * (3 * a2 + h * h) / 6, volume, rtol=1e-12)
    np.testing.assert_allclose(r, (a2 + h * h) / (2 * h), rtol=1e-12)
    thin = volume < 1e-9 * area**1.5
    np.testing.assert_allclose(h[thin], 2 * volume[thin] / area[thin], rtol=1e-6)
    assert np.isfinite(h).all() and (h > 0).all()


@pytest.mark.filterwarnings("ignore::FutureWarning")
def test_contacts3d_is_the_one_contacts_analyzer_and_refuses_a_bad_tolerance() -> None:
    p2 = packing_from_polygons([[(0, 0), (1, 0), (1, 1), (0, 1)]], domain=(0, 2, 0, 2))
    with pytest.raises(ConfigError, match=r"^analyzer 'contacts3d' analyses 3D packings, not 2D"):
        regopack.analyze(p2, "contacts3d")  # the old name keeps its dimension
    p = cube_lattice((2, 1, 1), GAPS)
    old = regopack.analyze(p, "contacts3d")["contacts3d"]
    assert old.scalars == regopack.analyze(p, "contacts")["contacts"].scalars
    with pytest.raises(ConfigError, match=r"contacts3d.tol = -1"):
        regopack.analyze(p, "contacts3d", contacts3d__tol=-1.0)


@pytest.mark.filterwarnings("ignore::FutureWarning")
def test_every_3d_analyzer_runs_on_a_lone_particle_and_skips_the_unplaced() -> None:
    import dataclasses

    p = cube_lattice((3, 1, 1), (0.0, 0.0, 0.0))
    centre = p.centre.copy()
    centre[1:] = np.nan  # only the first cube is placed
    lone = dataclasses.replace(p, centre=centre, insertion_index=np.array([0, -1, -1]))
    names = ["density3d", "contacts3d", "coordination3d", "rdf3d", "network3d"]
    res = regopack.analyze(lone, [*names, "homogeneity3d", "psd3d"], contacts3d__margin=0.0)
    assert res["contacts3d"]["n_contacts"] == 0 and res["coordination3d"]["z_domain"] == 0.0
    assert res["network3d"]["anisotropy"] is None and res["rdf3d"]["first_peak_r"] is None
    assert res["psd3d"]["n_placed"] == 1


def test_a_periodic_lattice_of_cubes_touches_across_the_faces() -> None:
    import dataclasses

    from regopack.geometry.domain import PeriodicBox

    # 3 x 3 x 3 cubes of side 1 with a gap of 1/64, as a periodic cell of side 3 (1 + 1/64):
    # grown along their face normals, all 26 neighbours meet at the same threshold, those
    # across the cell's faces included, as the centre cube's do in the walled lattice
    gap = 1 / 64
    p = cube_lattice((3, 3, 3), (gap, gap, gap))
    side = 3 * (1 + gap)
    lo = p.centre.min(axis=0) - 0.5 - gap / 2
    periodic = dataclasses.replace(p, domain=PeriodicBox(*(v for a in lo for v in (a, a + side))))
    c = Contacts(ContactsConfig(tol=0.05, margin=0.0)).compute(periodic, {})
    assert len(c.pairs) == 27 * 26 // 2
    assert np.allclose(c.threshold, gap)
    assert np.all(c.count_per_particle() == 26)
    walled = Contacts(ContactsConfig(tol=0.05, margin=0.0)).compute(p, {})
    assert int(walled.count_per_particle()[13]) == 26
    centre = (walled.i == 13) | (walled.j == 13)
    mine = (c.i == 13) | (c.j == 13)
    assert np.allclose(np.sort(c.area[mine]), np.sort(walled.area[centre]))
    assert np.allclose(np.sort(c.volume[mine]), np.sort(walled.volume[centre]))


def test_a_cube_in_a_periodic_cell_of_its_size_touches_its_own_images() -> None:
    import dataclasses

    from regopack.geometry.domain import PeriodicBox

    gap = 1 / 64
    p = cube_lattice((1, 1, 1), (gap, gap, gap))
    lo = p.centre[0] - 0.5 - gap / 2
    cell = dataclasses.replace(p, domain=PeriodicBox(*(v for a in lo for v in (a, a + 1 + gap))))
    c = Contacts(ContactsConfig(tol=0.05, margin=0.0)).compute(cell, {})
    assert c.pairs.tolist() == [[0, 0]] * 13  # half of its 26 neighbouring images, once each
    assert np.allclose(c.threshold, gap)
    assert c.count_per_particle().tolist() == [26]


def test_the_highs_fallback_gives_the_simplex_threshold_and_normal(packing3d, contacts3d) -> None:
    from regopack.plugins.analyzers.solid_contacts import _fallback_threshold

    for (i, j), tau in list(zip(contacts3d.pairs, contacts3d.threshold, strict=True))[:40:4]:
        half, normal = _fallback_threshold(packing3d, int(i), int(j))
        assert 2 * half == pytest.approx(tau, abs=1e-8)
        p, q = packing3d.world_vertices(i) @ normal, packing3d.world_vertices(j) @ normal
        assert q.min() - p.max() >= -1e-8  # a separating plane too


def test_a_lattice_of_touching_spheres_has_the_known_contacts() -> None:
    from lattices3d import sphere_lattice

    from regopack.geometry.sphere_volume import lens_volume

    tol = 0.05
    p = sphere_lattice((3, 3, 3), 1.0, 0.0)
    c = Contacts(ContactsConfig(tol=tol, margin=0.0)).compute(p, {})
    assert len(c.pairs) == 54  # 3 x 3 x 2 touching neighbours along each axis
    assert np.allclose(c.threshold, 0.0, atol=1e-12)
    grown = 1.0 + tol / 2
    assert np.allclose(c.area, np.pi * (grown**2 - 1.0))  # the disk where the grown surfaces cross
    assert np.allclose(c.volume, lens_volume(grown, grown, 2.0))
    assert np.allclose(np.abs(c.normal).max(axis=1), 1.0)  # along the lattice axes
    assert np.allclose(c.point, 0.5 * (p.centre[c.i] + p.centre[c.j]))
    assert int(c.count_per_particle()[13]) == 6  # the centre sphere
    # a gap of 0.03: in contact at tol = 0.05, not at 0.02
    apart = Contacts(ContactsConfig(tol=tol, margin=0.0)).compute(
        sphere_lattice((2, 1, 1), 1.0, 0.03), {}
    )
    assert apart.threshold == pytest.approx([0.03]) and len(apart.i) == 1
    assert apart.count_per_particle(0.02).sum() == 0


def test_periodic_spheres_touch_across_the_sides_and_their_own_images() -> None:
    from regopack.geometry.domain import PeriodicBox
    from regopack.geometry.sphere_volume import lens_volume

    # a simple cubic lattice of 3 x 3 x 3 touching unit spheres, as a periodic cell: every
    # sphere has six neighbours, those across the cell's faces included
    side = 6.0
    axis = np.arange(3) * 2.0 + 1.0
    c = np.stack(np.meshgrid(axis, axis, axis, indexing="ij"), axis=-1).reshape(-1, 3)
    lattice = Packing.of_spheres(c, np.ones(27), PeriodicBox(0, side, 0, side, 0, side))
    res = Contacts(ContactsConfig(tol=0.05, margin=0.0)).compute(lattice, {})
    assert len(res.pairs) == 27 * 6 // 2
    assert np.all(res.count_per_particle() == 6)
    assert np.allclose(res.threshold, 0.0, atol=1e-12)
    assert np.allclose(res.volume, lens_volume(1.025, 1.025, 2.0))
    # one sphere in a cell of its diameter touches its six images, three pairs of them
    lone = Packing.of_spheres([[1.0, 1.0, 1.0]], [1.0], PeriodicBox(0, 2, 0, 2, 0, 2))
    res = Contacts(ContactsConfig(tol=0.05, margin=0.0)).compute(lone, {})
    assert res.pairs.tolist() == [[0, 0]] * 3 and res.count_per_particle().tolist() == [6]
    # the same spheres shifted by half a period: the same contacts
    moved = Packing.of_spheres(
        np.mod(c + 3.0, side), np.ones(27), PeriodicBox(0, side, 0, side, 0, side)
    )
    again = Contacts(ContactsConfig(tol=0.05, margin=0.0)).compute(moved, {})
    assert len(again.pairs) == 81 and np.all(again.count_per_particle() == 6)
