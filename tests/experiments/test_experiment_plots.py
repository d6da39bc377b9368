from __future__ import annotations

import argparse
import csv
import math
from pathlib import Path

import numpy as np
import pytest
from rich.console import Console

from regopack.cli.sweep import run_sweep_command
from regopack.experiments.plots import fit_power_law, plot_experiment, seed_statistics
from regopack.geometry.domain import Rectangle
from regopack.packing.core import Packing
from regopack.packing.voids import free_space_mask, spans, void_metrics

SMALL = """\
name = "{name}"
base = "small"
{extra}

[set]
count = 150
"outputs.analyses" = ["density", "coordination"]

[sweep]
{sweep}
"""


def _sweep(tmp_path: Path, name: str, sweep: str, extra: str = "") -> Path:
    path = tmp_path / f"{name}.toml"
    path.write_text(SMALL.format(name=name, sweep=sweep, extra=extra), encoding="utf-8")
    out = tmp_path / name
    args = argparse.Namespace(
        experiment=path,
        builtin=None,
        list_builtin=False,
        out=out,
        workers=1,
        scheduler=None,
        quiet=True,
        no_plots=False,
    )
    assert run_sweep_command(args, Console()) == 0
    return out


def test_tiny_eta_sweep_plots(tmp_path: Path) -> None:
    out = _sweep(tmp_path, "eta", '"density.eta" = [0, 25, 50]\nseed = "1..2"', "voids = true")
    assert (out / "plots" / "phi_vs_eta.png").stat().st_size > 0
    assert (out / "plots" / "phi_vs_eta.svg").stat().st_size > 0
    with (out / "results.csv").open(newline="") as fh:
        rows = list(csv.DictReader(fh))
    assert all(row["voids.void_spans"] in ("true", "false") for row in rows)
    assert all(0.0 <= float(row["voids.largest_void_fraction"]) <= 1.0 for row in rows)


def test_tiny_seeds_sweep_table3(tmp_path: Path) -> None:
    out = _sweep(tmp_path, "seeds", 'seed = "1..3"')
    assert (out / "plots" / "seeds.png").is_file()
    table = (out / "plots" / "table3.md").read_text(encoding="utf-8")
    assert "| `phi_interior` |" in table
    assert "z_interior" in table
    assert "CV" in table


def test_no_plots_for_unrelated_results(tmp_path: Path) -> None:
    out = _sweep(tmp_path, "other", '"insertion.t" = [0.999, 1.0]')
    assert not (out / "plots").exists()


def test_time_plot(tmp_path: Path) -> None:
    out = tmp_path / "scaling"
    out.mkdir()
    (out / "experiment.json").write_text(
        '{"parameters": ["insertion.t", "domain.width", "domain.height", "insertion.search"]}'
    )
    with (out / "results.csv").open("w", newline="") as fh:
        writer = csv.writer(fh)
        writer.writerow(
            [
                "run_id",
                "insertion.t",
                "domain.width",
                "domain.height",
                "insertion.search",
                "status",
                "error",
                "placed",
                "insert_time_s",
            ]
        )
        for t in (1.0, 0.99):
            for search, sizes in (("indexed", (200, 400, 800)), ("linear", (200, 400))):
                for side in sizes:
                    n = side * side / 40
                    writer.writerow(
                        [
                            "x",
                            t,
                            side,
                            side,
                            search,
                            "done",
                            "",
                            n,
                            1e-5 * n ** (1.5 if search == "linear" else 1.2),
                        ]
                    )
    files = plot_experiment(out)
    assert out / "plots" / "time_vs_n.png" in files
    assert out / "plots" / "time_vs_n.svg" in files


def test_fit_power_law() -> None:
    n = np.array([1e3, 4e3, 1.6e4])
    k, c = fit_power_law(n, 3e-6 * n**1.47)
    assert k == pytest.approx(1.47)
    assert c == pytest.approx(3e-6)


def test_seed_statistics() -> None:
    stats = seed_statistics([{"phi": "0.86"}, {"phi": "0.87"}, {"phi": ""}], ["phi"])
    mean, sd, cv = stats["phi"]
    assert mean == pytest.approx(0.865)
    assert sd == pytest.approx(np.std([0.86, 0.87], ddof=1))
    assert cv == pytest.approx(sd / mean)


# --- the void criterion on synthetic packings --------------------------------


