"""Counts are written as JSON integers: in summary.json and in the packing's stats."""

from __future__ import annotations

import json

import pytest

from regopack.packing.core import load
from regopack.registry.manager import default_registry
from regopack.run.pipeline import run_scene
from regopack.scenes.model import load_scene, resolve_scene

COUNTS = {
    "available-arc": ("candidate_analyses", "empty_analyses"),
    "available-arc-sweep": (
        "candidate_analyses",
        "empty_analyses",
        "zone_raises",
        "refused",
        "not_offered",
    ),
    "rsa": ("attempts", "rejected_attempts", "not_tried"),
}
OVERRIDES = {
    "available-arc": [],
    "available-arc-sweep": ['insertion.order="sweep"'],
    "rsa": ['insertion={kind="rsa"}'],
}


@pytest.mark.parametrize("case", sorted(COUNTS))
def test_counts_of_a_real_run_are_integers_in_summary_json(case, tmp_path):
    overrides = ["count=60", "domain.width=80", "domain.height=80", *OVERRIDES[case]]
    scene = resolve_scene(load_scene("small", overrides), default_registry())
    run_scene(scene, out_dir=tmp_path / "run")
    text = (tmp_path / "run" / "summary.json").read_text(encoding="utf-8")
    summary = json.loads(text)
    for key in ("tried", "placed", "not_placed", *COUNTS[case]):
        assert type(summary[key]) is int, (key, summary[key])
        assert f'"{key}": {summary[key]},' in text or f'"{key}": {summary[key]}\n' in text
    stats = load(tmp_path / "run" / "packing.npz").stats
    for key in COUNTS[case]:
        assert type(stats[key]) is int, (key, stats[key])
