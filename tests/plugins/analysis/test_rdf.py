"""Radial distribution function."""

from __future__ import annotations

import numpy as np
import pytest

from regopack.plugins.analysis.rdf import Rdf, RdfConfig, rdf_histogram


def test_uniform_points_give_one_at_every_r() -> None:
    a, b = 300.0, 200.0
    curves = []
    for seed in range(6):
        rng = np.random.default_rng(seed)
        n = 4000
        x = rng.uniform(0, a, n)
        y = rng.uniform(0, b, n)
        total, _ = rdf_histogram(x, y, np.zeros(n, dtype=np.int64), 1, 0.0, 5.0, 36, a, b)
        curves.append(total)
    mean = np.mean(curves, axis=0)
    err = np.std(curves, axis=0, ddof=1) / np.sqrt(len(curves))
    assert np.all(np.abs(mean - 1.0) < 4 * err + 0.01)


def test_matches_brute_force_reference() -> None:
    rng = np.random.default_rng(1)
    a, b = 50.0, 40.0
    n = 300
    x, y = rng.uniform(0, a, n), rng.uniform(0, b, n)
    kind = rng.integers(0, 3, n).astype(np.int64)
    lo, width, bins = 1.0, 0.5, 30
    total, per = rdf_histogram(x, y, kind, 3, lo, width, bins, a, b)
    dx = x[:, None] - x[None, :]
    dy = y[:, None] - y[None, :]
    d = np.hypot(dx, dy)
    w = 1.0 / ((a - np.abs(dx)) * (b - np.abs(dy)))
    iu = np.triu_indices(n, 1)
    edges = lo + width * np.arange(bins + 1)
    shell = np.pi * (edges[1:] ** 2 - edges[:-1] ** 2)
    h, _ = np.histogram(d[iu], bins=edges, weights=w[iu])
    ref = h * (a * b) ** 2 / (n * (n - 1) / 2 * shell)
    assert np.allclose(total, ref, rtol=1e-10)
    sel = (kind[iu[0]] == 0) & (kind[iu[1]] == 2) | (kind[iu[0]] == 2) & (kind[iu[1]] == 0)
    h02, _ = np.histogram(d[iu][sel], bins=edges, weights=w[iu][sel])
    n0, n2 = np.sum(kind == 0), np.sum(kind == 2)
    assert np.allclose(per[0, 2], h02 * (a * b) ** 2 / (n0 * n2 * shell), rtol=1e-10)


def test_packing_rdf_has_a_contact_peak() -> None:
    from regopack.manager import default_registry
    from regopack.run import run_scene
    from regopack.scene import load_scene, resolve_scene

    resolved = resolve_scene(load_scene("small", ["count=600"]), default_registry(autoload=False))
    packing = run_scene(resolved, None).packing
    rdf = Rdf(RdfConfig(far=(20.0, 50.0), far_bin=2.0)).compute(packing, {})
    near = rdf.curves["near"]
    assert near["total"][near["r"] < 1.0].max(initial=0.0) == 0.0  # no two centres that close
    assert np.nanmax(near["total"]) > 1.5
    assert "pyroxene-pyroxene" in near


def test_bad_range_names_field() -> None:
    with pytest.raises(ValueError, match="near"):
        RdfConfig(near=(5.0, 1.0))
