"""The module of the certified refusals keeps the names that moved out of it."""

from __future__ import annotations

import pytest

from regopack.plugins.inserters.available_arc import kernel, refusal


def test_the_screened_search_moved_to_the_kernel_and_its_old_name_warns() -> None:
    with pytest.warns(DeprecationWarning, match=r"refusal\.place_screened is deprecated.*kernel"):
        old = refusal.place_screened
    assert old is kernel.place_screened
    with pytest.raises(AttributeError):
        _ = refusal.no_such_name