def _packing(squares: list[tuple[float, float, float]], side: float) -> Packing:
    """Axis-aligned squares (x, y, half side) in a ``side`` x ``side`` domain."""
    n = len(squares)
    verts, offsets = [], [0]
    for _, _, h in squares:
        verts.append(np.array([[-h, -h], [h, -h], [h, h], [-h, h]]))
        offsets.append(offsets[-1] + 4)
    radius = np.array([2 * h / math.sqrt(math.pi) for _, _, h in squares])
    return Packing(
        radius=radius,
        mineral=np.zeros(n, dtype=np.int64),
        mineral_names=("m",),
        vertices=np.concatenate(verts),
        offsets=np.array(offsets, dtype=np.int64),
        orientation=np.zeros(n),
        centre=np.array([[x, y] for x, y, _ in squares]),
        insertion_index=np.arange(n, dtype=np.int64),
        domain=Rectangle(-side / 2, side / 2, -side / 2, side / 2),
    )


def _tiling(side: float, h: float, skip_row: int | None = None) -> list[tuple[float, float, float]]:
    count = round(side / (2 * h))
    centres = -side / 2 + h + 2 * h * np.arange(count)
    return [
        (float(x), float(y), h) for j, y in enumerate(centres) for x in centres if j != skip_row
    ]


def test_dense_packing_does_not_span() -> None:
    packing = _packing(_tiling(100.0, 5.0), 100.0)  # squares tile the domain exactly
    metrics = void_metrics(packing, window=(-40.0, 40.0, -40.0, 40.0))
    assert metrics["void_spans"] is False
    assert metrics["largest_void_fraction"] < 0.01


def test_channel_across_the_window_spans() -> None:
    packing = _packing(_tiling(100.0, 5.0, skip_row=5), 100.0)  # one empty row: a channel
    metrics = void_metrics(packing, window=(-40.0, 40.0, -40.0, 40.0))
    assert metrics["void_spans"] is True
    assert metrics["largest_void_fraction"] == pytest.approx(10 / 80, rel=0.25)


def test_isolated_pores_do_not_span() -> None:
    squares = [(x, y, h * 0.9) for x, y, h in _tiling(100.0, 5.0)]  # thin gaps around each
    packing = _packing(squares, 100.0)
    free = free_space_mask(packing.polygons(), (-40.0, 40.0, -40.0, 40.0), 0.25)
    assert free.any()
    # the gaps form a grid of channels, so the free space connects ...
    assert spans(free)
    # ... but a square hole in the middle of a solid window does not
    hole = np.zeros((20, 20), dtype=bool)
    hole[8:12, 8:12] = True
    assert not spans(hole)


def test_default_window_is_interior() -> None:
    packing = _packing(_tiling(100.0, 5.0, skip_row=5), 100.0)
    metrics = void_metrics(packing)
    assert metrics["void_spans"] is True
    assert metrics["void_pixel"] == pytest.approx(0.25 * 2 * packing.radius.min())


def _numeric_results(out: Path) -> None:
    """A finished sweep of eta and count (values whose text order is not their order)."""
    out.mkdir()
    (out / "experiment.json").write_text('{"parameters": ["density.eta", "count", "seed"]}')
    with (out / "results.csv").open("w", newline="") as fh:
        writer = csv.writer(fh)
        writer.writerow(["run_id", "density.eta", "count", "seed", "status", "phi_interior"])
        for eta in (0, 10, 5):
            for count in (1000, 50):
                for seed in (1, 2):
                    phi = 0.8 - 0.001 * eta + 0.0001 * seed
                    writer.writerow(["x", eta, count, seed, "done", phi])


def test_table3_sections_follow_numeric_order(tmp_path: Path) -> None:
    out = tmp_path / "sweep"
    _numeric_results(out)
    plot_experiment(out)
    table = (out / "plots" / "table3.md").read_text(encoding="utf-8")
    sections = [line for line in table.splitlines() if line.startswith("## ")]
    assert sections == [
        "## eta = 0, count = 50",
        "## eta = 0, count = 1000",
        "## eta = 5, count = 50",
        "## eta = 5, count = 1000",
        "## eta = 10, count = 50",
        "## eta = 10, count = 1000",
    ]


def test_legend_entries_follow_numeric_order(tmp_path: Path, monkeypatch) -> None:
    from regopack.experiments import plots as experiment_plots

    legends: dict[str, list[str]] = {}
    real_save = experiment_plots._save

    def save(fig, plots, stem):
        legend = fig.axes[0].get_legend()
        legends[stem] = [t.get_text() for t in legend.get_texts()] if legend else []
        return real_save(fig, plots, stem)

    monkeypatch.setattr(experiment_plots, "_save", save)
    out = tmp_path / "sweep"
    _numeric_results(out)
    plot_experiment(out)
    assert legends["phi_vs_eta"] == ["count = 50", "count = 1000"]
