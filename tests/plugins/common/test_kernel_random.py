"""The kernels' uniform draws: one stream with the Generator, bit for bit."""

from __future__ import annotations

import numba
import numpy as np
import pytest

from regopack.plugins.common.kernel_random import kernel_source, pcg64_double, uniform


@numba.njit  # not cached: a cached copy would not see a changed kernel_random
def _draws(source, n):  # type: ignore[no-untyped-def]
    out = np.empty(n)
    for j in range(n):
        out[j] = uniform(source)
    return out


@pytest.mark.parametrize("seed", [0, 1, 12345, 2**63 + 17, [3, 1, 4, 1, 5]])
def test_pcg64_source_draws_the_generators_stream(seed: object) -> None:
    rng = np.random.default_rng(seed)  # type: ignore[arg-type]
    twin = np.random.default_rng(seed)  # type: ignore[arg-type]
    source = kernel_source(rng)
    assert isinstance(source, np.ndarray) and source.dtype == np.uint64
    # kernel, Generator, kernel again: one stream in one order, whoever draws
    assert np.array_equal(_draws(source, 2000), twin.random(2000))
    assert np.array_equal(rng.random(7), twin.random(7))
    assert np.array_equal(_draws(source, 5), twin.random(5))
    assert rng.bit_generator.state == twin.bit_generator.state


def test_source_follows_a_state_set_from_outside() -> None:
    rng = np.random.default_rng(5)
    source = kernel_source(rng)
    rng.bit_generator.state = np.random.default_rng(99).bit_generator.state
    assert np.array_equal(_draws(source, 3), np.random.default_rng(99).random(3))
    jumped = np.random.Generator(np.random.PCG64(8).jumped(3))
    twin = np.random.Generator(np.random.PCG64(8).jumped(3))
    assert np.array_equal(_draws(kernel_source(jumped), 4), twin.random(4))


@pytest.mark.parametrize(
    "bit", [np.random.Philox, np.random.SFC64, np.random.MT19937, np.random.PCG64DXSM]
)
def test_other_bit_generators_are_drawn_through_the_generator(bit: type) -> None:
    rng = np.random.Generator(bit(11))
    source = kernel_source(rng)
    assert source is rng
    assert np.array_equal(_draws(source, 50), np.random.Generator(bit(11)).random(50))


def test_pcg64_double_is_the_53_high_bits_of_the_xsl_rr_output() -> None:
    # an independent model in Python integers: state = state * M + inc, then XSL-RR
    rng = np.random.default_rng(2026)
    state = rng.bit_generator.state["state"]
    s, inc = state["state"], state["inc"]
    mult = 0x2360ED051FC65DA44385DF649FCCF645
    word = (1 << 64) - 1
    words = np.array([s & word, s >> 64, inc & word, inc >> 64], dtype=np.uint64)
    for _ in range(200):
        s = (s * mult + inc) & ((1 << 128) - 1)
        hi, lo = s >> 64, s & word
        x, rot = hi ^ lo, hi >> 58
        out = ((x >> rot) | (x << ((64 - rot) & 63))) & word
        assert pcg64_double(words) == (out >> 11) * 2.0**-53
    assert int(words[0]) == s & word and int(words[1]) == s >> 64


def test_the_view_holds_its_generator() -> None:
    import gc

    source = kernel_source(np.random.default_rng(7))  # the Generator itself is dropped here
    gc.collect()
    others = [np.random.PCG64(k) for k in range(200)]  # would take its memory if it were freed
    states = [bit.state for bit in others]
    assert np.array_equal(_draws(source, 10), np.random.default_rng(7).random(10))
    assert [bit.state for bit in others] == states
