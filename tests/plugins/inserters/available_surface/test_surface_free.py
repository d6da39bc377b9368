"""The free part of a candidate envelope's boundary and sampling on it."""

from __future__ import annotations

import numpy as np
import pytest
import shapely
from hypothesis import given, settings
from hypothesis import strategies as st
from scipy.stats import chisquare
from surface_helpers import (
    box,
    circumradius,
    crowded_scene,
    depth_on_boundary,
    face_samples,
    free_mask,
    overlap_depth,
    overlap_volume,
    random_polyhedron,
    rotation,
    transformed,
)

from regopack.plugins.inserters.available_surface.envelope import minkowski_envelope
from regopack.plugins.inserters.available_surface.free_surface import (
    FREE_EPS,
    THIN_FACTOR,
    FreeSurface,
    free_surface,
    interferers_from,
    sample_free_point,
)
from regopack.plugins.inserters.available_surface.polyhedron import (
    Polyhedron,
    face_area,
    plane_basis,
)

OPEN = (np.full(3, -np.inf), np.full(3, np.inf))
NO_PLANES = np.zeros((0, 4))


def run(scene: dict, lo: np.ndarray = OPEN[0], hi: np.ndarray = OPEN[1]) -> FreeSurface:
    it = interferers_from(scene["envelopes"], scene["centres"])
    return free_surface(scene["ek"], scene["centre"], it, lo, hi, NO_PLANES)


def per_face_area(fs: FreeSurface, nfaces: int) -> np.ndarray:
    areas = np.diff(np.concatenate([[0.0], fs.cumulative]))
    return np.bincount(fs.face, weights=areas, minlength=nfaces)


def total_area(env: Polyhedron) -> float:
    return sum(face_area(env, f) for f in range(len(env.normals)))


def samples(fs: FreeSurface, n: int, seed: int) -> np.ndarray:
    u = np.random.default_rng(seed).random((n, 3))
    return np.array([sample_free_point(fs, *row) for row in u])


def check_against_oracle(scene: dict, lo: np.ndarray, hi: np.ndarray, per_face: int) -> None:
    """The exact free area of every face against the fraction of uniform points found free."""
    fs = run(scene, lo, hi)
    ek = scene["ek"]
    nf = len(ek.normals)
    exact = per_face_area(fs, nf)
    rng = np.random.default_rng(0)
    estimate = 0.0
    variance = 0.0
    for f in range(nf):
        area = face_area(ek, f)
        p = min(max(exact[f] / area, 0.0), 1.0)
        pts = face_samples(ek, f, per_face, rng) + scene["centre"]
        hits = int(free_mask(pts, scene["envelopes"], scene["centres"], lo, hi).sum())
        sigma = np.sqrt(per_face * p * (1.0 - p))
        assert abs(hits - per_face * p) <= 5.0 * sigma + 2.0, (f, hits, per_face * p)
        estimate += area * hits / per_face
        variance += area**2 * p * (1.0 - p) / per_face
    assert abs(estimate - fs.area) <= 5.0 * np.sqrt(variance) + 1e-9 * total_area(ek)


def check_samples(scene: dict, fs: FreeSurface, lo: np.ndarray, hi: np.ndarray, n: int) -> None:
    """Sampled points lie on the envelope's boundary and are free (up to the tolerance)."""
    rk = circumradius(scene["ek"])
    pts = samples(fs, n, 1)
    assert np.all(np.abs(depth_on_boundary(pts, scene["ek"], scene["centre"])) <= 1e-9 * rk)
    slack = 2.0 * THIN_FACTOR * FREE_EPS * rk
    assert np.all(free_mask(pts, scene["envelopes"], scene["centres"], lo, hi, slack))


