"""Size distributions lognormal, rosin-rammler, uniform, monodisperse and tabulated.

Analytic moments and CDFs are checked against scipy.stats and closed forms,
samples against them with KS tests and standard-error tolerances.
"""

from __future__ import annotations

import doctest
import math
from pathlib import Path
from typing import Any

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st
from pydantic import BaseModel, ValidationError
from scipy import integrate, stats

import regopack.plugins.sizes.distributions as sd
from regopack.base.errors import ConfigError
from regopack.plugins.sizes.distributions import (
    LogNormal,
    LogNormalConfig,
    Monodisperse,
    MonodisperseConfig,
    RosinRammler,
    RosinRammlerConfig,
    Tabulated,
    TabulatedConfig,
    Uniform,
    UniformConfig,
    read_sieve_table,
)
from regopack.registry.manager import default_registry

N = 100_000
KINDS = ("lognormal", "rosin-rammler", "uniform", "monodisperse", "tabulated")


def write_table(path: Path, sizes: Any, percent: Any, header: str = "size_um,passing_pct") -> Path:
    lines = [header] if header else []
    lines += [f"{float(d)!r},{float(p)!r}" for d, p in zip(sizes, percent, strict=True)]
    path.write_text("\n".join(lines) + "\n", encoding="utf-8")
    return path


def assert_moments_match(d: np.ndarray, dist: Any, z: float = 5.0) -> None:
    """Sample mean diameter, area and volume agree with the analytic values within z SE."""
    for values, expected in (
        (d, dist.mean_diameter),
        (math.pi / 4 * d**2, dist.mean_area),
        (math.pi / 6 * d**3, dist.mean_volume),
    ):
        se = values.std() / math.sqrt(len(values))
        assert abs(values.mean() - expected) < z * se + 1e-12 * abs(expected)


# ---------------------------------------------------------------------------
# lognormal and rosin-rammler against scipy.stats


LOGNORMAL_CASES = [
    {"median": 10.0, "sigma": 0.5},
    {"mean": 10.0, "sigma": 1.0},
    {"median": 10.0, "sigma": 0.8, "d_min": 4.0, "d_max": 30.0},
    {"median": 10.0, "sigma": 0.8, "d_min": 25.0},
    {"median": 1.0, "sigma": 0.3, "d_max": 0.3},
]


def parent_lognormal(cfg: LogNormalConfig) -> Any:
    return stats.lognorm(cfg.sigma, scale=cfg.median_diameter)


def truncated_moment(parent: Any, k: int, lo: float, hi: float) -> float:
    mass = parent.cdf(hi) - parent.cdf(lo)
    points = [p for p in parent.ppf([0.01, 0.5, 0.99]) if lo < p < hi]
    if math.isinf(hi):
        value = integrate.quad(lambda x: x**k * parent.pdf(x), lo, np.inf, limit=200)[0]
    else:
        value = integrate.quad(
            lambda x: x**k * parent.pdf(x), lo, hi, points=points or None, limit=200
        )[0]
    return float(value / mass)


@pytest.mark.parametrize("params", LOGNORMAL_CASES)
def test_lognormal_moments_and_cdf(params: dict[str, float]) -> None:
    cfg = LogNormalConfig(**params)
    dist = LogNormal(cfg)
    parent = parent_lognormal(cfg)
    lo, hi = params.get("d_min", 0.0), params.get("d_max", math.inf)
    for k in (1, 2):
        assert dist.moment(k) == pytest.approx(truncated_moment(parent, k, lo, hi), rel=1e-8)
    x = np.geomspace(max(lo, parent.ppf(1e-6)), min(hi, parent.ppf(1 - 1e-6)), 50)
    expected = (parent.cdf(x) - parent.cdf(lo)) / (parent.cdf(hi) - parent.cdf(lo))
    assert np.allclose(dist.cdf(x), expected, atol=1e-12)


def test_lognormal_untruncated_closed_forms() -> None:
    mu, s = math.log(7.0), 0.6
    dist = LogNormal(LogNormalConfig(median=7.0, sigma=s))
    assert dist.mean_area == pytest.approx(math.pi / 4 * math.exp(2 * mu + 2 * s * s), rel=1e-14)
    assert dist.mean_diameter == pytest.approx(math.exp(mu + s * s / 2), rel=1e-14)
    by_mean = LogNormal(LogNormalConfig(mean=dist.mean_diameter, sigma=s))
    assert by_mean.median == pytest.approx(7.0, rel=1e-14)


