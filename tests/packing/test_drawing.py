"""Packing.plot, the notebook pictures and the one-line summary."""

from __future__ import annotations

import matplotlib

matplotlib.use("Agg")

import numpy as np
import pytest
from matplotlib.figure import Figure

import regopack
from regopack.base.colours import mineral_colours
from regopack.base.errors import ConfigError


@pytest.fixture(scope="module")
def tiny():
    return regopack.pack("small", domain__width=60, domain__height=60, count=40)


def test_plot_by_mineral_draws_every_placed_particle(tiny):
    ax = Figure().add_subplot()
    art = tiny.plot(ax)
    assert art.ax is ax
    assert len(art.particles.get_paths()) == tiny.n_placed
    colours = mineral_colours(tiny.mineral_names)
    faces = art.particles.get_facecolors()
    first = np.flatnonzero(tiny.placed)[0]
    assert matplotlib.colors.to_hex(faces[0]) == colours[tiny.mineral[first]].lower()
    labels = [t.get_text() for t in art.legend.get_texts()]
    assert labels[0].startswith(tiny.mineral_names[0])
    assert ax.get_xlim() == (-30.0, 30.0)


@pytest.mark.parametrize("color_by", ["diameter", "radius", "order", "Z"])
def test_plot_by_a_quantity_has_a_colour_bar(tiny, color_by):
    art = tiny.plot(Figure().add_subplot(), color_by=color_by)
    values = art.particles.get_array()
    assert values.shape == (tiny.n_placed,)
    assert art.colorbar is not None and art.legend is None
    if color_by == "diameter":
        np.testing.assert_allclose(values, 2 * tiny.radius[tiny.placed])


def test_plot_takes_values_per_drawn_or_per_placed_particle(tiny):
    per_drawn = np.arange(tiny.n_particles, dtype=float)
    art = tiny.plot(Figure().add_subplot(), color_by=per_drawn, label="index")
    np.testing.assert_array_equal(art.particles.get_array(), per_drawn[tiny.placed])
    art = tiny.plot(Figure().add_subplot(), color_by=np.ones(tiny.n_placed))
    assert art.particles.get_array().shape == (tiny.n_placed,)
    with pytest.raises(ConfigError, match="one per drawn particle"):
        tiny.plot(Figure().add_subplot(), color_by=np.ones(3))
    with pytest.raises(ConfigError, match="expected one of mineral"):
        tiny.plot(Figure().add_subplot(), color_by="colour")


def test_notebook_pictures(tiny):
    png = tiny._repr_png_()
    assert png.startswith(b"\x89PNG")
    html = tiny._repr_html_()
    assert "data:image/png;base64," in html
    assert f"{tiny.n_placed:,} of {tiny.n_particles:,} particles placed" in html


def test_a_periodic_packing_is_drawn_with_the_images_across_its_sides():
    p = regopack.pack(
        "small", domain__kind="periodic", domain__width=100, domain__height=100, count=200
    )
    art = p.plot(Figure().add_subplot(), color_by="diameter")
    placed = np.flatnonzero(p.placed)
    crossing = 0
    for poly in p.polygons(placed):
        lo, hi = poly.min(axis=0), poly.max(axis=0)
        nx = int(lo[0] < -50) + int(hi[0] > 50)
        ny = int(lo[1] < -50) + int(hi[1] > 50)
        crossing += (1 + nx) * (1 + ny) - 1
    assert crossing > 0
    assert len(art.particles.get_paths()) == p.n_placed + crossing
    assert len(art.particles.get_array()) == p.n_placed + crossing


def test_names_with_dollars_are_drawn_as_they_are():
    p = regopack.pack(
        "small", domain__width=60, domain__height=60, count=30, phases__0__name="x$^$"
    )
    assert p._repr_png_().startswith(b"\x89PNG")
    assert "data:image/png" in p._repr_html_()
    art = p.plot(Figure().add_subplot())
    assert any("x$^$" in t.get_text().replace("\\$", "$") for t in art.legend.get_texts())


def test_html_escapes_the_scene_name():
    p = regopack.pack("small", domain__width=60, domain__height=60, count=30, name="a<b>")
    assert "a&lt;b&gt;" in p._repr_html_() and "a<b>" not in p._repr_html_()


def test_ax_must_be_axes(tiny):
    with pytest.raises(ConfigError, match="ax: expected matplotlib axes"):
        tiny.plot(5)
    with pytest.raises(ConfigError, match="color_by"):
        tiny.plot(Figure().add_subplot(), color_by=["a"] * tiny.n_placed)