def six_neighbours(q: Polyhedron, rot: np.ndarray | None = None) -> dict:
    """A unit cube enclosed by six face-touching unit cubes, and the new particle ``q``."""
    r = np.eye(3) if rot is None else rot
    cube = box(1.0, r)
    centres = np.vstack([2.0 * np.eye(3), -2.0 * np.eye(3)]) @ r.T
    env = minkowski_envelope(cube, q)
    return {
        "pk": cube,
        "q": q,
        "centre": np.zeros(3),
        "ek": env,
        "pjs": [cube] * 6,
        "centres": centres,
        "envelopes": [env] * 6,
    }


def test_no_interferers_leave_the_whole_boundary() -> None:
    rng = np.random.default_rng(3)
    env = minkowski_envelope(random_polyhedron(rng), random_polyhedron(rng, 16, 0.5))
    scene = {"ek": env, "centre": np.array([1.0, 2.0, 3.0]), "envelopes": [], "centres": []}
    fs = run(scene)
    assert fs.area == pytest.approx(total_area(env), rel=1e-12)
    assert sorted(fs.face.tolist()) == list(range(len(env.normals)))
    assert np.allclose(per_face_area(fs, len(env.normals)),
                       [face_area(env, f) for f in range(len(env.normals))])  # fmt: skip


@pytest.mark.parametrize("seed", range(3))
def test_pieces_are_convex_counter_clockwise_and_on_their_faces(seed: int) -> None:
    scene = crowded_scene(np.random.default_rng(seed), 8, gap=(1.0, 1.5))
    fs = run(scene)
    ek = scene["ek"]
    rk = circumradius(ek)
    assert fs.area > 0.0
    for i in range(len(fs.cumulative)):
        pts = fs.points[fs.offsets[i] : fs.offsets[i + 1]]
        f = fs.face[i]
        assert np.all(np.abs((pts - scene["centre"]) @ ek.normals[f] - ek.support[f]) <= 1e-9 * rk)
        turns = np.cross(np.roll(pts, -1, 0) - pts, np.roll(pts, -2, 0) - np.roll(pts, -1, 0))
        assert np.all(turns @ ek.normals[f] > 0.0)


@pytest.mark.parametrize("small", ["cube", "random"])
@pytest.mark.parametrize("rotated", [False, True])
def test_a_cube_enclosed_by_six_cubes_has_no_free_surface(small: str, rotated: bool) -> None:
    rng = np.random.default_rng(11)
    rot = rotation(rng) if rotated else None
    q = box(0.1, rot) if small == "cube" else random_polyhedron(rng, 12, 0.1)
    scene = six_neighbours(q, rot)
    fs = run(scene)
    assert fs.area == 0.0 and len(fs.cumulative) == 0
    with pytest.raises(ValueError):
        sample_free_point(fs, 0.5, 0.5, 0.5)
    # one neighbour less opens one face of the candidate and the strips next to it
    scene["envelopes"] = scene["envelopes"][1:]
    scene["centres"] = scene["centres"][1:]
    assert run(scene).area > 0.0


def test_five_cubes_leave_exactly_the_open_face() -> None:
    scene = six_neighbours(box(0.1))
    scene["envelopes"] = scene["envelopes"][:5]  # no neighbour at -z
    scene["centres"] = scene["centres"][:5]
    fs = run(scene)
    assert fs.area == pytest.approx(2.2**2, rel=1e-12)
    pts = samples(fs, 50, 0)
    assert np.allclose(pts[:, 2], -1.1)


@pytest.mark.parametrize("seed", range(4))
def test_free_area_against_a_sampling_oracle(seed: int) -> None:
    rng = np.random.default_rng(seed)
    scene = crowded_scene(rng, int(rng.integers(3, 12)), gap=(1.0, 1.6))
    rk = circumradius(scene["ek"])
    c = scene["centre"]
    lo = np.array([-np.inf, -np.inf, c[2] - 0.6 * rk])
    hi = np.array([c[0] + 0.7 * rk, np.inf, np.inf])
    check_against_oracle(scene, lo, hi, per_face=400)
    check_against_oracle(scene, *OPEN, per_face=200)


