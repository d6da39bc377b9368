"""Packing control coefficient eta."""

from __future__ import annotations

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from regopack.plugins.density.eta import EtaConfig, EtaController


def test_zero_is_identity_and_draws_nothing() -> None:
    ctl = EtaController(EtaConfig(eta=0.0))
    rng = np.random.default_rng(0)
    arcs = np.array([[0.0, 1.0], [2.0, 2.5]])
    assert ctl.identity
    assert ctl.shrink(arcs, 1.0, 2.0, rng) is arcs
    assert rng.random() == np.random.default_rng(0).random()


def test_shrink_formula() -> None:
    ctl = EtaController(EtaConfig(eta=10.0))
    arcs = np.array([[0.0, 3.0]])
    xi = np.random.default_rng(4).random(1)
    out = ctl.shrink(arcs, 1.0, 3.0, np.random.default_rng(4))
    delta = (10.0 + xi[0] - 1.0) / 100.0 * (2.0 * 1.0 / (3.0 + 1.0))
    assert out[0, 0] == pytest.approx(delta) and out[0, 1] == pytest.approx(3.0 - delta)


@given(
    eta=st.floats(0.0, 1000.0),
    lo=st.floats(-10, 10),
    length=st.floats(1e-9, 7),
    r_new=st.floats(1e-6, 1e6),
    ratio=st.floats(1e-4, 1e4),
)
@settings(max_examples=200, deadline=None)
def test_never_lengthens_an_arc(
    eta: float, lo: float, length: float, r_new: float, ratio: float
) -> None:
    ctl = EtaController(EtaConfig(eta=eta))
    arcs = np.array([[lo, lo + length]])
    out = ctl.shrink(arcs, r_new, r_new * ratio, np.random.default_rng(0))
    assert out.shape[0] <= 1
    if out.shape[0]:
        assert out[0, 0] >= arcs[0, 0] and out[0, 1] <= arcs[0, 1] and out[0, 1] > out[0, 0]


def test_large_eta_drops_short_arcs() -> None:
    ctl = EtaController(EtaConfig(eta=50.0))
    arcs = np.array([[0.0, 0.1], [1.0, 6.0]])
    out = ctl.shrink(arcs, 1.0, 1.0, np.random.default_rng(0))
    assert out.shape == (1, 2)


def test_bad_eta_names_field() -> None:
    with pytest.raises(ValueError, match="eta"):
        EtaConfig(eta=-1.0)
