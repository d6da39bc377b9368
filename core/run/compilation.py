"""How long compiling the kernels took.

regopack's kernels are compiled by numba on first use and cached on disk
(see :mod:`regopack.base.jit`). :func:`compile_timer` measures the compilation that
happens inside a block, from numba's own compile events, so that a run can
report its insertion time without it. Compiling every kernel ahead of time is
:func:`regopack.api.warmup.compile_kernels`.
"""

from __future__ import annotations

import threading
import time
from collections.abc import Iterator
from contextlib import contextmanager
from dataclasses import dataclass, field
from typing import Any

__all__ = ["CompileTime", "compile_timer"]


@dataclass
class CompileTime:
    """Seconds spent compiling inside a :func:`compile_timer` block.

    Another thread (a helper of the insertion) may compile while the thread that
    opened the block goes on working, so the two are told apart.

    Attributes
    ----------
    seconds
        Wall time during which any thread compiled (nested compilations counted once).
    functions
        Number of compilations (each kernel signature compiled, nested ones included).
    own_seconds
        Wall time during which the thread that opened the block compiled; the rest
        of that thread's time is its own work, including waits for the compiler
        while another thread holds it.
    """

    seconds: float = 0.0
    functions: int = 0
    own_seconds: float = 0.0
    _owner: int = field(default_factory=threading.get_ident, repr=False, compare=False)
    _depth: dict[int, int] = field(default_factory=dict, repr=False, compare=False)
    _start: dict[int, float] = field(default_factory=dict, repr=False, compare=False)
    _busy: int = field(default=0, repr=False, compare=False)
    _since: float = field(default=0.0, repr=False, compare=False)
    _lock: threading.Lock = field(default_factory=threading.Lock, repr=False, compare=False)

    @property
    def elsewhere(self) -> bool:
        """Whether some compilation ran on another thread than the block's."""
        return self.seconds > self.own_seconds

    def run_times(self, wall: float) -> dict[str, Any]:
        """Return a run summary's timing fields for a block of ``wall`` seconds so far.

        The insertion time leaves out only the opening thread's compilations (a helper
        compiling meanwhile does not stop it); a note says when another thread compiled.
        """
        times: dict[str, Any] = {
            "wall_time_s": wall,
            "insertion_time_s": max(wall - self.own_seconds, 0.0),
            "compile_time_s": self.seconds,
        }
        if self.elsewhere:
            times["insertion_time_note"] = (
                "another thread compiled kernels during the insertion, which may have waited"
                " for it or gone on without its help: time a second run for the usual figure"
            )
        return times

    def _event(self, event: Any) -> None:
        me = threading.get_ident()
        now = time.perf_counter()
        with self._lock:
            depth = self._depth.get(me, 0)
            if event.is_start:
                if depth == 0:
                    self._start[me] = now
                    if self._busy == 0:
                        self._since = now
                    self._busy += 1
                self._depth[me] = depth + 1
                self.functions += 1
            elif depth > 0:
                self._depth[me] = depth - 1
                if depth == 1:
                    if me == self._owner:
                        self.own_seconds += now - self._start[me]
                    self._busy -= 1
                    if self._busy == 0:
                        self.seconds += now - self._since


@contextmanager
def compile_timer() -> Iterator[CompileTime]:
    """Measure the kernel compilation inside the block.

    Loading a kernel from the cache is not compilation and costs a few
    milliseconds; only real compilations are counted.

    Examples
    --------
    >>> with compile_timer() as timer:
    ...     pass
    >>> timer.seconds, timer.functions
    (0.0, 0)
    """
    from numba.core import event

    timer = CompileTime()

    class _Listener(event.Listener):
        def on_start(self, ev: Any) -> None:
            timer._event(ev)

        def on_end(self, ev: Any) -> None:
            timer._event(ev)

    with event.install_listener("numba:compile", _Listener()):
        yield timer