@pytest.mark.parametrize("scale", [1e-6, 1e6])
@pytest.mark.parametrize("ratio", [1e-3, 1.0, 1e3])
def test_scales_and_size_ratios(scale: float, ratio: float) -> None:
    rng = np.random.default_rng(int(ratio * 10) + 7)
    scene = crowded_scene(rng, 6, scale=scale, ratio=ratio, gap=(1.0, 1.4))
    rk = circumradius(scene["ek"])
    c = scene["centre"]
    lo = np.array([c[0] - 0.8 * rk, -np.inf, -np.inf])
    hi = np.full(3, np.inf)
    check_against_oracle(scene, lo, hi, per_face=200)
    fs = run(scene, lo, hi)
    if fs.area > 0.0:
        check_samples(scene, fs, lo, hi, 200)


@given(seed=st.integers(0, 2**32 - 1), scale=st.sampled_from([1e-6, 1.0, 1e6]))
@settings(max_examples=25, deadline=None)
def test_sampled_points_are_free_and_on_the_envelope(seed: int, scale: float) -> None:
    rng = np.random.default_rng(seed)
    scene = crowded_scene(rng, int(rng.integers(0, 15)), scale=scale, gap=(1.0, 1.5))
    rk = circumradius(scene["ek"])
    c = scene["centre"]
    lo = c - rng.uniform(0.3, 2.0, 3) * rk
    hi = c + rng.uniform(0.3, 2.0, 3) * rk
    fs = run(scene, lo, hi)
    if fs.area > 0.0:
        check_samples(scene, fs, lo, hi, 100)


@pytest.mark.parametrize("seed", range(3))
def test_a_particle_placed_at_a_sample_touches_and_overlaps_nothing(seed: int) -> None:
    rng = np.random.default_rng(seed + 100)
    scene = crowded_scene(rng, 10, gap=(1.0, 1.4))
    fs = run(scene)
    assert fs.area > 0.0
    rk = circumradius(scene["ek"])
    pk = scene["pk"].vertices + scene["centre"]
    for x in samples(fs, 15, seed):
        q = scene["q"].vertices + x
        assert abs(overlap_depth(q, pk)) <= 1e-8 * rk  # touches P_k
        for pj, cj in zip(scene["pjs"], scene["centres"], strict=True):
            assert overlap_depth(q, pj.vertices + cj) <= 1e-8 * rk
            assert overlap_volume(q, pj.vertices + cj) <= 1e-12 * rk**3


def test_uniform_on_the_faces_of_a_cube() -> None:
    env = minkowski_envelope(box(1.0), box(0.25))  # a cube of half size 1.25
    fs = run({"ek": env, "centre": np.zeros(3), "envelopes": [], "centres": []})
    pts = samples(fs, 30000, 5)
    axis = np.argmax(np.abs(pts), axis=1)
    face = 2 * axis + (pts[np.arange(len(pts)), axis] > 0)
    cells = np.zeros(len(pts), dtype=np.int64)
    for k, p in enumerate(pts):
        a, b = [d for d in range(3) if d != axis[k]]
        i = min(int((p[a] + 1.25) / 0.5), 4)
        j = min(int((p[b] + 1.25) / 0.5), 4)
        cells[k] = 25 * face[k] + 5 * i + j
    counts = np.bincount(cells, minlength=150)
    assert chisquare(counts).pvalue > 1e-4


