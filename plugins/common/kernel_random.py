"""Uniform draws of a numpy ``Generator`` inside compiled kernels, without unboxing it per call.

numba accepts a :class:`numpy.random.Generator` as an argument, but every
call of a compiled function that takes one pays for finding its type and
unboxing it (reading its bit generator's ctypes interface): 15–30 µs, more
than a sphere's whole turn at a candidate. A kernel called once per particle
pays it hundreds of thousands of times.

:func:`kernel_source` returns, for a Generator whose bit generator is
:class:`numpy.random.PCG64`, a ``uint64`` array that *is* that bit
generator's state (a view on its memory, not a copy): the kernels step it
themselves with :func:`pcg64_double`, which reproduces ``Generator.random()``
bit for bit, so the Generator and the kernels draw one stream in one order
whoever draws. For any other bit generator, or a state laid out otherwise
than checked, it returns the Generator itself. :func:`uniform` draws from
either inside a kernel (numba compiles it for the type it is given).

The view holds the Generator (its memory lives as long as the view). Like
the Generator's own compiled use, it takes no lock: one thread draws.
"""

from __future__ import annotations

import ctypes
from typing import Any

import numba
import numpy as np
from numba import types
from numba.extending import overload
from numpy.typing import NDArray

__all__ = ["KernelSource", "kernel_source", "pcg64_double", "uniform"]

UInt64Array = NDArray[np.uint64]
KernelSource = np.random.Generator | UInt64Array
"""What a kernel draws from: a Generator, or the state words of its PCG64."""

_MULT_HI = np.uint64(0x2360ED051FC65DA4)
_MULT_LO = np.uint64(0x4385DF649FCCF645)
_LOW32 = np.uint64(0xFFFFFFFF)
_WORD = 1 << 64


def _pcg64_words(rng: np.random.Generator) -> UInt64Array | None:
    """Return the four state words of ``rng``'s PCG64 as ``[state_lo, state_hi, inc_lo, inc_hi]``.

    None when the bit generator is not PCG64 or its memory is not laid out
    as 128-bit little-endian integers (checked against its ``state``).
    """
    bit = rng.bit_generator
    if type(bit) is not np.random.PCG64:
        return None
    # the C state is {pcg64_random_t *pcg_state; int has_uint32; uint32_t uinteger}
    address = ctypes.c_void_p.from_address(bit.ctypes.state_address).value
    if not address:
        return None
    words = (ctypes.c_uint64 * 4).from_address(address)
    words.generator = rng  # type: ignore[attr-defined]  # the view's base holds it
    view: UInt64Array = np.ctypeslib.as_array(words)
    state = bit.state["state"]
    expected = [
        state["state"] % _WORD,
        state["state"] // _WORD,
        state["inc"] % _WORD,
        state["inc"] // _WORD,
    ]
    if [int(w) for w in view] != expected:
        return None
    return view


def kernel_source(rng: np.random.Generator) -> KernelSource:
    """Return what kernels draw ``rng``'s uniforms from: its PCG64 state words, or ``rng``.

    Examples
    --------
    >>> rng = np.random.default_rng(7)
    >>> src = kernel_source(rng)
    >>> src.dtype == np.uint64
    True
    >>> twin = np.random.default_rng(7)
    >>> pcg64_double(src) == twin.random()
    True
    >>> rng.random() == twin.random()  # one stream: the Generator goes on after the kernel
    True
    """
    words = _pcg64_words(rng)
    return rng if words is None else words


@numba.njit(cache=True, inline="always")
def _mulhi(a: np.uint64, b: np.uint64) -> np.uint64:
    """Return the high 64 bits of the 128-bit product ``a * b``."""
    s32 = np.uint64(32)
    a_lo = a & _LOW32
    a_hi = a >> s32
    b_lo = b & _LOW32
    b_hi = b >> s32
    t = a_lo * b_lo
    m1 = a_hi * b_lo + (t >> s32)
    m2 = a_lo * b_hi + (m1 & _LOW32)
    return a_hi * b_hi + (m1 >> s32) + (m2 >> s32)


@numba.njit(cache=True)
def pcg64_double(words: UInt64Array) -> float:
    """Step a PCG64 state (``[state_lo, state_hi, inc_lo, inc_hi]``) and return a double in [0, 1).

    The 128-bit linear congruential step and the XSL-RR output of numpy's
    PCG64, and ``Generator.random()``'s 53 high bits of the output.
    """
    lo = words[0]
    hi = words[1]
    p_lo = lo * _MULT_LO
    p_hi = _mulhi(lo, _MULT_LO) + hi * _MULT_LO + lo * _MULT_HI
    n_lo = p_lo + words[2]
    n_hi = p_hi + words[3]
    if n_lo < p_lo:
        n_hi += np.uint64(1)
    words[0] = n_lo
    words[1] = n_hi
    x = n_hi ^ n_lo
    rot = n_hi >> np.uint64(58)
    out = (x >> rot) | (x << ((np.uint64(64) - rot) & np.uint64(63)))
    return float(out >> np.uint64(11)) * (1.0 / 9007199254740992.0)


def uniform(source: Any) -> float:
    """Draw a uniform double in [0, 1) from a kernel source (compiled code only)."""
    raise NotImplementedError("uniform() is called from compiled kernels")


@overload(uniform)
def _uniform(source):  # type: ignore[no-untyped-def]  # numba matches the unannotated lambdas
    if isinstance(source, types.NumPyRandomGeneratorType):
        return lambda source: source.random()
    if isinstance(source, types.Array) and source.dtype == types.uint64 and source.ndim == 1:
        return lambda source: pcg64_double(source)
    return None
