"""The contract checks of :mod:`regopack.testing` pass for the built-in plugins and
fail, with a clear message, for plugins that break a rule."""

from __future__ import annotations

import math

import numpy as np
import pytest
from pydantic import ValidationError

from regopack.geometry.population import ShapeBatch
from regopack.plugins.density.eta import EtaConfig, EtaController
from regopack.plugins.shapes.octagon import OctagonConfig, RandomPolygon
from regopack.plugins.sizes.change5 import Change5, Change5Config
from regopack.registry.interfaces import DensityController, ShapeGenerator, SizeDistribution
from regopack.registry.manager import default_registry
from regopack.testing import (
    DEFAULT_RADII,
    check_density_controller,
    check_shape_generator,
    check_size_distribution,
    check_solid_generator,
)

# ---------------------------------------------------------------------------
# the built-in plugins pass


@pytest.mark.parametrize(
    "params",
    [{}, {"psi": 0.25}, {"psi": 15.0}, {"psi": 2.0, "a": 1.0}, {"m": 3}, {"m": 64}],
    ids=str,
)
def test_octagon_keeps_the_shape_contract(params):
    batch = check_shape_generator(RandomPolygon(OctagonConfig(**params)))
    assert len(batch) == len(DEFAULT_RADII)


def test_octagon_with_other_radii_and_seed():
    check_shape_generator(RandomPolygon(OctagonConfig()), radii=[1e-6, 1.0, 1e6], seed=42)


@pytest.mark.parametrize(
    "params", [{}, {"d_min": 1.0, "d_max": 2.0}, {"alpha": 1.0, "d0": 0.0}], ids=str
)
def test_change5_keeps_the_size_contract(params):
    radii = check_size_distribution(Change5(Change5Config(**params)))
    assert radii.shape == (100_000,)


@pytest.mark.parametrize("eta", [0.0, 1.0, 10.0, 50.0, 1000.0])
def test_eta_keeps_the_controller_contract(eta):
    check_density_controller(EtaController(EtaConfig(eta=eta)))


def test_every_registered_plugin_with_defaults_keeps_its_contract():
    registry = default_registry(autoload=False)
    checked = []
    for kind, check in (
        ("shape", check_shape_generator),
        ("size", check_size_distribution),
        ("density", check_density_controller),
    ):
        for name in registry.names(kind):
            spec = registry.get(kind, name)
            if any(f.is_required() for f in spec.config_model.model_fields.values()):
                continue  # needs parameters we cannot guess (e.g. a file)
            try:
                built = spec.build({})
            except ValidationError:
                continue  # no defaults alone (a density target needs its value)
            if getattr(spec, "dimension", 2) == 3:
                check_solid_generator(built)
            else:
                check(built)
            checked.append(name)
    assert {"octagon", "change5", "eta", "sphere"} <= set(checked)


# ---------------------------------------------------------------------------
# broken shape generators fail


def regular(radius: np.ndarray, m: int, theta: np.ndarray | None = None) -> ShapeBatch:
    """Regular m-gons of area pi r^2 (counter-clockwise)."""
    n = radius.shape[0]
    theta = np.zeros(n) if theta is None else theta
    big = radius * math.sqrt(2 * math.pi / (m * math.sin(2 * math.pi / m)))
    ang = theta[:, None] + 2 * math.pi * np.arange(m) / m
    v = np.stack([big[:, None] * np.cos(ang), big[:, None] * np.sin(ang)], axis=-1)
    return ShapeBatch(v.reshape(-1, 2), np.arange(0, m * n + 1, m, dtype=np.int64), theta)


class Hexagons(ShapeGenerator):
    def generate(self, radius, rng):  # type: ignore[no-untyped-def]
        return regular(radius, 6, rng.uniform(0, 1, radius.shape[0]))


class WrongArea(ShapeGenerator):
    def generate(self, radius, rng):  # type: ignore[no-untyped-def]
        return regular(1.1 * radius, 6)


class Clockwise(ShapeGenerator):
    def generate(self, radius, rng):  # type: ignore[no-untyped-def]
        b = regular(radius, 6)
        flipped = b.vertices.reshape(-1, 6, 2)[:, ::-1].reshape(-1, 2)
        return ShapeBatch(flipped, b.offsets, b.orientation)


class Star(ShapeGenerator):
    """A non-convex dart: a square with one corner pushed in, scaled to area pi r^2."""

    def generate(self, radius, rng):  # type: ignore[no-untyped-def]
        dart = np.array([[-0.5, -0.5], [1.5, -0.5], [0.2, 0.2], [-0.5, 1.5]])
        x, y = dart[:, 0], dart[:, 1]
        area = 0.5 * np.sum(x * np.roll(y, -1) - np.roll(x, -1) * y)
        scale = np.sqrt(np.pi / area) * radius
        v = (scale[:, None, None] * dart[None]).reshape(-1, 2)
        n = radius.shape[0]
        return ShapeBatch(v, np.arange(0, 4 * n + 1, 4, dtype=np.int64), np.zeros(n))