RR_CASES = [
    {"d63": 10.0, "n": 2.0},
    {"d63": 10.0, "n": 0.7},
    {"d63": 10.0, "n": 3.5, "d_min": 5.0, "d_max": 12.0},
    {"d63": 10.0, "n": 1.2, "d_min": 30.0},
    {"d63": 10.0, "n": 4.0, "d_max": 2.0},
]


@pytest.mark.parametrize("params", RR_CASES)
def test_rosin_rammler_moments_and_cdf(params: dict[str, float]) -> None:
    cfg = RosinRammlerConfig(**params)
    dist = RosinRammler(cfg)
    parent = stats.weibull_min(cfg.n, scale=cfg.d63)
    lo, hi = params.get("d_min", 0.0), params.get("d_max", math.inf)
    for k in (1, 2):
        assert dist.moment(k) == pytest.approx(truncated_moment(parent, k, lo, hi), rel=1e-8)
    x = np.geomspace(max(lo, parent.ppf(1e-6)), min(hi, parent.ppf(1 - 1e-6)), 50)
    expected = (parent.cdf(x) - parent.cdf(lo)) / (parent.cdf(hi) - parent.cdf(lo))
    assert np.allclose(dist.cdf(x), expected, atol=1e-12)


def test_rosin_rammler_untruncated_closed_forms() -> None:
    dist = RosinRammler(RosinRammlerConfig(d63=3.0, n=1.7))
    assert dist.mean_area == pytest.approx(math.pi / 4 * 9.0 * math.gamma(1 + 2 / 1.7), rel=1e-14)
    assert dist.mean_diameter == pytest.approx(3.0 * math.gamma(1 + 1 / 1.7), rel=1e-14)
    assert float(dist.cdf(3.0)) == pytest.approx(1 - math.exp(-1), rel=1e-15)


@pytest.mark.parametrize(
    "dist",
    [LogNormal(LogNormalConfig(**p)) for p in LOGNORMAL_CASES]
    + [RosinRammler(RosinRammlerConfig(**p)) for p in RR_CASES],
    ids=[f"lognormal{i}" for i in range(len(LOGNORMAL_CASES))]
    + [f"rosin-rammler{i}" for i in range(len(RR_CASES))],
)
def test_samples_match_moments_cdf_and_bounds(dist: Any) -> None:
    d = dist.sample_diameters(N, np.random.default_rng(11))
    assert_moments_match(d, dist)
    assert stats.kstest(d, dist.cdf).pvalue > 1e-3
    assert np.all(d >= 2 * dist.r_min) and np.all(d <= 2 * dist.r_max)
    cfg = dist.config
    if cfg.d_min is not None:
        assert dist.r_min == cfg.d_min / 2 and d.min() >= cfg.d_min
    if cfg.d_max is not None:
        assert dist.r_max == cfg.d_max / 2 and d.max() <= cfg.d_max


def test_ks_detects_a_wrong_sigma() -> None:
    dist = LogNormal(LogNormalConfig(median=10.0, sigma=0.5))
    other = LogNormal(LogNormalConfig(median=10.0, sigma=0.55))
    d = other.sample_diameters(N, np.random.default_rng(1))
    assert stats.kstest(d, dist.cdf).pvalue < 1e-6


def test_unbounded_tails_give_finite_positive_extremes() -> None:
    wide = LogNormal(LogNormalConfig(median=1.0, sigma=5.0))
    assert 0 < wide.r_min < wide.r_max < math.inf
    # the extreme quantiles 2^-54 and 1 - 2^-54
    z = stats.norm.isf(2.0**-54)
    assert 2 * wide.r_max == pytest.approx(math.exp(5.0 * z), rel=1e-9)
    assert 2 * wide.r_min == pytest.approx(math.exp(-5.0 * z), rel=1e-9)
    heavy = RosinRammler(RosinRammlerConfig(d63=1.0, n=0.1))
    assert 0 < heavy.r_min and math.isfinite(heavy.r_max)
    r = heavy.sample(10_000, np.random.default_rng(0))
    assert np.all((r >= heavy.r_min) & (r <= heavy.r_max))


