"""Atomic operations on ``int64`` array elements, for kernels that share memory across threads.

Two compiled loops on two threads (see
:mod:`~regopack.plugins.inserters.available_arc.partner`) hand work to each other
through small ``int64`` arrays. A plain load in a waiting loop may be hoisted
out of it by the compiler, and plain stores may become visible out of order;
these intrinsics give the element accesses the ordering the hand-off needs:
a store with release order publishes every write before it, a load with
acquire order sees them. Compiled code only.
"""

from __future__ import annotations

import platform
from typing import Any

from llvmlite import ir
from numba.core import cgutils, types
from numba.extending import intrinsic
from numba.np.arrayobj import make_array

_PAUSE = platform.machine().lower() in ("x86_64", "amd64", "i386", "i686")
"""Whether the processor has the ``pause`` spin-wait hint (x86); elsewhere the hint is a no-op."""


def _element(context: Any, builder: ir.IRBuilder, signature: Any, args: Any) -> ir.Value:
    """Pointer to element ``args[1]`` of the one-dimensional array ``args[0]``."""
    aryty = signature.args[0]
    ary = make_array(aryty)(context, builder, value=args[0])
    index = context.cast(builder, args[1], signature.args[1], types.intp)
    return cgutils.get_item_pointer(context, builder, aryty, ary, [index], wraparound=False)


def _int64_vector(a: types.Type, i: types.Type) -> bool:
    """Whether ``a`` is a one-dimensional ``int64`` array and ``i`` an integer."""
    return (
        isinstance(a, types.Array)
        and a.ndim == 1
        and a.dtype == types.int64
        and isinstance(i, types.Integer)
    )


def _type_load_acquire(typingctx: Any, a: types.Type, i: types.Type) -> Any:
    if not _int64_vector(a, i):
        return None

    def codegen(context: Any, builder: ir.IRBuilder, signature: Any, args: Any) -> ir.Value:
        return builder.load_atomic(_element(context, builder, signature, args), "acquire", 8)

    return types.int64(a, i), codegen


def _type_store_release(typingctx: Any, a: types.Type, i: types.Type, v: types.Type) -> Any:
    if not _int64_vector(a, i) or not isinstance(v, types.Integer):
        return None

    def codegen(context: Any, builder: ir.IRBuilder, signature: Any, args: Any) -> ir.Value:
        value = context.cast(builder, args[2], signature.args[2], types.int64)
        builder.store_atomic(value, _element(context, builder, signature, args), "release", 8)
        return context.get_dummy_value()

    return types.void(a, i, v), codegen


def _type_compare_swap(
    typingctx: Any, a: types.Type, i: types.Type, old: types.Type, new: types.Type
) -> Any:
    if not _int64_vector(a, i) or not isinstance(old, types.Integer):
        return None
    if not isinstance(new, types.Integer):
        return None

    def codegen(context: Any, builder: ir.IRBuilder, signature: Any, args: Any) -> ir.Value:
        expect = context.cast(builder, args[2], signature.args[2], types.int64)
        value = context.cast(builder, args[3], signature.args[3], types.int64)
        pair = builder.cmpxchg(
            _element(context, builder, signature, args), expect, value, "acq_rel", "acquire"
        )
        return builder.extract_value(pair, 1)

    return types.boolean(a, i, old, new), codegen


def _type_spin_hint(typingctx: Any) -> Any:
    def codegen(context: Any, builder: ir.IRBuilder, signature: Any, args: Any) -> ir.Value:
        if _PAUSE:
            fnty = ir.FunctionType(ir.VoidType(), [])
            pause = cgutils.get_or_insert_function(builder.module, fnty, "llvm.x86.sse2.pause")
            builder.call(pause, [])
        return context.get_dummy_value()

    return types.void(), codegen


def _type_yield_processor(typingctx: Any) -> Any:
    def codegen(context: Any, builder: ir.IRBuilder, signature: Any, args: Any) -> ir.Value:
        fnty = ir.FunctionType(ir.IntType(32), [])
        builder.call(cgutils.get_or_insert_function(builder.module, fnty, "sched_yield"), [])
        return context.get_dummy_value()

    return types.void(), codegen


def _type_sleep_us(typingctx: Any, us: types.Type) -> Any:
    if not isinstance(us, types.Integer):
        return None

    def codegen(context: Any, builder: ir.IRBuilder, signature: Any, args: Any) -> ir.Value:
        fnty = ir.FunctionType(ir.IntType(32), [ir.IntType(32)])
        value = context.cast(builder, args[0], signature.args[0], types.uint32)
        builder.call(cgutils.get_or_insert_function(builder.module, fnty, "usleep"), [value])
        return context.get_dummy_value()

    return types.void(us), codegen


load_acquire: Any = intrinsic(_type_load_acquire)
"""``load_acquire(a, i)``: ``a[i]`` read with acquire order (``a`` a 1-D ``int64`` array)."""
store_release: Any = intrinsic(_type_store_release)
"""``store_release(a, i, v)``: ``a[i] = v`` written with release order."""
compare_swap: Any = intrinsic(_type_compare_swap)
"""``compare_swap(a, i, old, new)``: set ``a[i] = new`` if it holds ``old``, atomically;
returns whether it did."""
spin_hint: Any = intrinsic(_type_spin_hint)
"""``spin_hint()``: tell the processor that this is a waiting loop (``pause`` on x86)."""
yield_processor: Any = intrinsic(_type_yield_processor)
"""``yield_processor()``: give the processor to another runnable thread (POSIX
``sched_yield``)."""
sleep_us: Any = intrinsic(_type_sleep_us)
"""``sleep_us(n)``: sleep about ``n`` microseconds (POSIX ``usleep``)."""
