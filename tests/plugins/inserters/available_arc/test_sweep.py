"""The sweep order of the available-arc inserter, checked by the shapely oracles."""

from __future__ import annotations

import numpy as np
import pytest
import shapely
from arc_helpers import as_packing, change5_population, octagon_population, pack
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st
from test_domains import brute_force_periodic_overlap

from regopack.base.errors import ConfigError
from regopack.geometry.domain import Circle, ConvexPolygon, Domain, PeriodicRectangle, Rectangle
from regopack.geometry.population import Population, concat_shapes
from regopack.packing.core import Packing
from regopack.plugins.inserters.available_arc import AvailableArc, AvailableArcConfig, sweep
from regopack.plugins.shapes.disk import Disk
from regopack.plugins.shapes.octagon import OctagonConfig, RandomPolygon
from regopack.plugins.sizes.change5 import Change5, Change5Config
from regopack.registry.interfaces import DensityController
from regopack.testing import extreme_radii
from regopack.verification.polygons import verify

PENTAGON = ((-100.0, -80.0), (90.0, -100.0), (120.0, 60.0), (0.0, 110.0), (-110.0, 40.0))
DOMAINS: dict[str, Domain] = {
    "rectangle": Rectangle.centred(220.0, 180.0, (3.0, -2.0)),
    "polygon": ConvexPolygon(PENTAGON),
    "circle": Circle(5.0, -3.0, 110.0),
    "periodic": PeriodicRectangle.centred(200.0, 160.0, (4.0, -2.0)),
}


def _oracle(packing: Packing) -> None:
    """No overlap (verify; nine images when periodic) and nothing outside (shapely)."""
    report = verify(packing)
    assert report.ok, str(report)
    domain = packing.domain
    if isinstance(domain, PeriodicRectangle):
        assert brute_force_periodic_overlap(packing) < 1e-9
    elif isinstance(domain, Circle):  # exact: every vertex, grown by the rounding, inside
        placed = np.flatnonzero(packing.placed)
        rho = np.zeros(packing.n_particles) if packing.rounding is None else packing.rounding
        off = packing.offsets
        for j in placed:
            v = packing.vertices[off[j] : off[j + 1]] + packing.centre[j]
            reach = np.hypot(v[:, 0] - domain.cx, v[:, 1] - domain.cy).max() + rho[j]
            assert reach <= domain.radius * (1.0 + 1e-9)
    else:
        window = shapely.Polygon(domain.outline()).buffer(1e-9 * domain.width)
        assert shapely.contains(window, packing.to_shapely()).all()


def disks_and_octagons(radius: np.ndarray, rng: np.random.Generator, share: float) -> Population:
    """Disks with probability ``share``, random octagons (psi = 1) otherwise."""
    disk = rng.random(len(radius)) < share
    parts = [(np.flatnonzero(disk), Disk())]
    parts.append((np.flatnonzero(~disk), RandomPolygon(OctagonConfig(psi=1.0))))
    batches = [(idx, gen.generate(radius[idx], rng)) for idx, gen in parts]
    mineral = disk.astype(np.int64)
    return Population(radius, mineral, ("octagon", "disk"), concat_shapes(batches, len(radius)))


@pytest.mark.parametrize("kind", list(DOMAINS))
def test_sweep_fills_every_domain_kind_without_overlap(kind: str) -> None:
    domain = DOMAINS[kind]
    n = round(domain.area / Change5(Change5Config()).mean_area)
    pop, rng = change5_population(n, 3)
    res = pack(pop, domain, rng, order="sweep")
    packing = as_packing(pop, res, domain)
    _oracle(packing)
    assert packing.area()[packing.placed].sum() / domain.area > 0.75
    stats = res.stats
    assert stats["refused"] + stats["not_offered"] == n - packing.n_placed


@pytest.mark.parametrize(
    ("kind", "share"),
    [("rectangle", 1.0), ("periodic", 1.0), ("circle", 0.5), ("polygon", 0.5)],
)
def test_sweep_packs_disks_and_mixed_scenes(kind: str, share: float) -> None:
    domain = DOMAINS[kind]
    rng = np.random.default_rng(6)
    n = round(domain.area / Change5(Change5Config()).mean_area)
    pop = disks_and_octagons(Change5(Change5Config()).sample(n, rng), rng, share)
    res = pack(pop, domain, rng, eta=10.0 * (1.0 - share), order="sweep")
    _oracle(as_packing(pop, res, domain))
    assert res.placed.sum() > 0.85 * n