def test_upper_tail_quantiles_keep_precision() -> None:
    dist = LogNormal(LogNormalConfig(median=1.0, sigma=1.0))
    q = np.array([1e-10, 1e-14])
    d = dist._quantile(1.0 - q, q)
    assert np.log(d) == pytest.approx(stats.norm.isf(q), rel=1e-12)


# ---------------------------------------------------------------------------
# uniform and monodisperse


def test_uniform() -> None:
    a, b = 3.0, 11.0
    dist = Uniform(UniformConfig(d_min=a, d_max=b))
    assert dist.mean_area == pytest.approx(math.pi / 4 * (b**3 - a**3) / (3 * (b - a)), rel=1e-15)
    assert dist.mean_diameter == (a + b) / 2
    assert dist.moment(3) == pytest.approx((b**4 - a**4) / (4 * (b - a)), rel=1e-14)
    assert dist.moment(-1) == pytest.approx(math.log(b / a) / (b - a), rel=1e-14)
    d = dist.sample_diameters(N, np.random.default_rng(2))
    assert d.min() >= a and d.max() <= b
    assert (dist.r_min, dist.r_max) == (a / 2, b / 2)
    assert_moments_match(d, dist)
    assert stats.kstest(d, stats.uniform(a, b - a).cdf).pvalue > 1e-3


def test_monodisperse() -> None:
    dist = Monodisperse(MonodisperseConfig(d=4.0))
    rng = np.random.default_rng(0)
    state = rng.bit_generator.state
    assert np.all(dist.sample(5, rng) == 2.0)
    assert rng.bit_generator.state == state  # no random numbers drawn
    assert dist.mean_area == pytest.approx(4 * math.pi, rel=1e-15)
    assert dist.r_min == dist.r_max == 2.0
    assert dist.cdf([3.9, 4.0]).tolist() == [0.0, 1.0]


# ---------------------------------------------------------------------------
# scale invariance and determinism


def configs(scale: float, table: Path) -> list[tuple[type, BaseModel]]:
    return [
        (LogNormal, LogNormalConfig(median=10 * scale, sigma=0.7)),
        (LogNormal, LogNormalConfig(mean=10 * scale, sigma=0.7, d_min=3 * scale, d_max=40 * scale)),
        (RosinRammler, RosinRammlerConfig(d63=10 * scale, n=1.5)),
        (RosinRammler, RosinRammlerConfig(d63=10 * scale, n=1.5, d_min=scale, d_max=20 * scale)),
        (Uniform, UniformConfig(d_min=2 * scale, d_max=9 * scale)),
        (Monodisperse, MonodisperseConfig(d=5 * scale)),
        (Tabulated, TabulatedConfig(path=table, basis="mass")),
    ]


SIEVES = np.array([1.0, 2.0, 4.0, 8.0, 16.0, 32.0])
PASSING = np.array([0.0, 5.0, 20.0, 55.0, 90.0, 100.0])


@given(exponent=st.floats(min_value=-6.0, max_value=6.0))
@settings(max_examples=12, deadline=None)
def test_scale_invariance(exponent: float, tmp_path_factory: pytest.TempPathFactory) -> None:
    scale = 10.0**exponent
    folder = tmp_path_factory.mktemp("scale")
    base_table = write_table(folder / "base.csv", SIEVES, PASSING)
    scaled_table = write_table(folder / "scaled.csv", SIEVES * scale, PASSING)
    u = np.random.default_rng(0).random(2000)
    for (cls, base_cfg), (_, scaled_cfg) in zip(
        configs(1.0, base_table), configs(scale, scaled_table), strict=True
    ):
        base, scaled = cls(base_cfg), cls(scaled_cfg)
        assert np.allclose(scaled.ppf(u) / scale, base.ppf(u), rtol=1e-12, atol=0)
        r0 = base.sample(500, np.random.default_rng(4))
        r1 = scaled.sample(500, np.random.default_rng(4))
        assert np.allclose(r1 / scale, r0, rtol=1e-12, atol=0)
        assert scaled.mean_area / scale**2 == pytest.approx(base.mean_area, rel=1e-12)
        assert scaled.r_min / scale == pytest.approx(base.r_min, rel=1e-12)
        assert scaled.r_max / scale == pytest.approx(base.r_max, rel=1e-12)