class Pentagram(ShapeGenerator):
    """Visits the vertices of a regular pentagon in the order 0, 2, 4, 1, 3: turns only
    left, but winds twice."""

    def generate(self, radius, rng):  # type: ignore[no-untyped-def]
        b = regular(radius, 5)
        v = b.vertices.reshape(-1, 5, 2)[:, [0, 2, 4, 1, 3]]
        x, y = v[..., 0], v[..., 1]
        area = 0.5 * np.sum(x * np.roll(y, -1, axis=1) - np.roll(x, -1, axis=1) * y, axis=1)
        v = v * np.sqrt(np.pi * radius**2 / area)[:, None, None]
        return ShapeBatch(v.reshape(-1, 2), b.offsets, b.orientation)


class OffCentre(ShapeGenerator):
    def generate(self, radius, rng):  # type: ignore[no-untyped-def]
        b = regular(radius, 6)
        big = np.repeat(2.0 * radius, 6)
        return ShapeBatch(b.vertices + np.stack([big, 0 * big], axis=1), b.offsets, b.orientation)


class Unseeded(ShapeGenerator):
    def __init__(self) -> None:
        self.own = np.random.default_rng()

    def generate(self, radius, rng):  # type: ignore[no-untyped-def]
        return regular(radius, 6, self.own.uniform(0, 1, radius.shape[0]))


class GlobalRandom(ShapeGenerator):
    def generate(self, radius, rng):  # type: ignore[no-untyped-def]
        return regular(radius, 6, np.random.uniform(0, 1, radius.shape[0]))  # noqa: NPY002


class WrongCount(ShapeGenerator):
    def generate(self, radius, rng):  # type: ignore[no-untyped-def]
        return regular(radius[:-1], 6) if radius.shape[0] else regular(radius, 6)


class NotABatch(ShapeGenerator):
    def generate(self, radius, rng):  # type: ignore[no-untyped-def]
        return [regular(radius, 6)]


class EmptyFails(ShapeGenerator):
    def generate(self, radius, rng):  # type: ignore[no-untyped-def]
        if radius.shape[0] == 0:
            raise ValueError("zero-size array to reduction operation maximum")
        return regular(radius, 6)


def test_a_good_fake_passes():
    check_shape_generator(Hexagons())


@pytest.mark.parametrize(
    ("generator", "message"),
    [
        (WrongArea(), r"outline 0 \(radius 0.01\) has area .* expected pi r\^2"),
        (Clockwise(), "is not counter-clockwise"),
        (Star(), "is not convex: it turns clockwise"),
        (Pentagram(), "is not convex: .* winds around more than once"),
        (OffCentre(), r"reference point \(0, 0\) is not strictly inside"),
        (Unseeded(), "is not deterministic"),
        (GlobalRandom(), "global random generator"),
        (WrongCount(), r"offsets have shape \(41,\), expected \(42,\)"),
        (NotABatch(), "returned a list, not a ShapeBatch"),
    ],
    ids=lambda x: type(x).__name__ if isinstance(x, ShapeGenerator) else "",
)
def test_broken_shape_generators_fail(generator, message):
    with pytest.raises(AssertionError, match=message) as info:
        check_shape_generator(generator)
    assert type(generator).__name__ in str(info.value)


def test_a_generator_that_cannot_take_no_radii_fails():
    with pytest.raises(ValueError, match="zero-size"):
        check_shape_generator(EmptyFails())


def test_area_tolerance_is_adjustable():
    check_shape_generator(WrongArea(), rtol=0.25)


# ---------------------------------------------------------------------------
# broken size distributions fail


class Uniform(SizeDistribution):
    """Radii uniform on [lo, hi]; the fakes below break one rule each."""

    lo, hi = 1.0, 3.0

    def sample(self, n, rng):  # type: ignore[no-untyped-def]
        return rng.uniform(self.lo, self.hi, n)

    @property
    def mean_area(self) -> float:
        a, b = self.lo, self.hi
        return math.pi * (a * a + a * b + b * b) / 3

    @property
    def r_min(self) -> float:
        return self.lo

    @property
    def r_max(self) -> float:
        return self.hi


class OutOfBounds(Uniform):
    def sample(self, n, rng):  # type: ignore[no-untyped-def]
        return rng.uniform(self.lo, 1.01 * self.hi, n)


class BelowMinimum(Uniform):
    def sample(self, n, rng):  # type: ignore[no-untyped-def]
        return rng.uniform(0.5 * self.lo, self.hi, n)