@pytest.mark.parametrize("seed", range(2))
def test_uniform_over_the_free_pieces(seed: int) -> None:
    """Chi-square over bins cut independently of the pieces: faces halved by random lines."""
    rng = np.random.default_rng(seed + 20)
    scene = crowded_scene(rng, 8, gap=(1.0, 1.6))
    fs = run(scene)
    ek = scene["ek"]
    c = scene["centre"]
    n = 40000
    pts = samples(fs, n, seed)
    face_of_point = np.argmin(np.abs((pts - c) @ ek.normals.T - ek.support), axis=1)
    expected = []
    observed = []
    for f in np.unique(fs.face):
        e1, e2 = plane_basis(ek.normals[f])
        polys = []
        for i in np.flatnonzero(fs.face == f):
            p3 = fs.points[fs.offsets[i] : fs.offsets[i + 1]] - c
            polys.append(shapely.Polygon(np.column_stack([p3 @ e1, p3 @ e2])))
        region = shapely.union_all(polys)
        mid = np.array(region.centroid.coords[0])
        normal = rng.normal(size=2)
        on_face = face_of_point == f
        side = (np.column_stack([(pts - c) @ e1, (pts - c) @ e2]) - mid) @ normal > 0
        corners = np.array(region.convex_hull.exterior.coords)
        big = 4.0 * float(np.max(np.linalg.norm(corners - mid, axis=1)))
        half = shapely.Polygon([mid + big * np.array(d) for d in _half_plane_corners(normal)])
        area_pos = region.intersection(half).area
        for area, mask in ((area_pos, side), (region.area - area_pos, ~side)):
            expected.append(n * area / fs.area)
            observed.append(int(np.sum(on_face & mask)))
    expected = np.array(expected)
    observed = np.array(observed)
    keep = expected >= 5.0
    obs = np.append(observed[keep], observed[~keep].sum())
    exp = np.append(expected[keep], expected[~keep].sum())
    if exp[-1] < 5.0:
        obs, exp = obs[:-1], exp[:-1]
    assert observed.sum() == n  # every point is on one face's free region
    assert chisquare(obs, exp * obs.sum() / exp.sum()).pvalue > 1e-4


def test_chi_square_over_the_pieces() -> None:
    """Each point is found in its piece geometrically; counts against the pieces' areas."""
    scene = crowded_scene(np.random.default_rng(31), 10, gap=(1.0, 1.6))
    fs = run(scene)
    ek = scene["ek"]
    n = 20000
    pts = samples(fs, n, 7)
    rk = circumradius(ek)
    owner = np.full(n, -1)
    for i in range(len(fs.cumulative)):
        corners = fs.points[fs.offsets[i] : fs.offsets[i + 1]]
        normal = ek.normals[fs.face[i]]
        on_plane = np.abs((pts - corners[0]) @ normal) <= 1e-9 * rk
        edges = np.roll(corners, -1, 0) - corners
        # inside: to the left of every edge, seen from outside
        left = np.einsum("ijk,k->ij", np.cross(edges[None], pts[:, None] - corners[None]), normal)
        inside = on_plane & np.all(left >= -1e-12 * rk**2, axis=1) & (owner < 0)
        owner[inside] = i
    assert np.all(owner >= 0)
    counts = np.bincount(owner, minlength=len(fs.cumulative)).astype(float)
    expected = n * np.diff(np.concatenate([[0.0], fs.cumulative])) / fs.area
    keep = expected >= 5.0
    obs = np.append(counts[keep], counts[~keep].sum())
    exp = np.append(expected[keep], expected[~keep].sum())
    assert chisquare(obs, exp * obs.sum() / exp.sum()).pvalue > 1e-4


def _half_plane_corners(normal: np.ndarray) -> list[tuple[float, float]]:
    """Corners (unit scale, about 0) of a big square on the side ``normal`` points to."""
    u = normal / np.linalg.norm(normal)
    v = np.array([-u[1], u[0]])
    return [tuple(v), tuple(v + 2 * u), tuple(-v + 2 * u), tuple(-v)]


