"""Borrowed arrays: same data, no memory record, refused for other counted objects."""

from __future__ import annotations

from typing import Any, NamedTuple

import numba
import numpy as np
import pytest
from numba.core import types
from numba.core.errors import TypingError
from numba.extending import intrinsic
from numba.np.arrayobj import make_array

from regopack.plugins.borrowed import borrowed


def _type_meminfo_is_null(typingctx: Any, a: types.Type) -> Any:
    """Whether array ``a`` has no memory record (a test-only probe)."""

    def codegen(context: Any, builder: Any, signature: Any, args: Any) -> Any:
        ary = make_array(a)(context, builder, value=args[0])  # type: ignore[no-untyped-call]
        return builder.icmp_unsigned("==", ary.meminfo, ary.meminfo.type(None))

    return types.boolean(a), codegen


_meminfo_is_null: Any = intrinsic(_type_meminfo_is_null)


class Pair(NamedTuple):
    x: np.ndarray
    n: np.ndarray


@numba.njit
def _probe_array(a: np.ndarray) -> tuple[bool, bool, float]:
    b = borrowed(a)
    b[1] = 7.0  # writes reach the caller's array
    return _meminfo_is_null(a), _meminfo_is_null(b), b.sum()


@numba.njit
def _probe_tuple(p: Pair, k: int) -> tuple[bool, bool, int, float]:
    q = borrowed(p)
    both = (q, k)
    r = borrowed(both)
    return (
        _meminfo_is_null(q.x) and _meminfo_is_null(q.n),
        _meminfo_is_null(r[0].x[1:]),  # a view of a borrowed array is borrowed too
        r[1],
        q.x[2] + q.n[0],
    )


@numba.njit
def _borrow_none(h: Any) -> bool:
    return borrowed(h) is None


def test_array_is_borrowed_with_the_same_data() -> None:
    a = np.arange(4.0)
    owned, borrowed_null, total = _probe_array(a)
    assert not owned
    assert borrowed_null
    assert total == 0.0 + 7.0 + 2.0 + 3.0
    assert a[1] == 7.0


def test_tuples_are_borrowed_item_by_item() -> None:
    p = Pair(np.array([1.0, 2.0, 3.0]), np.array([10, 20]))
    null, view_null, k, value = _probe_tuple(p, 5)
    assert null and view_null
    assert k == 5
    assert value == 13.0


def test_none_passes_through() -> None:
    assert _borrow_none(None)


def test_other_counted_objects_are_refused() -> None:
    @numba.njit
    def borrow_generator(rng: np.random.Generator) -> Any:
        return borrowed(rng)

    with pytest.raises(TypingError):
        borrow_generator(np.random.default_rng(1))
