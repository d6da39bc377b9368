"""Meshes and STL writers for the solid template tests (independent of the reader)."""

from __future__ import annotations

import math
import struct
from pathlib import Path

import numpy as np
from scipy.spatial import ConvexHull

PHI = (1.0 + math.sqrt(5.0)) / 2.0

CUBE = np.array([[x, y, z] for x in (0.0, 1.0) for y in (0.0, 1.0) for z in (0.0, 1.0)])
"""The unit cube: volume 1, centroid (1/2, 1/2, 1/2)."""

TETRAHEDRON = np.array([[0.0, 0.0, 0.0], [1.0, 0.0, 0.0], [0.0, 1.0, 0.0], [0.0, 0.0, 1.0]])
"""The corner tetrahedron: volume 1/6, centroid (1/4, 1/4, 1/4)."""

ICOSAHEDRON = np.array(
    [[0.0, s * 1.0, t * PHI] for s in (-1, 1) for t in (-1, 1)]
    + [[s * 1.0, t * PHI, 0.0] for s in (-1, 1) for t in (-1, 1)]
    + [[t * PHI, 0.0, s * 1.0] for s in (-1, 1) for t in (-1, 1)]
)
"""The icosahedron of edge 2: volume (5/12)(3 + sqrt 5) 2^3, centroid at the origin."""

ICOSAHEDRON_VOLUME = 5.0 / 12.0 * (3.0 + math.sqrt(5.0)) * 8.0

L_PRISM = np.array(
    [[x, y, z] for z in (0.0, 1.0) for x, y in [(0, 0), (2, 0), (2, 1), (1, 1), (1, 2), (0, 2)]],
    dtype=np.float64,
)
"""An L-shaped prism (not convex): its hull cuts the notch off with the plane x + y = 3."""

L_PRISM_HULL_VOLUME = 3.5
"""Area of the L's hull (the 2 x 2 square less the triangle beyond x + y = 3), times 1."""


def hull_volume_and_centroid(points: np.ndarray) -> tuple[float, np.ndarray]:
    """Volume and volume centroid of the hull of ``points``, from Qhull's triangles."""
    hull = ConvexHull(points)
    inside = points[hull.vertices].mean(axis=0)
    tets = points[hull.simplices] - inside
    vol6 = np.abs(np.einsum("ij,ij->i", tets[:, 0], np.cross(tets[:, 1], tets[:, 2])))
    centroid = inside + (vol6[:, None] * tets.sum(axis=1) / 4.0).sum(axis=0) / vol6.sum()
    return float(vol6.sum() / 6.0), centroid


def hull_triangles(points: np.ndarray) -> np.ndarray:
    """Triangles of the hull of ``points``, in Qhull's arbitrary orientation."""
    return np.asarray(points, dtype=np.float64)[ConvexHull(points).simplices]


def l_prism_triangles() -> np.ndarray:
    """A closed, non-convex triangle mesh of the L-shaped prism."""
    bottom = [[0, 1, 2], [0, 2, 3], [0, 3, 5], [3, 4, 5]]
    tris = [[a, c, b] for a, b, c in bottom] + [[a + 6, b + 6, c + 6] for a, b, c in bottom]
    for i in range(6):
        j = (i + 1) % 6
        tris += [[i, j, j + 6], [i, j + 6, i + 6]]
    return L_PRISM[np.array(tris)]


def write_binary(path: Path, triangles: np.ndarray, header: bytes = b"binary test mesh") -> Path:
    """A binary STL (float32 coordinates, zero normals)."""
    tris = np.asarray(triangles, dtype=np.float32).reshape(-1, 9)
    body = b"".join(struct.pack("<12fH", 0.0, 0.0, 0.0, *t.tolist(), 0) for t in tris)
    path.write_bytes(header.ljust(80, b" ")[:80] + struct.pack("<I", len(tris)) + body)
    return path


def ascii_text(triangles: np.ndarray, name: str = "test") -> str:
    """ASCII STL text, coordinates with 17 significant digits (exact float64)."""
    lines = [f"solid {name}"]
    for t in np.asarray(triangles, dtype=np.float64).reshape(-1, 3, 3):
        lines += ["  facet normal 0 0 0", "    outer loop"]
        lines += [f"      vertex {x!r} {y!r} {z!r}" for x, y, z in t.tolist()]
        lines += ["    endloop", "  endfacet"]
    lines.append(f"endsolid {name}")
    return "\n".join(lines) + "\n"


def write_ascii(path: Path, triangles: np.ndarray, name: str = "test") -> Path:
    """An ASCII STL of ``triangles``."""
    path.write_text(ascii_text(triangles, name), encoding="ascii")
    return path
