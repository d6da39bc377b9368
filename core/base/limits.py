"""Bounds on the sizes a scene implies, checked before anything is allocated.

A scene sets lengths and counts; the packing derives further sizes from
them: cells of a neighbour grid, bins of a sweep's zone or of a histogram,
runs of a sweep, bytes of memory. A user-set value that is valid on its own
can imply a derived size that overflows 64-bit integers, is not a number, or
asks for more memory than the machine has, and a compiled kernel given such
a size indexes out of bounds. Every derived size therefore passes
:func:`derived_count` (or :func:`check_memory`) before it is allocated or
handed to a kernel; a size beyond the bound raises :class:`LimitError`,
which names the scene field it comes from and that field's value, so that
the run can prefix the source of that value (the scene file or ``--set``).

Bounds are counts (cells, bins, particles, bytes) or ratios of lengths,
never absolute lengths: a scene scaled by any factor is accepted or refused
alike.
"""

from __future__ import annotations

import math
import os
from pathlib import Path

from regopack.base.field_error import FieldValueError

__all__ = [
    "BIN_BYTES",
    "MAX_EXTENT_RATIO",
    "MAX_HISTOGRAM_BINS",
    "LimitError",
    "check_memory",
    "derived_count",
    "format_bytes",
    "histogram_bins",
    "memory_limit",
    "zone_bins",
]

MAX_EXTENT_RATIO = 1e8
"""Largest extent of a domain along one axis over the smallest particle diameter.

Beyond it, 64-bit coordinates across the domain no longer resolve the
smallest particle finely (their spacing grows to ``1e-8`` of its diameter),
and a neighbour grid or a sweep's bins over that axis grow without bound.
"""


MAX_HISTOGRAM_BINS = 1 << 16
"""Most bins an analyzer's histogram may have over its range (range / bin width).

Six hundred times the defaults' hundred-odd bins: finer than any curve a
packing of a million particles fills, and small enough that the curves of
every pair of minerals, and a polygon window's covariogram at every bin,
stay cheap. A bin width of ``1e-9`` over ``r`` in ``[0, 10]`` asked for
``10**10`` bins (74 GiB).
"""


BIN_BYTES = 64
"""Memory a histogram needs per bin and per pair of kinds (minerals), in bytes.

The pair counts, their edge-corrected and normalised curves, the merged and
the fine curve of every pair: about six 8-byte values, rounded up.
"""


class LimitError(FieldValueError):
    """A size derived from a scene is beyond what can be allocated or computed.

    ``field`` is the dotted scene field the size derives from (e.g.
    ``insertion.zone``), ``value`` that field's value (``None`` for a table),
    ``text`` what the value implies and what is allowed (see
    :class:`~regopack.base.field_error.FieldValueError`).
    """


def derived_count(
    value: float, what: str, most: int, *, field: str, given: object = None, hint: str = ""
) -> int:
    """Return a count derived from the scene as an ``int``, or refuse it.

    Parameters
    ----------
    value
        The count as computed (a float: it may be infinite or NaN).
    what
        What is counted, for the message (e.g. ``"bins of the sweep's zone"``).
    most
        The largest count allowed.
    field, given
        The scene field the count derives from and its value (see :class:`LimitError`).
    hint
        What to change, appended to the message.

    Raises
    ------
    LimitError
        When ``value`` is not finite, negative, or larger than ``most``.

    Examples
    --------
    >>> derived_count(12.0, "cells", 100, field="domain")
    12
    >>> derived_count(1e300, "bins", 1 << 20, field="insertion.zone", given=1e300)
    Traceback (most recent call last):
    ...
    regopack.base.limits.LimitError: insertion.zone = 1e+300: gives 1e+300 bins; at most 1,048,576
    """
    if not (math.isfinite(value) and 0 <= value <= most):
        shown = f"{value:.3g}" if math.isfinite(value) else "no finite number of"
        text = f"gives {shown} {what}; at most {most:,}"
        raise LimitError(field, given, f"{text}{'; ' + hint if hint else ''}")
    return int(value)


def memory_limit() -> tuple[int, str] | None:
    """Return the memory this process may use, in bytes, and what sets that limit.

    The smallest of the machine's physical memory, the memory available now
    (``MemAvailable`` of ``/proc/meminfo``: free memory and caches that can be
    dropped), the control group's limit (``memory.max``, in containers and
    batch jobs) and the address-space limit (``ulimit -v``); ``None`` where
    none of them is known.
    """
    limits: list[tuple[int, str]] = []
    try:
        for line in Path("/proc/meminfo").read_text(encoding="ascii").splitlines():
            name, _, rest = line.partition(":")
            if name == "MemAvailable" and rest.split()[0].isdigit():
                limits.append((int(rest.split()[0]) * 1024, "free memory (MemAvailable)"))
    except (OSError, UnicodeDecodeError, IndexError):
        pass
    try:
        limits.append((os.sysconf("SC_PAGE_SIZE") * os.sysconf("SC_PHYS_PAGES"), "memory"))
    except (AttributeError, OSError, ValueError):
        pass
    try:
        text = Path("/sys/fs/cgroup/memory.max").read_text(encoding="ascii").strip()
        if text.isdigit():
            limits.append((int(text), "memory limit (cgroup memory.max)"))
    except (OSError, UnicodeDecodeError):
        pass
    try:
        import resource

        soft = resource.getrlimit(resource.RLIMIT_AS)[0]
        if soft != resource.RLIM_INFINITY and soft > 0:
            limits.append((int(soft), "address-space limit (ulimit -v)"))
    except (ImportError, OSError, ValueError):
        pass
    return min(limits) if limits else None