@pytest.mark.parametrize("rotated", [False, True])
def test_an_envelope_touching_a_face_removes_nothing(rotated: bool) -> None:
    rot = rotation(np.random.default_rng(5)) if rotated else np.eye(3)
    q = box(0.1, rot)
    cube = box(1.0, rot)
    env = minkowski_envelope(cube, q)  # half size 1.1
    full = total_area(env)
    # the neighbour's envelope touches the candidate's along the face x = 1.1
    touching = np.array([[2.2, 0.0, 0.0]]) @ rot.T
    scene = {"ek": env, "centre": np.zeros(3), "envelopes": [env], "centres": touching}
    assert run(scene).area == pytest.approx(full, rel=1e-12)
    # overlapping by 1e-9 of the size removes that face (and strips 1e-9 wide)
    scene["centres"] = np.array([[2.2 - 1.1e-9, 0.0, 0.0]]) @ rot.T
    assert run(scene).area == pytest.approx(full - 2.2**2, rel=1e-7)


@pytest.mark.parametrize("seed", range(4))
def test_an_envelope_touching_at_a_vertex_or_edge_removes_nothing(seed: int) -> None:
    rng = np.random.default_rng(seed + 40)
    scene = crowded_scene(rng, 0)
    ek = scene["ek"]
    full = total_area(ek)
    env = minkowski_envelope(random_polyhedron(rng), scene["q"])
    f = int(rng.integers(len(ek.normals)))
    n = ek.normals[f]
    # put the neighbour beyond face f's plane, touching it; its deepest point
    # lies on the face when the face is large enough, else on the plane beside it
    reach = float(np.max(env.vertices @ -n))
    centre = scene["centre"] + (ek.support[f] + reach) * n
    scene.update(envelopes=[env], centres=centre[None])
    assert run(scene).area == pytest.approx(full, rel=1e-12)
    scene["centres"] = (centre - 1e-9 * circumradius(ek) * n)[None]
    assert run(scene).area <= full * (1.0 + 1e-12)


def test_the_box_cuts_faces_and_a_face_on_the_box_is_free() -> None:
    env = minkowski_envelope(box(1.0), box(0.1))  # half size 1.1
    scene = {"ek": env, "centre": np.zeros(3), "envelopes": [], "centres": []}
    # the box ends exactly at the face z = 1.1 and cuts the faces at x = 0.5
    lo = np.array([-np.inf, -np.inf, -np.inf])
    hi = np.array([0.5, np.inf, 1.1])
    fs = run(scene, lo, hi)
    # x <= 0.5: the -x face, the top and bottom (1.6 x 2.2) and the y faces (1.6 x 2.2)
    assert fs.area == pytest.approx(2.2**2 + 4 * 1.6 * 2.2, rel=1e-12)
    # a box below the face removes it
    hi[2] = 1.1 - 1e-9
    assert run(scene, lo, hi).area == pytest.approx(2.2**2 + 3 * 1.6 * 2.2, rel=1e-7)


def test_many_interferers_on_one_face() -> None:
    """A grid of small cubes centred on one face cuts it into many pieces."""
    small = box(0.01)
    env = minkowski_envelope(box((5.0, 5.0, 1.0)), small)  # half sizes 5.01, 5.01, 1.01
    holes = minkowski_envelope(box(0.19), small)  # half size 0.2
    grid = np.array([(x, y, 1.01) for x in np.arange(-4.5, 5.0) for y in np.arange(-4.5, 5.0)])
    scene = {"ek": env, "centre": np.zeros(3), "envelopes": [holes] * 100, "centres": grid}
    fs = run(scene)
    top = int(np.argmax(env.normals[:, 2]))
    assert np.sum(fs.face == top) > 100  # more than the first buffers hold
    assert fs.area == pytest.approx(total_area(env) - 100 * 0.4**2, rel=1e-10)
    pts = samples(fs, 500, 3)
    assert np.all(free_mask(pts, scene["envelopes"], grid, *OPEN))


