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

from regopack.plugins.common.borrowed import borrowed


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
    return (
        _meminfo_is_null(q.x) and _meminfo_is_null(q.n),
        _meminfo_is_null(q.x[1:]),  # a view of a borrowed array is borrowed too
        k,
        q.x[2] + q.n[0],
    )


@numba.njit
def _probe_nested(p: Pair, a: np.ndarray, k: int, flag: bool) -> tuple[bool, bool, int, bool]:
    r = borrowed(((p, k), flag, (None, a)))
    (q, k2), flag2, (_, b) = r
    return (
        _meminfo_is_null(q.x) and _meminfo_is_null(q.n),
        _meminfo_is_null(b) and not _meminfo_is_null(a),
        k2,
        flag2,
    )


@numba.njit
def _return_borrowed(a: np.ndarray) -> np.ndarray:
    return borrowed(a)


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


def test_nested_tuples_are_borrowed_through() -> None:
    p = Pair(np.array([1.0, 2.0, 3.0]), np.array([10, 20]))
    assert _probe_nested(p, np.zeros(3), 4, True) == (True, True, 4, True)


def test_a_whole_argument_returned_comes_back_as_itself() -> None:
    a = np.arange(3.0)
    assert _return_borrowed(a) is a


def test_none_passes_through() -> None:
    assert _borrow_none(None)


def test_other_counted_objects_are_refused() -> None:
    @numba.njit
    def borrow_generator(rng: np.random.Generator) -> Any:
        return borrowed(rng)

    @numba.njit
    def borrow_tuple_with_generator(a: np.ndarray, rng: np.random.Generator) -> Any:
        return borrowed((a, rng))

    with pytest.raises(TypingError):
        borrow_generator(np.random.default_rng(1))
    with pytest.raises(TypingError):
        borrow_tuple_with_generator(np.zeros(2), np.random.default_rng(1))