def test_same_seed_same_sweep_packing_bit_for_bit() -> None:
    domain = DOMAINS["rectangle"]
    runs = []
    for _ in range(2):
        pop, rng = change5_population(600, 11)
        res = pack(pop, domain, rng, eta=5.0, order="sweep")
        runs.append(res)
    assert np.array_equal(runs[0].centre, runs[1].centre, equal_nan=True)
    assert np.array_equal(runs[0].insertion_index, runs[1].insertion_index)


def test_the_paper_order_is_unchanged_by_the_sweep_option() -> None:
    domain = DOMAINS["rectangle"]
    pop, rng = change5_population(500, 2)
    a = pack(pop, domain, rng)
    pop, rng = change5_population(500, 2)
    b = pack(pop, domain, rng, order="paper", zone=3.0)
    assert np.array_equal(a.centre, b.centre, equal_nan=True)


def test_the_sweep_grows_from_the_bottom() -> None:
    domain = DOMAINS["rectangle"]
    n = round(domain.area / Change5(Change5Config()).mean_area)
    pop, rng = change5_population(n, 4)
    res = pack(pop, domain, rng, order="sweep")
    order = np.argsort(np.where(res.placed, res.insertion_index, np.iinfo(np.int64).max))
    y = res.centre[order[: res.placed.sum()], 1]
    first, last = y[: len(y) // 5], y[-len(y) // 5 :]
    assert np.median(first) < np.median(last)  # the first fifth lies below the last fifth
    assert y[0] < domain.ymin + 2.0 * pop.circumradius.max()  # type: ignore[attr-defined]


def test_every_refusal_is_certified_by_an_exact_scan() -> None:
    """A refused particle has no available arc at any candidate that is not retired."""
    from regopack.plugins.density.eta import EtaConfig, EtaController
    from regopack.plugins.inserters.available_arc import sweep
    from regopack.plugins.inserters.available_arc.state import ArcState

    domain = Rectangle.centred(90.0, 70.0)
    n = round(1.1 * domain.area / Change5(Change5Config()).mean_area)
    pop, rng = change5_population(n, 7)
    inserter = AvailableArc(AvailableArcConfig(order="sweep"))
    res = inserter.pack(pop, domain, EtaController(EtaConfig()), rng)
    assert res.stats["refused"] >= 1
    # replay the same run by hand, keeping the sweep's state
    pop, rng = change5_population(n, 7)
    st_ = ArcState(pop, domain, t=0.999, tau=None, linear=False)
    sw = sweep.Sweep(n, domain.height, 6.0 * float(pop.radius.max()))
    sw.run(0, n, st_.outlines, st_.packed, st_.work, rng, st_.rounded)
    assert np.array_equal(np.isfinite(st_.packed.cx), res.placed)
    refused = np.flatnonzero(sw.status == sweep.STATUS_REFUSED)
    assert len(refused) == res.stats["refused"]
    # the last refused particle: no candidate left open has an arc for it, exactly
    from regopack.plugins.inserters.available_arc import kernel

    i = int(refused[-1])
    mq = kernel.begin_particle(i, st_.outlines, st_.packed, st_.work)
    open_ = np.flatnonzero(sw.flag[: st_.count] != sweep.RETIRED)
    for k in open_:
        arcs = kernel.analyze_candidate(
            int(st_.packed.order[k]), i, mq, st_.outlines, st_.packed, st_.work, None
        )
        assert arcs.shape[0] == 0


def test_sweep_with_a_python_controller_is_refused_in_one_line() -> None:
    class Half(DensityController):
        def shrink(self, arcs, r_new, r_cand, rng):  # type: ignore[no-untyped-def]
            return arcs

    pop, rng = change5_population(20, 1)
    inserter = AvailableArc(AvailableArcConfig(order="sweep"))
    with pytest.raises(ConfigError, match="order = 'sweep' needs the built-in 'eta'"):
        inserter.pack(pop, DOMAINS["rectangle"], Half(), rng)


def test_a_particle_larger_than_the_domain_is_refused() -> None:
    domain = Rectangle.centred(10.0, 10.0)
    rng = np.random.default_rng(1)
    pop = octagon_population(np.array([20.0, 1.0, 1.0, 30.0, 1.0]), rng)
    res = pack(pop, domain, rng, order="sweep")
    assert not res.placed[0] and not res.placed[3]
    assert res.placed[[1, 2, 4]].all()
    _oracle(as_packing(pop, res, domain))


@given(
    seed=st.integers(0, 2**31 - 1),
    n=st.integers(2, 50),
    ratio=st.sampled_from([1.0, 10.0, 1e2, 1e4]),
    scale=st.sampled_from([1e-6, 1.0, 1e6]),
    psi=st.sampled_from([0.01, 1.0, 1000.0]),
    a=st.sampled_from([0.05, 1 / 3, 1.0]),
    kind=st.sampled_from(["rectangle", "polygon", "circle", "periodic"]),
    eta=st.sampled_from([0.0, 30.0]),
    zone=st.sampled_from([0.0, 0.5, 3.0]),
    closing=st.sampled_from(["paced", "prompt", "tail"]),
    strip=st.sampled_from([0.0, 0.3]),
)
@settings(max_examples=40, deadline=None, suppress_health_check=[HealthCheck.too_slow])
def test_no_overlap_and_nothing_outside_at_the_extremes(
    seed, n, ratio, scale, psi, a, kind, eta, zone, closing, strip
) -> None:
    rng = np.random.default_rng(seed)
    radius = extreme_radii(n, ratio, scale, rng)
    pop = octagon_population(radius, rng, psi=psi, a=a)
    size = scale * max(4.0 * ratio, 3.0 * np.sqrt(np.sum(radius**2 / scale**2)))
    size = max(size, 4.4 * float(pop.circumradius.max()))
    centre = (3.0 * scale, -2.0 * scale)
    domain: Domain
    if kind == "rectangle":
        domain = Rectangle.centred(size, 0.8 * size, centre)
    elif kind == "polygon":
        r = 1.5 * size
        t = np.array([0.3, 1.9, 3.1, 4.6])
        domain = ConvexPolygon(
            tuple((centre[0] + r * np.cos(x), centre[1] + r * np.sin(x)) for x in t)
        )
    elif kind == "circle":
        domain = Circle(centre[0], centre[1], 0.8 * size)
    else:
        domain = PeriodicRectangle.centred(size, 1.1 * size, centre)
    zone_length = zone * float(radius.max())
    res = pack(
        pop, domain, rng, eta=eta, order="sweep", zone=zone_length, closing=closing,
        strip=strip * size,
    )  # fmt: skip
    assert res.placed.sum() >= 1
    _oracle(as_packing(pop, res, domain))


def test_exact_screening_rescues_particles_and_certifies_the_rest() -> None:
    from regopack.plugins.inserters.available_arc import kernel
    from regopack.plugins.inserters.available_arc.state import ArcState

    domain = Rectangle.centred(90.0, 72.0)
    n = round(1.1 * domain.area / Change5(Change5Config()).mean_area)
    pop, rng = change5_population(n, 5)
    paper = pack(pop, domain, rng)
    pop, rng = change5_population(n, 5)
    exact = pack(pop, domain, rng, screening="exact")
    _oracle(as_packing(pop, exact, domain))
    assert exact.stats["rescued"] >= 1
    assert exact.placed.sum() == paper.placed.sum() + exact.stats["rescued"]
    # identical up to the first particle the exact scan rescues
    first = int(np.flatnonzero(exact.placed != paper.placed)[0])
    assert np.array_equal(exact.centre[:first], paper.centre[:first], equal_nan=True)
    # replay: the last particle not placed has no arc at any candidate
    pop, rng = change5_population(n, 5)
    st_ = ArcState(pop, domain, t=0.999, tau=None, linear=False)
    counts = np.zeros(1, dtype=np.int64)
    st_.pack_range_exact(0, n, rng, counts)
    assert np.array_equal(np.isfinite(st_.packed.cx), exact.placed)
    i = int(np.flatnonzero(~exact.placed)[-1])
    mq = kernel.begin_particle(i, st_.outlines, st_.packed, st_.work)
    for k in range(st_.count):
        arcs = kernel.analyze_candidate(
            int(st_.packed.order[k]), i, mq, st_.outlines, st_.packed, st_.work, None
        )
        assert arcs.shape[0] == 0


def test_exact_screening_with_a_python_controller_is_refused_in_one_line() -> None:
    class Same(DensityController):
        def shrink(self, arcs, r_new, r_cand, rng):  # type: ignore[no-untyped-def]
            return arcs

    pop, rng = change5_population(20, 1)
    inserter = AvailableArc(AvailableArcConfig(screening="exact"))
    with pytest.raises(ConfigError, match="screening = 'exact' needs the built-in 'eta'"):
        inserter.pack(pop, DOMAINS["rectangle"], Same(), rng)


def test_the_sweep_removes_the_radial_grading_of_the_paper_order() -> None:
    from regopack.analysis.pipeline import run_analyses
    from regopack.registry.manager import default_registry
    from regopack.run.pipeline import run_scene
    from regopack.scenes.model import load_scene, resolve_scene

    registry = default_registry(autoload=False)
    slopes = {}
    for order in ("paper", "sweep"):
        overrides = ["domain.width=400", "domain.height=400", f"insertion.order={order}"]
        packing = run_scene(resolve_scene(load_scene("table1", overrides), registry)).packing
        h = run_analyses(packing, registry, [("homogeneity", {})])["homogeneity"].results()
        slopes[order] = (h["density_slope_per_100"], h["density_slope_err"])
    slope, err = slopes["paper"]
    assert slope < -4.0 * err  # the paper's order grades: fewer particles far from the centre
    slope, err = slopes["sweep"]
    assert abs(slope) < 3.0 * err


def test_the_paced_closing_places_more_and_the_prompt_one_refuses_fewer() -> None:
    domain = DOMAINS["rectangle"]
    n = round(1.2 * domain.area / Change5(Change5Config()).mean_area)
    runs = {}
    for closing in ("paced", "prompt"):
        pop, rng = change5_population(n, 8)
        runs[closing] = pack(pop, domain, rng, order="sweep", closing=closing)
        _oracle(as_packing(pop, runs[closing], domain))
    assert runs["prompt"].stats["refused"] < runs["paced"].stats["refused"]
    assert runs["paced"].placed.sum() > runs["prompt"].placed.sum()
    assert runs["paced"].stats["not_offered"] < runs["prompt"].stats["not_offered"]


@pytest.mark.parametrize("kind", list(DOMAINS))
def test_the_tail_closing_places_every_particle_it_offers(kind: str) -> None:
    """The particles left out are the end of the stream (a random tail), bar one refusal."""
    domain = DOMAINS[kind]
    n = round(1.2 * domain.area / Change5(Change5Config()).mean_area)
    pop, rng = change5_population(n, 4)
    res = pack(pop, domain, rng, order="sweep", closing="tail")
    _oracle(as_packing(pop, res, domain))
    placed = res.placed
    # these scenes refuse nothing in the bulk: one particle fits nowhere and lifts the
    # zone to the top (refused, the run goes on), the next refusal ends the run, and
    # everything after it is a suffix of the stream, not offered
    assert res.stats["refused"] == 2 and res.stats["not_offered"] > 0
    last = int(np.flatnonzero(placed).max())
    assert np.count_nonzero(~placed[: last + 1]) == 1
    assert not placed[last + 1 :].any()
    assert res.stats["not_offered"] == n - last - 2
    pop2, rng2 = change5_population(n, 4)
    paced = pack(pop2, domain, rng2, order="sweep", closing="paced")
    assert res.stats["refused"] < paced.stats["refused"]


def test_a_particle_too_large_for_the_front_does_not_carry_the_zone_away() -> None:
    # a disk wider than the domain comes second: its rises must be undone
    domain = Rectangle.centred(10.0, 100.0)
    radius = np.ones(200)
    radius[1] = 6.0
    for closing in ("paced", "prompt", "tail"):
        rng = np.random.default_rng(1)
        pop = disks_and_octagons(radius, rng, share=1.0)
        res = pack(pop, domain, rng, order="sweep", closing=closing)
        assert res.placed.sum() == 199 and not res.placed[1]
        assert res.stats["refused"] == 1


def test_a_large_eta_does_not_stop_the_sweep() -> None:
    domain = Rectangle.centred(200.0, 200.0)
    n = round(domain.area / Change5(Change5Config()).mean_area)
    pop, rng = change5_population(n, 5)
    paper = pack(pop, domain, rng, eta=99.0)
    pop, rng = change5_population(n, 5)
    res = pack(pop, domain, rng, eta=99.0, order="sweep")
    _oracle(as_packing(pop, res, domain))
    assert res.placed.sum() > 0.85 * paper.placed.sum()


@pytest.mark.parametrize("zone", [1e-12, 150.0, 12000.0])
def test_zones_far_below_and_far_above_the_domain_size_work(zone: float) -> None:
    domain = Rectangle.centred(150.0, 150.0)
    n = round(domain.area / Change5(Change5Config()).mean_area)
    pop, rng = change5_population(n, 3)
    paper = pack(pop, domain, rng)
    for closing in ("paced", "prompt"):
        pop, rng = change5_population(n, 3)
        res = pack(pop, domain, rng, order="sweep", zone=zone, closing=closing)
        _oracle(as_packing(pop, res, domain))
        assert res.placed.sum() > 0.9 * paper.placed.sum()


@pytest.mark.parametrize(
    ("setting", "field", "hint"),
    [
        ("insertion.order=spiral", 'insertion.order = "spiral"', "'paper' or 'sweep'"),
        ("insertion.zone=-1", "insertion.zone = -1", "greater than or equal to 0"),
        ("insertion.zone=nan", "insertion.zone = nan", "finite"),
        ("insertion.strip=-1", "insertion.strip = -1", "greater than or equal to 0"),
        ("insertion.strip=inf", "insertion.strip = inf", "finite"),
        ("insertion.closing=late", 'insertion.closing = "late"', "'paced', 'prompt' or 'tail'"),
        ("insertion.screening=none", 'insertion.screening = "none"', "'paper' or 'exact'"),
    ],
)
def test_the_options_from_the_command_line(
    capsys: pytest.CaptureFixture[str], setting: str, field: str, hint: str
) -> None:
    from regopack.cli import main

    assert main(["config", "--set", setting]) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1
    assert err[0].startswith(f"regopack: error: --set: {field}: ")
    assert hint in err[0]


def test_dem_is_the_table1_scene_in_the_sweep_order() -> None:
    """The same materials and domain, the sweep order, strips no narrower than the domain."""
    from regopack.registry.manager import default_registry
    from regopack.scenes.model import load_scene, resolve_scene

    registry = default_registry(autoload=False)
    dem = resolve_scene(load_scene("dem"), registry).to_dict()
    table1 = resolve_scene(load_scene("table1"), registry).to_dict()
    assert dem["insertion"].pop("order") == "sweep"
    assert table1["insertion"].pop("order") == "paper"
    # strips as wide as the domain: one zone across it, as without strips
    assert dem["insertion"].pop("strip") == dem["domain"]["width"]
    assert table1["insertion"].pop("strip") == 0.0
    dem.pop("name")
    table1.pop("name")
    assert dem == table1


@pytest.mark.parametrize("kind", list(DOMAINS))
@pytest.mark.parametrize("closing", ["paced", "tail"])
def test_strips_fill_every_domain_kind_without_overlap(kind: str, closing: str) -> None:
    domain = DOMAINS[kind]
    n = round(domain.area / Change5(Change5Config()).mean_area)
    pop, rng = change5_population(n, 3)
    res = pack(pop, domain, rng, order="sweep", strip=55.0, closing=closing)
    packing = as_packing(pop, res, domain)
    _oracle(packing)
    assert res.stats["strips"] == int(domain.width // 55.0) >= 3
    assert packing.area()[packing.placed].sum() / domain.area > 0.7
    stats = res.stats
    assert stats["refused"] + stats["not_offered"] == n - packing.n_placed


def test_a_strip_as_wide_as_the_domain_is_the_sweep_without_strips() -> None:
    domain = DOMAINS["periodic"]
    runs = []
    for strip in (0.0, domain.width, 1.9 * domain.width):
        pop, rng = change5_population(700, 8)
        runs.append(pack(pop, domain, rng, order="sweep", strip=strip))
    for res in runs[1:]:
        assert res.stats["strips"] == 1
        assert np.array_equal(res.centre, runs[0].centre, equal_nan=True)
        assert np.array_equal(res.insertion_index, runs[0].insertion_index)


def test_same_seed_same_packing_with_strips() -> None:
    domain = DOMAINS["rectangle"]
    runs = []
    for _ in range(2):
        pop, rng = change5_population(800, 12)
        runs.append(pack(pop, domain, rng, eta=5.0, order="sweep", strip=50.0))
    assert np.array_equal(runs[0].centre, runs[1].centre, equal_nan=True)
    assert np.array_equal(runs[0].insertion_index, runs[1].insertion_index)


def test_the_fronts_of_the_strips_rise_together() -> None:
    """Each fifth of the placements lies at about the same height in every strip."""
    domain = Rectangle.centred(300.0, 300.0)
    n = round(domain.area / Change5(Change5Config()).mean_area)
    pop, rng = change5_population(n, 5)
    res = pack(pop, domain, rng, order="sweep", strip=60.0, closing="tail")
    assert res.stats["strips"] == 5
    order = np.argsort(np.where(res.placed, res.insertion_index, np.iinfo(np.int64).max))
    xy = res.centre[order[: res.placed.sum()]]
    strip = np.minimum(((xy[:, 0] - domain.xmin) // 60.0).astype(int), 4)
    zone = 6.0 * float(pop.radius.max())
    for part in np.array_split(np.arange(len(xy)), 5):
        heights = [np.median(xy[part][strip[part] == k, 1]) for k in range(5)]
        assert max(heights) - min(heights) < zone
    # every strip starts at the bottom
    first = [np.flatnonzero(strip == k)[0] for k in range(5)]
    assert all(xy[j, 1] < domain.ymin + zone for j in first)


def test_strips_keep_the_tail_a_suffix_of_the_stream() -> None:
    """Under the tail closing with strips, every particle offered is placed or refused."""
    domain = DOMAINS["rectangle"]
    n = round(1.2 * domain.area / Change5(Change5Config()).mean_area)
    pop, rng = change5_population(n, 4)
    res = pack(pop, domain, rng, order="sweep", closing="tail", strip=55.0)
    placed = res.placed
    last = int(np.flatnonzero(placed).max())
    assert not placed[last + 1 :].any()
    assert res.stats["not_offered"] > 0
    # refusals: particles that fit in no strip they were offered to
    assert np.count_nonzero(~placed[: last + 1]) <= res.stats["refused"]
    assert res.stats["refused"] + res.stats["not_offered"] == n - placed.sum()


def test_a_strip_narrower_than_its_particles_is_widened() -> None:
    """A strip narrower than two circumradii has no front of its own: it is widened."""
    n = round(1.1 * DOMAINS["polygon"].area / Change5(Change5Config()).mean_area)
    for kind, strip in (("polygon", 20.0), ("rectangle", 5.0), ("rectangle", 5e-324)):
        pop, rng = change5_population(n, 3)
        res = pack(pop, DOMAINS[kind], rng, order="sweep", strip=strip)
        width = DOMAINS[kind].width
        assert res.stats["strips"] <= width / (2.0 * pop.circumradius.max())  # type: ignore[attr-defined]
        assert res.stats["refused"] < 0.3 * n
        assert res.placed.sum() > 0.5 * n


def test_a_periodic_strip_does_not_start_at_a_particle_wrapped_to_the_top() -> None:
    domain = DOMAINS["periodic"]
    n = round(1.1 * domain.area / Change5(Change5Config()).mean_area)
    pop, rng = change5_population(n, 1)
    res = pack(pop, domain, rng, order="sweep", strip=55.0, closing="tail")
    assert res.stats["strips"] == 3
    union = shapely.union_all(as_packing(pop, res, domain).to_shapely())
    x0, x1, y0, y1 = domain.bounds()
    w = (x1 - x0) / 3
    for k in range(3):  # the bottom quarter of every strip is packed
        cell = shapely.box(x0 + k * w, y0, x0 + (k + 1) * w, y0 + 0.25 * (y1 - y0))
        assert union.intersection(cell).area / cell.area > 0.7


def test_the_prompt_closing_with_strips_costs_about_what_one_zone_does() -> None:
    """A refusal retires a bin of every full strip that refused it, so the strips close
    after about as many refusals as one zone (not one strip at a time, each refusal
    scanned in every strip)."""
    domain = Rectangle.centred(200.0, 80.0)
    n = round(2.5 * domain.area / Change5(Change5Config()).mean_area)
    out = {}
    for strip in (0.0, 50.0):
        pop, rng = change5_population(n, 1)
        res = pack(pop, domain, rng, order="sweep", strip=strip, closing="prompt")
        placed = int(res.placed.sum())
        stats = res.stats
        out[strip] = (stats["strips"], stats["refused"], stats["candidate_analyses"] / placed)
    assert out[50.0][0] == 4
    assert out[50.0][1] <= 2 * out[0.0][1], out
    assert out[50.0][2] <= 1.5 * out[0.0][2], out


def test_the_sweep_with_a_python_controller_is_refused_before_drawing() -> None:
    from fakes import PythonDensity

    import regopack
    from regopack.testing import make_registry

    registry = make_registry(PythonDensity())
    scene = regopack.scene("dem", registry=registry, density={"kind": "half"})
    with pytest.raises(ConfigError) as err:
        regopack.pack(scene)
    assert str(err.value).endswith(
        "density.kind: 'half' is not the built-in 'eta' density controller, which "
        "insertion.order = 'sweep' needs"
    )
    exact = regopack.scene("table1", registry=registry, density={"kind": "half"})
    with pytest.raises(ConfigError, match=r"insertion\.screening = 'exact' needs"):
        regopack.pack(regopack.scene(exact, insertion__screening="exact", registry=registry))
    # the paper's order takes any controller
    from regopack.run.pipeline import check_inserter

    check_inserter(regopack.scene("table1", registry=registry, density={"kind": "half"}))


def _tree_holds_its_maxima(tree: np.ndarray, leaves: int) -> bool:
    inner = np.arange(1, leaves)
    return bool(np.array_equal(tree[inner], np.maximum(tree[2 * inner], tree[2 * inner + 1])))


def _hidden(s: object, strip: int) -> list[int]:
    out = []
    e = int(s.hhead[strip])  # type: ignore[attr-defined]
    while e >= 0:
        out.append(e)
        e = int(s.hnext[e])  # type: ignore[attr-defined]
        assert len(out) <= len(s.hnext)  # type: ignore[attr-defined]
    return out


@pytest.mark.parametrize("narrow", [False, True])
def test_a_search_hides_the_other_strips_candidates_it_meets_and_a_switch_shows_them(
    narrow: bool,
) -> None:
    """The walk given the packing or only its search's arrays (``kernel.Screen``)."""
    from regopack.plugins.inserters.available_arc import kernel
    from regopack.plugins.inserters.available_arc.state import ArcState

    pop, _ = change5_population(40, 2)
    st_ = ArcState(pop, Rectangle.centred(100.0, 100.0), t=0.999, tau=None, linear=False)
    s = st_.packed
    c = kernel.screen(s) if narrow else s
    leaves = st_.counter(kernel.I_LEAVES)
    rmin = np.array([np.inf, 2.0, 0.5, 3.0, np.inf, 1.5])
    home = np.array([1, 0, 1, 1, 0, 1])
    for k, (r, h) in enumerate(zip(rmin, home, strict=True)):
        kernel.tree_set(s.tree, leaves, k, r)
        s.home[k] = h
    s.ipar[kernel.I_STRIP] = 0
    # strip 0's first candidate passing r = 1.0 is 1; candidate 0 (strip 1) is met first
    assert kernel.next_candidate(c, 0, 6, 1.0, 1.0, False) == 1
    assert _hidden(s, 1) == [0] and s.tree[leaves] == -np.inf
    # from 2 on: 2 does not pass (0.5), 3 (strip 1) is met and hidden, 4 passes
    assert kernel.next_candidate(c, 2, 6, 1.0, 1.0, False) == 4
    assert _hidden(s, 1) == [3, 0] and s.tree[leaves + 3] == -3.0
    assert s.tree[leaves + 2] == 0.5  # not met: the screening passed over it
    assert kernel.next_candidate(c, 5, 6, 1.0, 1.0, False) == -1  # 5 is hidden on the way
    assert _hidden(s, 1) == [5, 3, 0]
    assert _tree_holds_its_maxima(s.tree, leaves)
    # the same in the paper's order finds every strip's candidates, hiding none
    s.ipar[kernel.I_STRIP] = -1
    assert kernel.next_candidate(c, 0, 6, 0.1, 1.0, False) == 1  # 0 is hidden now
    # switching to strip 1 puts back the radii of its active candidates
    bins = sweep.Bins(np.full((2, 1), -1), np.full(6, -1), np.full(6, sweep.ACTIVE))
    bins.flag[5] = sweep.RETIRED  # retired while hidden: stays hidden
    sweep._show(1, s, bins)
    assert _hidden(s, 1) == []
    assert np.all(s.hnext[:6] == kernel.NOT_LISTED)
    assert list(s.tree[leaves : leaves + 6]) == [np.inf, 2.0, 0.5, 3.0, np.inf, -1.5]
    # a candidate already on a list is not put on it twice (a cycle would never end)
    s.ipar[kernel.I_STRIP] = 0
    kernel.hide_candidate(3, -np.inf, c)
    kernel.hide_candidate(3, -np.inf, c)
    assert _hidden(s, 1) == [3]
    assert _tree_holds_its_maxima(s.tree, leaves)


@pytest.mark.parametrize("closing", ["paced", "prompt", "tail"])
@pytest.mark.parametrize("disks", [False, True])
def test_candidates_of_the_strips_not_searched_are_hidden(closing: str, disks: bool) -> None:
    """Run in chunks; after each: the strip searched shows every active candidate's radius,
    the others' active candidates are all on their strip's hidden list, negated."""
    from regopack.plugins.inserters.available_arc import kernel
    from regopack.plugins.inserters.available_arc.state import ArcState

    domain = Rectangle.centred(160.0, 90.0)
    n = round(1.2 * domain.area / Change5(Change5Config()).mean_area)
    pop, rng = change5_population(n, 11)
    if disks:
        pop = disks_and_octagons(pop.radius, rng, 1.0)
    st_ = ArcState(pop, domain, t=0.999, tau=None, linear=False)
    assert st_.counter(kernel.I_DISKS) == int(disks)
    sw = sweep.Sweep(n, domain.height, 6.0 * float(pop.radius.max()), closing, 160.0, 30.0)
    assert sw.nstrip == 5
    s = st_.packed
    leaves = st_.counter(kernel.I_LEAVES)
    switches = hidden_seen = 0
    last = -1
    for begin in range(0, n, 29):
        sw.run(begin, min(n, begin + 29), st_.outlines, s, st_.work, rng, st_.rounded)
        count = st_.count
        cur = int(sw.zs[sweep.Z_CUR])
        switches += cur != last
        last = cur
        assert st_.counter(kernel.I_STRIP) == cur
        leaf = s.tree[leaves : leaves + count]
        flag = sw.flag[:count]
        home = s.home[:count]
        lists = {t: _hidden(s, t) for t in range(sw.nstrip)}
        assert lists[cur] == []
        on_list = np.zeros(count, dtype=bool)
        for t, ks in lists.items():
            assert len(set(ks)) == len(ks) and np.all(home[ks] == t)
            on_list[ks] = True
        active = flag == sweep.ACTIVE
        assert np.all(leaf[~active] == -np.inf)
        assert np.all(leaf[active & (home == cur)] > 0)
        other = active & (home != cur)
        assert np.all(on_list[other]) and np.all(leaf[other] < 0)  # hidden on a list
        hidden_seen += int(np.count_nonzero(on_list & active))
        assert _tree_holds_its_maxima(s.tree, leaves)
    assert switches > 3 and hidden_seen > 0


def test_the_strip_searched_keeps_the_turn_within_a_tenth_of_a_zone() -> None:
    """The lowest open strip takes the next particle, unless the strip searched stands
    at most ``stay`` bins above it (and is open, not full and not tried)."""
    choose = sweep._choose
    sz = np.zeros((3, sweep.N_SZ), dtype=np.int64)
    sz[:, sweep.S_SEEDED] = 1
    sz[:, sweep.S_HI] = [13, 5, 20]
    tried = np.full(3, -2, dtype=np.int64)
    assert choose(sz, tried, 7, 0, 8) == 0  # 13 - 5 = 8 bins: stays
    assert choose(sz, tried, 7, 0, 7) == 1  # beyond: the lowest
    assert choose(sz, tried, 7, 2, 8) == 1  # 20 - 5 = 15 bins
    assert choose(sz, tried, 7, -1, 8) == 1  # no strip searched yet
    assert choose(sz, tried, 7, 0, -1) == 1  # no stay: always the lowest
    sz[1, sweep.S_HI] = 13
    assert choose(sz, tried, 7, 1, 0) == 1  # a tie keeps the turn too
    sz[1, sweep.S_HI] = 5
    tried[0] = 7  # particle 7 was refused by strip 0: the lowest of the others
    assert choose(sz, tried, 7, 0, 8) == 1
    tried[0] = -2
    sz[0, sweep.S_FULL] = 1  # a full strip passes the turn at once
    assert choose(sz, tried, 7, 0, 8) == 1
    sz[0, sweep.S_FULL] = 0
    sz[0, sweep.S_CLOSED] = 1
    assert choose(sz, tried, 7, 0, 8) == 1
    sz[0, sweep.S_CLOSED] = 0
    # measured from the lowest strip not tried: 13 - 10 = 3 bins
    sz[:, sweep.S_HI] = [13, 5, 10]
    tried[1] = 7
    assert choose(sz, tried, 7, 0, 3) == 0 and choose(sz, tried, 7, 0, 2) == 2
    tried[1] = -2
    assert choose(sz, tried, 7, 1, 8) == 1  # the strip searched is the lowest
    # at the top, a strip not yet marked full keeps the turn over a full one ...
    sz[:, sweep.S_HI] = 30
    sz[:, sweep.S_FULL] = [1, 1, 0]
    assert choose(sz, tried, 7, 2, 8) == 2
    # ... and full strips take turns after the strip searched, so they close together
    sz[2, sweep.S_FULL] = 1
    assert [choose(sz, tried, 7, c, 8) for c in (0, 1, 2)] == [1, 2, 0]
    sz[:, sweep.S_CLOSED] = 1
    assert choose(sz, tried, -1, -1, 0) == -1  # no open strip left


@pytest.mark.parametrize(("zone", "stay"), [(100.0, 8), (2000.0, 8), (0.008, 0)])
def test_the_band_is_a_tenth_of_a_zone_of_at_most_80_bins(zone: float, stay: int) -> None:
    """A zone taller than the domain (more than ``ZONE_BINS`` bins) keeps the band of
    8 bins; a zone of fewer than ten bins (``MAX_BINS``) keeps the turn on ties only."""
    sw = sweep.Sweep(10, 1000.0, zone, width=400.0, strip=100.0)
    assert sw.zs[sweep.Z_STAY] == stay
