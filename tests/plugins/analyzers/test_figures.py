"""Figures of the structure analysis, of 2D and 3D packings."""

from __future__ import annotations

import doctest

import numpy as np
import pytest

pytest.importorskip("regopack.plugins.inserters.available_arc")
pytest.importorskip("matplotlib")

from matplotlib.collections import LineCollection
from matplotlib.image import imread

from regopack.analysis.pipeline import DEFAULT_ANALYSES, run_analyses, write_analysis
from regopack.plugins.analyzers import (
    Contacts,
    ContactsConfig,
    Coordination,
    CoordinationConfig,
    figure_style,
    figures,
)
from regopack.plugins.analyzers.figure_specs import CAPTIONS
from regopack.registry.manager import default_registry
from regopack.run.pipeline import run_scene
from regopack.scenes.model import load_scene, resolve_scene
from regopack.testing import packing_from_polygons

STEMS = ["packing", "contact-network", "contact-histograms", "z-vs-tol", "z-per-mineral", "rdf"]


@pytest.fixture(scope="module")
def registry():
    return default_registry(autoload=False)


@pytest.fixture(scope="module")
def packing(registry):
    return run_scene(resolve_scene(load_scene("small", ["count=300"]), registry)).packing


@pytest.fixture(scope="module")
def analyzers(packing, registry):
    return run_analyses(packing, registry, [(n, {}) for n in DEFAULT_ANALYSES])


def test_every_figure_of_the_default_analyses_is_drawn(packing, analyzers, tmp_path):
    paths = figures.figures_for(packing, analyzers, tmp_path / "figs", formats=("png",))
    assert [p.name for p in paths] == [f"{s}.png" for s in STEMS]
    for path in paths:
        assert path.stat().st_size > 1000
    image = imread(tmp_path / "figs" / "packing.png")
    assert image.shape[1] == pytest.approx(figures.WIDTH * figures.DPI, abs=2)
    assert set(CAPTIONS) == {*STEMS, "homogeneity", "psd", "local-fraction"}


def test_only_the_figures_of_computed_analyzers(packing, registry, tmp_path):
    done = run_analyses(packing, registry, [("rdf", {})])
    files = write_analysis(tmp_path, packing, done)
    assert [p.name for p in files.figures] == ["rdf.png", "rdf.svg"]
    svg = (tmp_path / "figures" / "rdf.svg").read_text(encoding="utf-8")
    assert "centre distance r (µm)" in svg
    assert "<dc:date>" not in svg  # reproducible files
    report = files.report.read_text(encoding="utf-8")
    assert "](figures/rdf.png)" in report
    assert "contact-network" not in report


def test_network_line_widths_are_proportional_to_contact_area(packing, analyzers):
    contacts = analyzers["contacts"]
    fig = figures.draw_network(packing, contacts)
    lines = [c for c in fig.axes[0].collections if isinstance(c, LineCollection)]
    assert len(lines) == 1
    widths = np.asarray(lines[0].get_linewidths())
    assert widths.max() == pytest.approx(figures.MAX_LINE_PT)
    assert np.allclose(widths / widths.max(), contacts.area / contacts.area.max())


def test_mineral_centred_rdf_averages_back_to_the_total(packing, analyzers):
    from regopack.plugins.analyzers.common import interior_mask

    rdf = analyzers["rdf"]
    names = packing.mineral_names
    sel = interior_mask(packing, rdf.results()["interior_margin"])
    counts = np.bincount(packing.mineral[sel], minlength=len(names))
    curves = rdf.curves_fine["near"]  # the pair curves before their bins are merged
    per = figures.mineral_centred_rdf(curves, names, counts.tolist())
    weighted = sum(counts[k] * per[name] for k, name in enumerate(names) if name in per)
    assert np.allclose(weighted / counts.sum(), curves["total"])


def test_exact_z_of_tol_matches_the_sweep(packing, analyzers):
    contacts, coordination = analyzers["contacts"], analyzers["coordination"]
    t, z_dom, z_int = figures._exact_z_of_tol(packing, contacts, 0.02, 0.5)
    for tol, zd, zi in zip(
        coordination.tols, coordination.z_tol_domain, coordination.z_tol_interior, strict=True
    ):
        k = np.searchsorted(t, tol, side="left") - 1  # the curve just below tol
        assert z_dom[max(k, 0)] == pytest.approx(zd)
        assert z_int[max(k, 0)] == pytest.approx(zi)