def test_same_seed_same_sample(tmp_path: Path) -> None:
    table = write_table(tmp_path / "t.csv", SIEVES, PASSING)
    for cls, cfg in configs(1.0, table):
        dist = cls(cfg)
        a = dist.sample(1000, np.random.default_rng(123))
        b = dist.sample(1000, np.random.default_rng(123))
        assert np.array_equal(a, b)
        assert np.all(np.isfinite(a) & (a > 0))
        assert a.dtype == np.float64 and a.shape == (1000,)
        if cls is not Monodisperse:
            assert not np.array_equal(a, dist.sample(1000, np.random.default_rng(124)))


# ---------------------------------------------------------------------------
# validation of the parameters


@pytest.mark.parametrize(
    ("model", "params", "match"),
    [
        (LogNormalConfig, {"sigma": 0.5}, "exactly one of median and mean"),
        (LogNormalConfig, {"median": 1.0, "mean": 2.0, "sigma": 0.5}, "got both"),
        (LogNormalConfig, {"median": 1.0}, "sigma"),
        (LogNormalConfig, {"median": 1.0, "sigma": 0.0}, "sigma"),
        (LogNormalConfig, {"median": 1.0, "sigma": 6.0}, "sigma"),
        (LogNormalConfig, {"median": -1.0, "sigma": 1.0}, "median"),
        (LogNormalConfig, {"median": 1.0, "sigma": 1.0, "d_min": 2.0, "d_max": 2.0}, "d_max"),
        (LogNormalConfig, {"median": 1.0, "sigma": 0.1, "d_min": 100.0}, "probability"),
        (LogNormalConfig, {"median": 1.0, "sigma": 1.0, "bogus": 1}, "bogus"),
        (RosinRammlerConfig, {"d63": 1.0, "n": 0.05}, "n"),
        (RosinRammlerConfig, {"d63": 0.0, "n": 2.0}, "d63"),
        (RosinRammlerConfig, {"d63": 1.0, "n": 2.0, "d_min": 3.0, "d_max": 1.0}, "d_max"),
        (RosinRammlerConfig, {"d63": 1.0, "n": 2.0, "d_min": 10.0}, "probability"),
        (UniformConfig, {"d_min": 2.0, "d_max": 1.0}, "d_max"),
        (UniformConfig, {"d_min": 0.0, "d_max": 1.0}, "d_min"),
        (UniformConfig, {"d_min": 1.0, "d_max": math.inf}, "d_max"),
        (MonodisperseConfig, {"d": 0.0}, "d"),
        (MonodisperseConfig, {}, "d"),
    ],
)
def test_bad_parameters_are_rejected(
    model: type[BaseModel], params: dict[str, float], match: str
) -> None:
    with pytest.raises(ValidationError, match=match):
        model.model_validate(params)


# ---------------------------------------------------------------------------
# tabulated


def test_tabulated_number_single_segment_is_log_uniform(tmp_path: Path) -> None:
    a, b = 2.0, 8.0
    dist = Tabulated(
        TabulatedConfig(path=write_table(tmp_path / "t.csv", [a, b], [0, 100]), basis="number")
    )
    x = np.geomspace(a, b, 9)
    assert np.allclose(dist.cdf(x), np.log(x / a) / math.log(b / a), atol=1e-15)
    assert dist.mean_area == pytest.approx(
        math.pi / 4 * (b**2 - a**2) / (2 * math.log(b / a)), rel=1e-14
    )
    d = dist.sample_diameters(N, np.random.default_rng(3))
    assert_moments_match(d, dist)
    assert stats.kstest(d, dist.cdf).pvalue > 1e-3


