"""Borrowed arrays: the packing state without reference counts inside the kernels.

A compiled function counts up every array it receives when it starts and
counts it down when it returns, each an atomic operation on the array's
memory record. The kernels pass the packing state as named tuples of some
fifty arrays through calls made once per candidate analysis, so these counts
took a quarter to a third of the insertion time.

:func:`borrowed` returns the same arrays (or tuples of them) with no memory
record: the counts become a test of a null pointer. It is applied where a
kernel is entered from Python, whose arguments keep the memory alive until
the kernel returns. A borrowed array must not outlive that call: a kernel
never returns one to Python and never stores one beyond the call. (Each keeps
its link to the Python array it came from, so a whole argument returned by
mistake comes back as that array; a view of it would come back as an array
over memory that Python may free.)
"""

from __future__ import annotations

from typing import Any, cast

from llvmlite import ir
from numba.core import cgutils, types
from numba.extending import intrinsic
from numba.np.arrayobj import make_array


def _borrow_value(context: Any, builder: ir.IRBuilder, ty: types.Type, value: ir.Value) -> ir.Value:
    """``value`` of type ``ty`` with the memory records of its arrays set to null."""
    if isinstance(ty, types.Array):
        ary = make_array(ty)(context, builder, value=value)
        ary.meminfo = cgutils.get_null_value(ary.meminfo.type)
        return ary._getvalue()
    if isinstance(ty, types.BaseTuple):
        out = value
        for index, item in enumerate(_items(ty)):
            if _has_arrays(item):
                field = builder.extract_value(value, index)
                out = builder.insert_value(out, _borrow_value(context, builder, item, field), index)
        return out
    return value


def _items(ty: types.BaseTuple) -> tuple[types.Type, ...]:
    """Item types of a tuple type."""
    return tuple(cast(Any, ty).types)


def _has_arrays(ty: types.Type) -> bool:
    """Whether ``ty`` is an array or a tuple holding one."""
    if isinstance(ty, types.Array):
        return True
    if isinstance(ty, types.BaseTuple):
        return any(_has_arrays(item) for item in _items(ty))
    return False


def _supported(ty: types.Type) -> bool:
    """Whether ``ty`` holds arrays, numbers and ``None`` only (no other counted object)."""
    if isinstance(ty, types.BaseTuple):
        return all(_supported(item) for item in _items(ty))
    return isinstance(ty, (types.Array, types.Number, types.Boolean, types.NoneType))


def _type_borrowed(typingctx: Any, x: types.Type) -> Any:
    """Type ``borrowed(x)``: ``x`` with its arrays borrowed, for arrays and tuples of them.

    Tuples may hold arrays, numbers, booleans, ``None`` and such tuples; the
    result has the type of ``x``. Anything else that numba counts (a
    generator, a list) is refused when the caller compiles.
    """
    if not _supported(x):
        return None

    def codegen(context: Any, builder: ir.IRBuilder, signature: Any, args: Any) -> ir.Value:
        return _borrow_value(context, builder, x, args[0])

    return x(x), codegen


borrowed: Any = intrinsic(_type_borrowed)
"""``borrowed(x)``: ``x`` (an array, ``None``, or a tuple of arrays, numbers, booleans,
``None`` and such tuples) with its arrays borrowed. Compiled code only."""