class WrongMean(Uniform):
    @property
    def mean_area(self) -> float:
        return math.pi * ((self.lo + self.hi) / 2) ** 2  # pi E[r]^2, not E[pi r^2]


class BadBounds(Uniform):
    @property
    def r_min(self) -> float:
        return 4.0


class Unseeded2(Uniform):
    def sample(self, n, rng):  # type: ignore[no-untyped-def]
        return np.random.default_rng().uniform(self.lo, self.hi, n)


class NotFinite(Uniform):
    def sample(self, n, rng):  # type: ignore[no-untyped-def]
        out = rng.uniform(self.lo, self.hi, n)
        out[n // 2 :] = np.nan
        return out


class WrongLength(Uniform):
    def sample(self, n, rng):  # type: ignore[no-untyped-def]
        return rng.uniform(self.lo, self.hi, n + 1)


def test_a_good_size_fake_passes():
    check_size_distribution(Uniform())


@pytest.mark.parametrize(
    ("dist", "message"),
    [
        (OutOfBounds(), "above r_max = 3"),
        (BelowMinimum(), "below r_min = 1"),
        (WrongMean(), "mean_area declares .*relative difference"),
        (BadBounds(), "0 < r_min <= r_max"),
        (Unseeded2(), "is not deterministic"),
        (NotFinite(), "not finite"),
        (WrongLength(), r"returned shape \(1,\), expected \(0,\)"),
    ],
    ids=lambda x: type(x).__name__ if isinstance(x, SizeDistribution) else "",
)
def test_broken_size_distributions_fail(dist, message):
    with pytest.raises(AssertionError, match=message) as info:
        check_size_distribution(dist, n=20_000)
    assert type(dist).__name__ in str(info.value)


# ---------------------------------------------------------------------------
# broken density controllers fail


class Trim(DensityController):
    def shrink(self, arcs, r_new, r_candidate, rng):  # type: ignore[no-untyped-def]
        out = arcs + np.array([0.01, -0.01]) * rng.random((arcs.shape[0], 1))
        return out[out[:, 1] > out[:, 0]]


class Lengthens(DensityController):
    def shrink(self, arcs, r_new, r_candidate, rng):  # type: ignore[no-untyped-def]
        return arcs + np.array([-0.01, 0.01])


class Shifts(DensityController):
    """Keeps every length but moves the arcs: the end leaves the input arc."""

    def shrink(self, arcs, r_new, r_candidate, rng):  # type: ignore[no-untyped-def]
        return arcs + 0.001


class Duplicates(DensityController):
    """Returns each arc twice: each copy is inside, but together they are longer."""

    def shrink(self, arcs, r_new, r_candidate, rng):  # type: ignore[no-untyped-def]
        return np.concatenate([arcs, arcs])


class KeepsEmpty(DensityController):
    def shrink(self, arcs, r_new, r_candidate, rng):  # type: ignore[no-untyped-def]
        out = arcs.copy()
        out[:, 1] = np.maximum(out[:, 0], out[:, 1] - 0.5)
        return out


class InPlace(DensityController):
    def shrink(self, arcs, r_new, r_candidate, rng):  # type: ignore[no-untyped-def]
        arcs[:, 0] += 0.0 if arcs.size == 0 else 1e-12 * (arcs[:, 1] - arcs[:, 0])
        return arcs


class FalseIdentity(Trim):
    identity = True


class Unseeded3(DensityController):
    def shrink(self, arcs, r_new, r_candidate, rng):  # type: ignore[no-untyped-def]
        cut = np.random.default_rng().random((arcs.shape[0], 1)) * 1e-3
        out = arcs + np.hstack([cut, -cut])
        return out[out[:, 1] > out[:, 0]]


class Flat(DensityController):
    def shrink(self, arcs, r_new, r_candidate, rng):  # type: ignore[no-untyped-def]
        return arcs.ravel()


def test_a_good_controller_fake_passes():
    check_density_controller(Trim())


@pytest.mark.parametrize(
    ("controller", "message"),
    [
        (Lengthens(), "lengthened an arc: .* is not inside any input arc"),
        (Shifts(), "lengthened an arc"),
        (Duplicates(), "lengthened an arc: the arcs it returned inside .* add up to"),
        (KeepsEmpty(), "of no length; drop such arcs"),
        (InPlace(), "changed its input array"),
        (FalseIdentity(), "declares identity = True"),
        (Unseeded3(), "is not deterministic"),
        (Flat(), r"expected \(k, 2\)"),
    ],
    ids=lambda x: type(x).__name__ if isinstance(x, DensityController) else "",
)
def test_broken_density_controllers_fail(controller, message):
    with pytest.raises(AssertionError, match=message) as info:
        check_density_controller(controller)
    assert type(controller).__name__ in str(info.value)