def test_tabulated_mass_single_segment_is_exact(tmp_path: Path) -> None:
    # mass linear in ln d  =>  number density of d proportional to d^-4
    a, b = 2.0, 8.0
    dist = Tabulated(
        TabulatedConfig(path=write_table(tmp_path / "t.csv", [a, b], [0, 100]), basis="mass")
    )

    def cdf(d: Any) -> Any:
        return (1 - (a / np.asarray(d)) ** 3) / (1 - (a / b) ** 3)

    x = np.geomspace(a, b, 9)
    assert np.allclose(dist.cdf(x), cdf(x), atol=1e-14)
    mean_d2 = (1 / a - 1 / b) / ((a**-3 - b**-3) / 3)
    assert dist.mean_area == pytest.approx(math.pi / 4 * mean_d2, rel=1e-13)
    d = dist.sample_diameters(N, np.random.default_rng(4))
    assert stats.kstest(d, cdf).pvalue > 1e-3
    assert_moments_match(d, dist)


def test_tabulated_mass_exponent_zero_equals_number(tmp_path: Path) -> None:
    table = write_table(tmp_path / "t.csv", SIEVES, PASSING)
    by_number = Tabulated(TabulatedConfig(path=table, basis="number"))
    by_mass = Tabulated(TabulatedConfig(path=table, basis="mass", mass_exponent=0.0))
    u = np.linspace(0.001, 0.999, 99)
    assert np.allclose(by_mass.ppf(u), by_number.ppf(u), rtol=1e-13)
    assert by_mass.mean_area == pytest.approx(by_number.mean_area, rel=1e-13)


def test_tabulated_reproduces_a_rosin_rammler_curve(tmp_path: Path) -> None:
    weibull = stats.weibull_min(2.0, scale=10.0)
    sizes = np.geomspace(weibull.ppf(1e-6), weibull.ppf(1 - 1e-12), 60)
    table = write_table(tmp_path / "rr.csv", sizes, 100 * weibull.cdf(sizes))
    dist = Tabulated(TabulatedConfig(path=table, basis="number"))
    x = np.linspace(sizes[0], sizes[-1], 2001)
    assert np.max(np.abs(dist.cdf(x) - weibull.cdf(x))) < 5e-3
    exact = RosinRammler(RosinRammlerConfig(d63=10.0, n=2.0))
    assert dist.mean_area == pytest.approx(exact.mean_area, rel=1e-2)
    d = dist.sample_diameters(20_000, np.random.default_rng(6))
    assert stats.kstest(d, dist.cdf).pvalue > 1e-3


def test_tabulated_mass_curve_of_a_uniform_number_distribution(tmp_path: Path) -> None:
    # number uniform on [a, b]  =>  mass fraction passing (d^4 - a^4) / (b^4 - a^4)
    a, b = 2.0, 8.0
    sizes = np.geomspace(a, b, 60)
    table = write_table(tmp_path / "m.csv", sizes, 100 * (sizes**4 - a**4) / (b**4 - a**4))
    dist = Tabulated(TabulatedConfig(path=table, basis="mass"))
    x = np.linspace(a, b, 2001)
    assert np.max(np.abs(dist.cdf(x) - (x - a) / (b - a))) < 1e-3
    exact = Uniform(UniformConfig(d_min=a, d_max=b))
    assert dist.mean_area == pytest.approx(exact.mean_area, rel=2e-3)
    assert dist.mean_diameter == pytest.approx(exact.mean_diameter, rel=2e-3)
    # read as numbers, the same table would be far too coarse
    wrong = Tabulated(TabulatedConfig(path=table, basis="number"))
    assert wrong.mean_diameter > 1.1 * exact.mean_diameter


def test_tabulated_narrow_mass_curve_is_nearly_monodisperse(tmp_path: Path) -> None:
    table = write_table(tmp_path / "n.csv", [5.0, 5.001], [0, 100])
    dist = Tabulated(TabulatedConfig(path=table, basis="mass"))
    assert dist.mean_area == pytest.approx(math.pi / 4 * 25.0, rel=1e-3)
    d = dist.sample_diameters(1000, np.random.default_rng(0))
    assert d.min() >= 5.0 and d.max() <= 5.001


