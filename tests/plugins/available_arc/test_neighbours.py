"""Neighbour lists: the same interferers, hence the same packing, as the grid search."""

from __future__ import annotations

import numpy as np
import pytest
from arc_helpers import change5_population, octagon_population, pack
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from regopack.domain import Circle, ConvexPolygon, Domain, PeriodicRectangle, Rectangle
from regopack.plugins.available_arc import kernel, state
from regopack.plugins.available_arc.neighbours import GAP_SLACK
from regopack.plugins.available_arc.state import ArcState
from regopack.population import Population
from regopack.testing import extreme_radii

HEXAGON = tuple((60.0 * np.cos(a), 60.0 * np.sin(a)) for a in np.linspace(0, 2 * np.pi, 7)[:-1])


def _run(
    pop: Population, domain: Domain, seed: int, lists: bool, tau: float | None = None
) -> tuple[ArcState, bytes]:
    """Pack ``pop`` with or without neighbour lists; return the state and its packing bytes."""
    st_ = ArcState(pop, domain, t=0.999, tau=tau, linear=False, neighbour_lists=lists)
    st_.pack_range(0, len(pop), np.random.default_rng(seed))
    p = st_.packed
    key = p.cx.tobytes() + p.cy.tobytes() + p.order.tobytes()
    return st_, key + bytes(str(st_.counter(kernel.I_ANALYSES)), "ascii")


def _same_with_and_without_lists(
    pop: Population, domain: Domain, seed: int, tau: float | None = None
) -> ArcState:
    with_lists, a = _run(pop, domain, seed, True, tau)
    _, b = _run(pop, domain, seed, False, tau)
    assert with_lists.counter(kernel.I_NBLISTS) == 1
    assert a == b
    return with_lists


@pytest.mark.parametrize(
    ("seed", "domain", "tau"),
    [
        (1, Rectangle.centred(110.0, 90.0, (3.0, -7.0)), None),
        (2, Rectangle.centred(110.0, 90.0), None),
        (3, Rectangle.centred(110.0, 90.0), 0.65),
        (4, Circle(1.0, 2.0, 55.0), None),
        (5, ConvexPolygon(HEXAGON), None),
    ],
)
def test_lists_and_grid_give_identical_packings(seed: int, domain: Domain, tau: float) -> None:
    pop, _ = change5_population(450, seed)
    st_ = _same_with_and_without_lists(pop, domain, seed, tau)
    assert st_.count > 200


def test_scene_option_turns_the_lists_off_and_keeps_the_packing() -> None:
    domain = Rectangle.centred(100.0, 80.0)
    out = []
    for lists in (True, False):
        pop, rng = change5_population(350, 12)
        out.append(pack(pop, domain, rng, eta=10.0, neighbour_lists=lists))
    assert out[0].centre.tobytes() == out[1].centre.tobytes()
    assert out[0].stats == {
        **out[1].stats,
        **{k: out[0].stats[k] for k in out[0].stats if "time" in k},
    }


@pytest.mark.parametrize("scale", [1e-150, 1e40, 1e150])
def test_lists_and_grid_agree_far_beyond_the_usual_scales(scale: float) -> None:
    rng = np.random.default_rng(0)
    radius = scale * np.exp(rng.uniform(0.0, np.log(5.0), 150))
    pop = octagon_population(radius, rng, psi=0.5)
    side = 1.2 * np.sqrt(np.sum(np.pi * (radius / scale) ** 2)) * scale
    st_ = _same_with_and_without_lists(pop, Rectangle.centred(side, side), 0)
    assert st_.count > 100


def test_full_lists_fall_back_to_the_grid(monkeypatch: pytest.MonkeyPatch) -> None:
    monkeypatch.setattr(state, "LIST_CAPACITY", 6)
    pop, _ = change5_population(400, 8)
    st_ = _same_with_and_without_lists(pop, Rectangle.centred(100.0, 100.0), 8)
    placed = st_.packed.order[: st_.count]
    dropped = np.sum(st_.packed.nb_n[placed] < 0)
    assert 0 < dropped < st_.count


def test_lists_hold_every_near_particle_sorted_by_gap() -> None:
    pop, _ = change5_population(500, 9)
    st_, _ = _run(pop, Rectangle.centred(110.0, 110.0), 9, True)
    p = st_.packed
    cap = p.fpar[kernel.F_NBCAP]
    reach = p.nb_reach
    placed = p.order[: st_.count]
    assert cap > 0
    checked = 0
    for q in placed:
        cnt = p.nb_n[q]
        if cnt < 0:
            continue
        others = placed[placed != q]
        d = np.hypot(p.cx[others] - p.cx[q], p.cy[others] - p.cy[q])
        lim = reach[q] + reach[others] + 2.0 * cap
        must = set(others[d < lim].tolist())
        may = set(others[d < lim * (1 + 2 * GAP_SLACK)].tolist())
        got = p.nb_o[q, :cnt].astype(np.int64)
        assert must <= set(got.tolist()) <= may
        assert len(set(got.tolist())) == cnt
        assert np.all(np.diff(p.nb_gap[q, :cnt]) >= 0)
        # offsets are the same floats the grid search computes
        assert np.array_equal(p.nb_dx[q, :cnt], p.cx[got] - p.cx[q])
        assert np.array_equal(p.nb_dy[q, :cnt], p.cy[got] - p.cy[q])
        checked += 1
    assert checked > 0.9 * len(placed)


def test_lists_are_not_kept_where_the_grid_is_needed() -> None:
    pop, _ = change5_population(50, 1)
    periodic = ArcState(pop, PeriodicRectangle.centred(80.0, 80.0), t=0.999, tau=None, linear=False)
    assert periodic.counter(kernel.I_NBLISTS) == 0
    assert periodic.packed.nb_dx.shape == (1, 1)
    off = ArcState(
        pop, Rectangle.centred(80.0, 80.0), t=0.999, tau=None, linear=False, neighbour_lists=False
    )
    assert off.counter(kernel.I_NBLISTS) == 0


@given(
    seed=st.integers(0, 2**32 - 1),
    n=st.integers(2, 80),
    ratio=st.sampled_from([1.0, 10.0, 1e2, 1e4]),
    scale=st.sampled_from([1e-6, 1.0, 1e6]),
    psi=st.sampled_from([0.01, 0.5, 15.0, 1000.0]),
    tau=st.sampled_from([None, None, 0.65]),
)
@settings(max_examples=40, deadline=None, suppress_health_check=[HealthCheck.too_slow])
def test_lists_and_grid_agree_in_random_scenes(seed, n, ratio, scale, psi, tau) -> None:
    rng = np.random.default_rng(seed)
    radius = extreme_radii(n, ratio, scale, rng)
    pop = octagon_population(radius, rng, psi=psi)
    side = max(scale * 4.0 * ratio, 3.0 * np.sqrt(np.sum(radius**2)), 2.6 * pop.circumradius.max())
    domain = Rectangle.centred(side, 0.8 * side, (3.0 * scale, -2.0 * scale))
    _same_with_and_without_lists(pop, domain, seed, tau)


def test_the_option_from_the_command_line(capsys: pytest.CaptureFixture[str]) -> None:
    import tomllib

    from regopack.cli import main

    assert main(["config", "--set", "insertion.neighbour_lists=false"]) == 0
    assert tomllib.loads(capsys.readouterr().out)["insertion"]["neighbour_lists"] is False
    assert main(["config", "--set", "insertion.neighbour_lists=3"]) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert err == [
        "regopack: error: --set: insertion.neighbour_lists = 3: Input should be a valid boolean"
    ]