def test_a_candidate_inside_an_interferer_has_nothing_free() -> None:
    env = minkowski_envelope(box(1.0), box(0.1))
    big = minkowski_envelope(box(5.0), box(0.1))
    scene = {"ek": env, "centre": np.zeros(3), "envelopes": [big], "centres": np.zeros((1, 3))}
    assert run(scene).area == 0.0


def test_the_culling_radii_only_cull() -> None:
    scene = crowded_scene(np.random.default_rng(9), 10, gap=(1.0, 1.5))
    culled = run(scene)
    it = interferers_from(scene["envelopes"], scene["centres"], np.full(10, np.inf))
    plain = free_surface(scene["ek"], scene["centre"], it, *OPEN, NO_PLANES)
    assert plain.area == pytest.approx(culled.area, rel=1e-12)
    far = interferers_from(
        scene["envelopes"], scene["centres"] + 1e3, [circumradius(e) for e in scene["envelopes"]]
    )
    assert free_surface(scene["ek"], scene["centre"], far, *OPEN, NO_PLANES).area == pytest.approx(
        total_area(scene["ek"]), rel=1e-12
    )


def test_interferers_from_checks_its_input() -> None:
    env = minkowski_envelope(box(1.0), box(0.1))
    with pytest.raises(ValueError):
        interferers_from([env], np.zeros((2, 3)))
    it = interferers_from([env, env], np.zeros((2, 3)))
    assert it.offsets.tolist() == [0, 6, 12]
    assert np.allclose(it.radii, np.sqrt(3) * 1.1)
    empty = interferers_from([], np.zeros((0, 3)))
    assert empty.normals.shape == (0, 3) and empty.offsets.tolist() == [0]


def test_sampling_follows_the_pieces_areas() -> None:
    """``u1`` selects the piece by cumulative area: the fraction of draws per piece."""
    scene = crowded_scene(np.random.default_rng(2), 8, gap=(1.0, 1.6))
    fs = run(scene)
    u1 = (np.arange(2000) + 0.5) / 2000
    pts = np.array([sample_free_point(fs, u, 0.3, 0.3) for u in u1])
    # each point lies in the piece whose cumulative-area interval holds u1
    piece = np.searchsorted(fs.cumulative, u1 * fs.area, side="right")
    for x, i in zip(pts, piece, strict=True):
        corners = fs.points[fs.offsets[i] : fs.offsets[i + 1]]
        normal = scene["ek"].normals[fs.face[i]]
        edges = np.roll(corners, -1, 0) - corners
        inside = np.cross(edges, x - corners) @ normal
        assert np.all(inside >= -1e-9 * circumradius(scene["ek"]))


def test_rotating_the_scene_keeps_the_free_area() -> None:
    rng = np.random.default_rng(4)
    scene = crowded_scene(rng, 8, gap=(1.0, 1.5))
    rot = rotation(rng)
    turned = {
        "ek": transformed(scene["ek"], 1.0, rot),
        "centre": scene["centre"] @ rot.T,
        "envelopes": [transformed(e, 1.0, rot) for e in scene["envelopes"]],
        "centres": scene["centres"] @ rot.T,
    }
    assert run(turned).area == pytest.approx(run(scene).area, rel=1e-9)


def test_the_covering_interferers_are_remembered_most_recent_first() -> None:
    from regopack.plugins.inserters.available_surface.free_surface import _remember

    last = np.full(4, -1, dtype=np.int64)
    for q in (5, 7, 9):  # found by the loop over the interferers
        _remember(last, last.shape[0] - 1, q)
    assert last.tolist() == [9, 7, 5, -1]
    _remember(last, 2, 5)  # found again in its slot
    assert last.tolist() == [5, 9, 7, -1]
    _remember(last, last.shape[0] - 1, 7)  # already listed: moved, not repeated
    assert last.tolist() == [7, 5, 9, -1]
    for q in (1, 2):
        _remember(last, last.shape[0] - 1, q)
    assert last.tolist() == [2, 1, 7, 5]  # the oldest goes