def test_tabulated_renormalises_and_skips_plateaus(tmp_path: Path) -> None:
    # 10 % finer than the first sieve and 5 % coarser than the last are left out;
    # nothing lies between 4 and 8
    table = write_table(tmp_path / "p.csv", [1, 2, 4, 8, 16, 32], [10, 10, 40, 40, 95, 95])
    dist = Tabulated(TabulatedConfig(path=table, basis="number"))
    assert (dist.r_min, dist.r_max) == (1.0, 8.0)
    assert float(dist.cdf(4.0)) == pytest.approx(30 / 85, rel=1e-14)
    d = dist.sample_diameters(N, np.random.default_rng(1))
    assert d.min() >= 2.0 and d.max() <= 16.0
    assert not np.any((d > 4.0) & (d < 8.0))
    assert_moments_match(d, dist)


def test_tabulated_reads_headers_comments_and_separators(tmp_path: Path) -> None:
    path = tmp_path / "s.csv"
    path.write_text(
        "\ufeff# sieve analysis, sample 7\nsize (um); passing (%)\n\n"
        "1.0 ; 0\n2.0\t30  # the 2 um sieve\n4.0 100,\n",
        encoding="utf-8",
    )
    sizes, percent = read_sieve_table(path)
    assert sizes.tolist() == [1.0, 2.0, 4.0] and percent.tolist() == [0.0, 30.0, 100.0]


