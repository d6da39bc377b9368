"""Figures of the 3D analyses: drawn into the analysis folder, at journal width, in the report."""

from __future__ import annotations

import numpy as np
import pytest

pytest.importorskip("matplotlib")

from matplotlib.image import imread

from regopack.analysis.pipeline import write_analysis
from regopack.plugins.analyzers.figure_specs import STEMS3D
from regopack.plugins.analyzers.figures import DPI, WIDTH

STEMS = [stem for stems in STEMS3D.values() for stem in stems]


def test_the_3d_figures_are_written_and_embedded(packing3d, analysed3d, tmp_path) -> None:
    from regopack.plugins.analyzers.homogeneity3d import Homogeneity3D
    from regopack.plugins.analyzers.psd3d import Psd3D

    analyzers = {
        **analysed3d.analyzers,
        "psd3d": Psd3D().compute(packing3d, {}),
        "homogeneity3d": Homogeneity3D().compute(packing3d, {}),
    }
    files = write_analysis(tmp_path / "a", packing3d, analyzers)
    names = sorted(p.name for p in files.figures)
    assert names == sorted([f"{s}.png" for s in STEMS] + [f"{s}.svg" for s in STEMS])
    report = files.report.read_text(encoding="utf-8")
    for stem in STEMS:
        image = imread(tmp_path / "a" / "figures" / f"{stem}.png")
        assert image.shape[1] == round(WIDTH * DPI)  # 7 inches wide at 300 dpi
        assert f"(figures/{stem}.png)" in report
    assert "Coordination number per mineral (3D)" in report


def test_the_3d_rdf_draws_merged_curves_as_steps(packing3d, analysed3d) -> None:
    from matplotlib.patches import StepPatch

    from regopack.plugins.analyzers.figures3d import draw_rdf3d

    rdf = analysed3d["rdf3d"].analyzer
    fig = draw_rdf3d(packing3d, rdf)
    near = fig.axes[0]
    steps = [p for p in near.patches if isinstance(p, StepPatch)]
    same = [c for k, c in rdf.pair_curves["near"].items() if k.split("-")[0] == k.split("-")[1]]
    merged = [c for c in same if c.g.size > 1 and c.widest > 0.15]  # one bin: not drawn
    assert len(steps) == len(merged) > 0
    for step, curve in zip(steps, merged, strict=True):
        np.testing.assert_allclose(step.get_data().edges, curve.edges)
    texts = " ".join(t.get_text() for t in near.texts)
    assert "no distinct first peak: plateau" in texts
