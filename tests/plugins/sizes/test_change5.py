"""Chang'e-5 size distribution: the facts of SPEC §1 and a KS test of samples."""

from __future__ import annotations

import math

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st
from pydantic import ValidationError
from scipy import stats

from regopack.plugins.sizes.change5 import Change5, Change5Config


@pytest.fixture(scope="module")
def dist() -> Change5:
    return Change5(Change5Config())


def test_mean_diameter(dist: Change5) -> None:
    assert dist.mean_diameter == pytest.approx(5.617, abs=5e-4)


def test_mean_area(dist: Change5) -> None:
    assert dist.mean_area == pytest.approx(38.60, abs=5e-3)


def test_tail_above_35um(dist: Change5) -> None:
    assert 1.0 - float(dist.cdf(35.0)) == pytest.approx(0.00091, abs=5e-6)


def test_auto_count_of_table1_domain(dist: Change5) -> None:
    assert round(800.0 * 800.0 / dist.mean_area) == 16579


def test_samples_within_bounds_and_ks(dist: Change5) -> None:
    r = dist.sample(20000, np.random.default_rng(3))
    d = 2.0 * r
    assert d.min() >= 2.0 and d.max() <= 40.0
    result = stats.kstest(d, lambda x: dist.cdf(x))
    assert result.pvalue > 1e-3


def test_ks_detects_a_wrong_exponent(dist: Change5) -> None:
    other = Change5(Change5Config(alpha=5.0))
    d = 2.0 * other.sample(20000, np.random.default_rng(3))
    assert stats.kstest(d, lambda x: dist.cdf(x)).pvalue < 1e-6


def test_sample_mean_matches_moment(dist: Change5) -> None:
    r = dist.sample(200000, np.random.default_rng(5))
    assert np.mean(math.pi * r**2) == pytest.approx(dist.mean_area, rel=0.01)
    assert np.mean(4.0 / 3.0 * math.pi * r**3) == pytest.approx(dist.mean_volume, rel=0.02)


def test_ppf_inverts_cdf(dist: Change5) -> None:
    u = np.linspace(0.0, 1.0, 101)
    assert np.allclose(dist.cdf(dist.ppf(u)), u, atol=1e-12)


@given(scale=st.sampled_from([1e-6, 1e-3, 1.0, 1e3, 1e6]))
@settings(max_examples=10, deadline=None)
def test_scale_invariance(scale: float) -> None:
    base = Change5(Change5Config())
    scaled = Change5(Change5Config(d_min=2 * scale, d_max=40 * scale, d0=16 * scale))
    u = np.random.default_rng(0).random(1000)
    assert np.allclose(scaled.ppf(u) / scale, base.ppf(u), rtol=1e-12)
    assert scaled.mean_area / scale**2 == pytest.approx(base.mean_area, rel=1e-12)


def test_alpha_one_uses_log_form() -> None:
    dist = Change5(Change5Config(alpha=1.0))
    u = np.linspace(0, 1, 11)
    d = dist.ppf(u)
    assert d[0] == pytest.approx(2.0) and d[-1] == pytest.approx(40.0)
    assert np.all(np.diff(d) > 0)


@pytest.mark.parametrize(
    ("params", "field"),
    [
        ({"d_min": -1.0}, "d_min"),
        ({"alpha": 0.0}, "alpha"),
        ({"d_max": 1.0}, "d_max"),
        ({"bogus": 1}, "bogus"),
    ],
)
def test_bad_parameters_are_rejected(params: dict[str, float], field: str) -> None:
    with pytest.raises(ValidationError, match=field):
        Change5Config.model_validate(params)