def format_bytes(n: float) -> str:
    """``n`` bytes in binary units, e.g. ``7.3 TiB``.

    Examples
    --------
    >>> format_bytes(512), format_bytes(3 * 1024**3)
    ('512 B', '3.0 GiB')
    """
    for unit in ("B", "KiB", "MiB", "GiB", "TiB", "PiB", "EiB"):
        if unit == "EiB" and n >= 1e6:
            return f"{n:.3g} {unit}"
        if n < 1024 or unit == "EiB":
            return f"{n:,.0f} {unit}" if unit == "B" else f"{n:,.1f} {unit}"
        n /= 1024
    raise AssertionError("unreachable")


def check_memory(
    needed: float,
    what: str,
    *,
    field: str,
    given: object = None,
    limit: tuple[int, str] | None = None,
) -> None:
    """Refuse an allocation of ``needed`` bytes larger than the memory this process may use.

    Parameters
    ----------
    needed
        Bytes the work implies (an estimate).
    what
        What needs them, for the message (e.g. ``"50,000,000 particles (...)"``).
    field, given
        The scene field and its value (see :class:`LimitError`).
    limit
        The memory limit and what sets it; default :func:`memory_limit`.

    Raises
    ------
    LimitError
        When ``needed`` is not finite or exceeds the limit.
    """
    limit = limit if limit is not None else memory_limit()
    if limit is None:
        return
    if math.isfinite(needed) and needed <= limit[0]:
        return
    need = format_bytes(needed) if math.isfinite(needed) else "more than any"
    raise LimitError(
        field,
        given,
        f"{what} need about {need} of memory; this machine's {limit[1]} is "
        f"{format_bytes(limit[0])}",
    )


def histogram_bins(lo: float, hi: float, width: float, *, field: str, range_name: str) -> int:
    """Return the number of bins of ``width`` over ``[lo, hi)``, or refuse it.

    The count is ``(hi - lo) / width``, a ratio of lengths, bounded by
    :data:`MAX_HISTOGRAM_BINS`; a ``width`` wider than the range gives one bin.

    Parameters
    ----------
    lo, hi
        The range of the histogram.
    width
        The bin width.
    field, range_name
        The field holding ``width`` and the one holding the range (for the message).

    Raises
    ------
    LimitError
        When the width is not a finite positive number or gives more bins than allowed.

    Examples
    --------
    >>> histogram_bins(0.0, 10.0, 0.1, field="near_bin", range_name="near")
    100
    >>> histogram_bins(0.0, 10.0, 1e-9, field="near_bin", range_name="near")
    Traceback (most recent call last):
    ...
    regopack.base.limits.LimitError: near_bin = 1e-09: gives 1e+10 bins over near = [0, 10]; at most 65,536; give a bin width of at least 0.000152588 (the range / 65,536) or a shorter range
    """  # noqa: E501
    if not (math.isfinite(width) and width > 0):
        raise LimitError(field, width, "must be a finite number > 0")
    span = hi - lo
    with_range = f"bins over {range_name} = [{lo:g}, {hi:g}]"
    least = span / MAX_HISTOGRAM_BINS
    hint = (
        f"give a bin width of at least {least:.6g} (the range / {MAX_HISTOGRAM_BINS:,}) "
        "or a shorter range"
        if math.isfinite(least)
        else "give a finite range"
    )
    count = derived_count(
        span / width, with_range, MAX_HISTOGRAM_BINS, field=field, given=width, hint=hint
    )
    return max(1, count)


MAX_ZONE_BINS = 1 << 20
"""Most bins of a sweep's zone over the domain's height (both sweeps, 2D and 3D)."""


def zone_bins(zone: float, delta: float, height: float, per_zone: int) -> int:
    """Bins of ``delta`` in a sweep's zone of height ``zone``: at most :data:`MAX_ZONE_BINS`.

    ``per_zone`` is the sweep's bins per zone height (for the message).

    Raises
    ------
    LimitError
        When the zone is more than :data:`MAX_ZONE_BINS` bins high (a zone of
        more than ``MAX_ZONE_BINS / per_zone`` times the domain's height).
    """
    derived_count(
        zone / delta,
        "bins of the sweep's zone",
        MAX_ZONE_BINS,
        field="insertion.zone",
        given=zone,
        hint=(
            f"a zone of at most {MAX_ZONE_BINS // per_zone:,} times the domain's height "
            f"({height:g})"
        ),
    )
    return round(zone / delta)