def test_a_packing_without_contacts_still_draws(tmp_path):
    square = [(0, 0), (1, 0), (1, 1), (0, 1)]
    far = [(x + 5, y + 5) for x, y in square]
    p = packing_from_polygons([square, far], domain=(-1, 7, -1, 7))
    contacts = Contacts(ContactsConfig(margin=0.0)).compute(p, {})
    coordination = Coordination(CoordinationConfig()).compute(p, {"contacts": contacts})
    done = {"contacts": contacts, "coordination": coordination}
    paths = figures.figures_for(p, done, tmp_path)
    assert {path.stem for path in paths} == {"contact-histograms", "z-vs-tol", "z-per-mineral"}


def test_docstring_examples():
    assert doctest.testmod(figures).failed == 0
    assert doctest.testmod(figure_style).failed == 0


@pytest.mark.slow  # 7 s; every default figure is drawn in the default run (below)
def test_write_analysis_draws_what_figures_for_draws(packing, analyzers, tmp_path):
    from regopack.plugins.analyzers.figure_specs import STEMS as OF_ANALYZER

    drawn = figures.figures_for(packing, analyzers, tmp_path / "all", formats=("png",))
    files = write_analysis(tmp_path / "analysis", packing, analyzers)
    pngs = [p.name for p in files.figures if p.suffix == ".png"]
    assert pngs == [p.name for p in drawn]
    assert set(CAPTIONS) == {s for stems in OF_ANALYZER.values() for s in stems}


def test_zoom_titles_show_a_round_length(packing, analyzers):
    """The zoom's side is a round length, and the titles print it as such."""
    placed = packing.placed
    raw = max(200.0 / 8, 20.0 * float(packing.radius[placed].mean()))
    assert raw != pytest.approx(round(raw))  # the side the zoom had, e.g. 64.2735 µm
    side = figures.nice_length(raw)
    fig = figures.draw_packing(packing)
    assert fig.axes[1].get_title() == f"zoom: {side:g} × {side:g} µm at the centre"
    x0, x1 = fig.axes[1].get_xlim()
    assert x1 - x0 == pytest.approx(side)
    network = figures.draw_network(packing, analyzers["contacts"])
    assert network.axes[1].get_title().startswith(f"zoom, {side:g} × {side:g} µm")


def test_nice_lengths():
    assert [figures.nice_length(v) for v in (128.447, 100.0, 33.0, 7.1, 0.0173)] == [
        120.0,
        100.0,
        30.0,
        8.0,
        0.015,
    ]
    assert figures.nice_length(128.447, most=110.0) == 100.0
    assert figures.nice_length(0.5, most=0.3) == 0.3
    assert figures.length_text(128.447) == "128"


def test_a_mineral_has_its_colour_whatever_the_phase_order(packing):
    """Glass is bluish green in every scene; the legend and the particles agree."""
    from regopack.base.colours import MINERAL_COLOURS, mineral_colours

    names = list(packing.mineral_names)
    assert mineral_colours(names) == mineral_colours(names[::-1])[::-1]
    assert mineral_colours(["olivine", "glass"]) == [
        MINERAL_COLOURS["olivine"],
        MINERAL_COLOURS["glass"],
    ]
    assert mineral_colours(["Glass", "plagioclase"]) == ["#009E73", "#56B4E9"]
    # unknown names: fixed by the name, distinct within a scene
    odd = mineral_colours(["troilite", "agglutinate", "spinel"])
    assert len(set(odd)) == 3 and not set(odd) & set(MINERAL_COLOURS.values())
    assert mineral_colours(["spinel"]) == mineral_colours(["spinel", "glass"])[:1]
    # the packing figure colours each particle by its mineral's name
    fig = figures.draw_packing(packing)
    legend = {
        t.get_text().split(" (")[0]: h.get_facecolor()
        for t, h in zip(fig.legends[0].get_texts(), fig.legends[0].legend_handles, strict=True)
    }
    from matplotlib.colors import to_rgba

    for name, colour in zip(names, mineral_colours(names), strict=True):
        assert legend[name] == pytest.approx(to_rgba(colour))


def test_lengths_are_labelled_in_the_scenes_unit_at_its_scale(packing):
    from regopack.plugins.analyzers.figures import draw_packing, draw_rdf
    from regopack.testing import scaled_packing

    in_mm = scaled_packing(packing, 1e-3)
    in_mm.scene["length_unit"] = "mm"
    ax, zoom = draw_packing(in_mm).axes[:2]
    assert ax.get_xlabel() == "x (10⁻³ mm)" and zoom.get_ylabel() == "y (10⁻³ mm)"
    assert "mm" in ax.get_title() and "µm" not in ax.get_title()
    done = run_analyses(in_mm, default_registry(), [("rdf", {})])
    near = draw_rdf(in_mm, done["rdf"]).axes[0]  # type: ignore[arg-type]
    assert near.get_xlabel() == "centre distance r (mm)"
    assert near.get_title() == "near field, bins of 0.0001 mm"  # d_min / 20
    peak = [t.get_text() for t in near.texts if "first peak" in t.get_text()]
    assert peak and peak[0].endswith(" mm") and "0.00" in peak[0]  # 5 decimals in mm
    assert draw_packing(packing).axes[0].get_xlabel() == "x (µm)"