def test_tabulated_relative_path_resolves_from_the_working_directory(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    write_table(tmp_path / "rel.csv", SIEVES, PASSING)
    monkeypatch.chdir(tmp_path)
    cfg = TabulatedConfig.model_validate({"path": "rel.csv", "basis": "number"})
    assert cfg.path == tmp_path.resolve() / "rel.csv"
    assert cfg.model_dump(mode="json")["path"] == str(tmp_path.resolve() / "rel.csv")


@pytest.mark.parametrize(
    ("content", "problem"),
    [
        ("size,pct\n1,0\n", "needs at least 2 rows"),
        ("", "needs at least 2 rows"),
        ("1,0\n2,50\n2,100\n", r"line 3: sieve size 2 is not greater than 2 on line 2"),
        ("2,0\n1,100\n", r"line 2: .*sizes must increase"),
        ("1,0\n2,60\n3,50\n", r"line 3: percent passing 50 is less than 60"),
        ("1,0\n2,101\n", r"line 2: percent passing 101 is outside 0–100"),
        ("1,-1\n2,50\n", r"line 1: percent passing -1 is outside 0–100"),
        ("1,0\n2,abc\n", r"line 2: 'abc' is not a number"),
        ("1,0\n2,50,7\n", r"line 2: expected 2 columns"),
        ("0,0\n2,100\n", r"line 1: sieve size 0 must be > 0"),
        ("1,0\nnan,100\n", r"line 2: 'nan' is not a finite number"),
        ("1,50\n2,50\n", "does not rise"),
    ],
)
def test_bad_tables_give_one_line_errors(tmp_path: Path, content: str, problem: str) -> None:
    path = tmp_path / "bad.csv"
    path.write_text(content, encoding="utf-8")
    with pytest.raises(ValueError, match=problem) as info:
        read_sieve_table(path)
    message = str(info.value)
    assert "\n" not in message and message.startswith(str(path))
    with pytest.raises(ValidationError, match=problem):
        TabulatedConfig(path=path, basis="mass")


def test_missing_and_unreadable_tables(tmp_path: Path) -> None:
    with pytest.raises(ValueError, match=r"nope\.csv: no such file"):
        read_sieve_table(tmp_path / "nope.csv")
    with pytest.raises(ValueError, match="is a directory"):
        read_sieve_table(tmp_path)
    (tmp_path / "bin.csv").write_bytes(b"\xff\xfe\x00\x81")
    with pytest.raises(ValueError, match="not a UTF-8 text file"):
        read_sieve_table(tmp_path / "bin.csv")
    with pytest.raises(ValidationError, match=r"path"):
        TabulatedConfig(path=tmp_path / "nope.csv", basis="number")


def test_tabulated_needs_a_basis_and_a_sane_exponent(tmp_path: Path) -> None:
    table = write_table(tmp_path / "t.csv", SIEVES, PASSING)
    with pytest.raises(ValidationError, match="basis"):
        TabulatedConfig.model_validate({"path": str(table)})
    with pytest.raises(ValidationError, match="basis"):
        TabulatedConfig.model_validate({"path": str(table), "basis": "volume"})
    with pytest.raises(ValidationError, match="mass_exponent"):
        TabulatedConfig.model_validate({"path": str(table), "basis": "mass", "mass_exponent": -1})


def test_table_removed_after_validation_is_a_config_error(tmp_path: Path) -> None:
    table = write_table(tmp_path / "t.csv", SIEVES, PASSING)
    cfg = TabulatedConfig(path=table, basis="number")
    table.unlink()
    with pytest.raises(ConfigError, match="no such file"):
        Tabulated(cfg)


# ---------------------------------------------------------------------------
# registration, scenes and packing


def test_registered_kinds_build_from_params(tmp_path: Path) -> None:
    registry = default_registry(autoload=False)
    assert set(KINDS) <= set(registry.names("size"))
    table = write_table(tmp_path / "t.csv", SIEVES, PASSING)
    params: dict[str, dict[str, Any]] = {
        "lognormal": {"median": 5.0, "sigma": 0.4, "d_max": 20.0},
        "rosin-rammler": {"d63": 5.0, "n": 3.0},
        "uniform": {"d_min": 1.0, "d_max": 2.0},
        "monodisperse": {"d": 3.0},
        "tabulated": {"path": str(table), "basis": "mass"},
    }
    for kind in KINDS:
        spec = registry.get("size", kind)
        assert spec.description
        dist = spec.build(params[kind])
        assert dist.mean_area > 0 and 0 < dist.r_min <= dist.r_max


def test_scene_errors_are_one_line(tmp_path: Path) -> None:
    from regopack.scenes.model import load_scene, resolve_scene

    bad = tmp_path / "bad.csv"
    bad.write_text("1,0\n2,150\n", encoding="utf-8")
    scene = load_scene("small", [f'size={{kind="tabulated", path="{bad}", basis="mass"}}'])
    with pytest.raises(ConfigError) as info:
        resolve_scene(scene, default_registry(autoload=False))
    message = str(info.value)
    assert "\n" not in message and "size.path" in message and "line 2" in message


@pytest.mark.parametrize("size", ['{kind="uniform", d_min=4.0, d_max=8.0}', "tabulated"])
def test_end_to_end_packing_without_overlap(size: str, tmp_path: Path) -> None:
    pytest.importorskip("regopack.plugins.inserters.available_arc")
    from regopack.run.pipeline import run_scene
    from regopack.scenes.model import load_scene, resolve_scene
    from regopack.testing import assert_valid_packing

    if size == "tabulated":
        table = write_table(tmp_path / "sieve.csv", [3.0, 5.0, 8.0], [0.0, 40.0, 100.0])
        size = f'{{kind="tabulated", path="{table}", basis="mass"}}'
    scene = load_scene("small", ["count=200", f"size={size}"])
    resolved = resolve_scene(scene, default_registry(autoload=False))
    outcome = run_scene(resolved, None)
    assert outcome.packing.n_particles == 200
    assert_valid_packing(outcome.packing)
    diameters = 2 * outcome.packing.radius
    assert diameters.min() >= 3.0 and diameters.max() <= 8.0


DOCS_PAGE = Path(__file__).resolve().parents[3] / "docs" / "reference" / "size-distributions.md"


def test_docs_examples_are_valid_scenes(tmp_path: Path, monkeypatch: pytest.MonkeyPatch) -> None:
    import re
    import tomllib

    text = DOCS_PAGE.read_text(encoding="utf-8")
    csv = re.search(r"```text\n(.*?)```", text, re.S)
    assert csv is not None
    (tmp_path / "sieve.csv").write_text(csv.group(1), encoding="utf-8")
    monkeypatch.chdir(tmp_path)
    registry = default_registry(autoload=False)
    seen = set()
    for block in re.findall(r"```toml\n(.*?)```", text, re.S):
        params = tomllib.loads(block)["size"]
        kind = params.pop("kind")
        dist = registry.get("size", kind).build(params)
        assert dist.mean_area > 0
        seen.add(kind)
    assert seen == set(KINDS)


def test_docstring_examples() -> None:
    result = doctest.testmod(sd, optionflags=doctest.ELLIPSIS)
    assert result.attempted > 0 and result.failed == 0