def test_merged_curves_are_drawn_as_steps_over_their_bins(packing, analyzers):
    """A rare mineral's curve is one step per merged bin, from its lower edge to its upper one."""
    from matplotlib.patches import StepPatch

    fig = figures.draw_rdf(packing, analyzers["rdf"])
    near = fig.axes[0]
    steps = [p for p in near.patches if isinstance(p, StepPatch)]
    assert steps  # the packing's rare minerals
    for step in steps:
        edges = step.get_data().edges
        assert edges[0] == 0.0 and edges[-1] == pytest.approx(10.0)
        assert np.all(np.diff(edges) > 0.15)  # merged: wider than the 0.1 µm bins
    # the total and the common minerals keep the fine bins, as lines
    assert [line.get_drawstyle() for line in near.get_lines()] == ["default"] * len(
        near.get_lines()
    )


def test_a_top_without_a_distinct_peak_is_labelled_as_a_plateau(packing, analyzers):
    rdf = analyzers["rdf"]
    assert not rdf.peak.distinct  # 300 particles: a noisy top
    texts = [t.get_text() for t in figures.draw_rdf(packing, rdf).axes[0].texts]
    lo, hi = rdf.results()["first_plateau"]
    assert f" no distinct first peak: plateau {lo:.2f}–{hi:.2f} µm" in texts
    assert not [t for t in texts if "±" in t]


def test_the_z_distribution_is_drawn_as_bars(packing, analyzers):
    """Z is an integer: one bar per mineral at each Z, no line joining the values."""
    from matplotlib.container import BarContainer

    coordination = analyzers["coordination"]
    fig = figures.draw_z_per_mineral(packing, coordination)
    ax = fig.axes[0]
    assert not ax.get_lines()
    bars = [c for c in ax.containers if isinstance(c, BarContainer)]
    present = np.unique(packing.mineral[coordination.interior])
    assert len(bars) == len(present)
    for container in bars:
        heights = [bar.get_height() for bar in container]
        assert sum(heights) == pytest.approx(1.0)  # each mineral's fractions
        left = np.array([bar.get_x() for bar in container])
        width = container[0].get_width()
        centres = left + 0.5 * width
        # each bar sits within its integer's group of width Z_BARS_WIDTH
        assert np.all(np.abs(centres - np.round(centres)) < 0.5 * figures.Z_BARS_WIDTH)


def test_the_3d_figures_are_written_and_embedded(packing3d, analysed3d, tmp_path) -> None:
    from regopack.plugins.analyzers.figure_specs import STEMS3D
    from regopack.plugins.analyzers.homogeneity import Homogeneity
    from regopack.plugins.analyzers.psd import Psd

    stems = [stem for stems in STEMS3D.values() for stem in stems]
    analyzers = {
        **analysed3d.analyzers,
        "psd3d": Psd().compute(packing3d, {}),
        "homogeneity3d": Homogeneity().compute(packing3d, {}),
    }
    files = write_analysis(tmp_path / "a", packing3d, analyzers)
    names = sorted(p.name for p in files.figures)
    assert names == sorted([f"{s}.png" for s in stems] + [f"{s}.svg" for s in stems])
    report = files.report.read_text(encoding="utf-8")
    for stem in stems:
        image = imread(tmp_path / "a" / "figures" / f"{stem}.png")
        assert image.shape[1] == round(figures.WIDTH * figures.DPI)  # 7 inches wide at 300 dpi
        assert f"(figures/{stem}.png)" in report
    assert "Coordination number per mineral (3D)" in report


def test_the_3d_rdf_draws_merged_curves_as_steps(packing3d, analysed3d) -> None:
    from matplotlib.patches import StepPatch

    rdf = analysed3d["rdf3d"].analyzer
    fig = figures.draw_rdf(packing3d, rdf)
    near = fig.axes[0]
    steps = [p for p in near.patches if isinstance(p, StepPatch)]
    same = [c for k, c in rdf.pair_curves["near"].items() if k.split("-")[0] == k.split("-")[1]]
    merged = [c for c in same if c.g.size > 1 and c.widest > 0.15]  # one bin: not drawn
    assert len(steps) == len(merged) > 0
    for step, curve in zip(steps, merged, strict=True):
        np.testing.assert_allclose(step.get_data().edges, curve.edges)
    texts = " ".join(t.get_text() for t in near.texts)
    assert "no distinct first peak: plateau" in texts
