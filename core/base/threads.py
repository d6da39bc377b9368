"""How numba runs regopack's parallel kernels: the threading layer and its threads.

Imported with the package root (it imports nothing heavy); a setting the
user made is kept:

- ``OMP_WAIT_POLICY=PASSIVE`` (:func:`configure_threads`);
- numba's order of threading layers: OpenMP, then its workqueue, then TBB,
  set in this process's numba configuration before numba starts its threads
  (:func:`prefer_layers`, :func:`kernel_threads`);
- a child forked after the parent ran a GNU OpenMP kernel runs its kernels on
  one thread (:func:`kernel_threads`).
"""

from __future__ import annotations

import os
import sys

__all__ = [
    "THREADING_LAYERS",
    "configure",
    "configure_threads",
    "kernel_threads",
    "prefer_layers",
]


def configure_threads() -> None:
    """Let the kernels' OpenMP threads sleep while they wait, unless the user chose.

    A thread that spins while it waits for a thread without a core (another
    process runs there) holds the core that thread needs: a parallel batch
    then waits a time slice, and the sweep's threaded exact scans ran 12 times
    slower than on one thread beside one busy process. Sleeping threads cost a
    few microseconds per batch instead. Read when OpenMP starts, that is at
    the first parallel kernel.
    """
    os.environ.setdefault("OMP_WAIT_POLICY", "PASSIVE")


THREADING_LAYERS: tuple[str, ...] = ("omp", "workqueue", "tbb")
"""numba's threading layers in regopack's order of preference (see :func:`prefer_layers`)."""

NUMBA_DEFAULT_ORDER: tuple[str, ...] = ("tbb", "omp", "workqueue")
"""numba's own order of preference, which :func:`prefer_layers` replaces."""

_ONE_THREAD = False
"""Set in a child forked after its parent started GNU OpenMP threads (:func:`kernel_threads`)."""

_PARENT_ON_GNU_OPENMP = False
"""Whether this process ran a GNU OpenMP kernel when it last forked (set just before the fork)."""


def prefer_layers() -> None:
    """Put TBB last in numba's order of threading layers, unless the user chose.

    numba takes TBB first when it finds it (``pip install tbb``, Debian's
    ``libtbb12``, which YADE brings, many conda environments). With TBB, a
    process that ran a parallel kernel from a thread other than the main one
    (a Dask worker thread, a thread pool) can spin for ever at exit, in TBB's
    blocking finalisation. regopack's one parallel kernel (the sweep's exact
    scans) runs from any thread but one at a time, so it needs no thread-safe
    layer: OpenMP (what numba takes without TBB) or else the workqueue serve
    it, and neither has that exit.

    Called just before numba starts its threads (:func:`kernel_threads`); the
    order is set in numba's configuration of this process only, never in the
    environment, so the programs this process starts keep numba's own. A
    choice of the user's is kept: ``NUMBA_THREADING_LAYER`` or
    ``NUMBA_THREADING_LAYER_PRIORITY`` in the environment or numba's
    configuration file, or ``numba.config`` set in code; so is a layer
    already running.
    """
    if os.environ.get("NUMBA_THREADING_LAYER") or os.environ.get("NUMBA_THREADING_LAYER_PRIORITY"):
        return
    from numba.core import config
    from numba.np.ufunc import parallel

    if getattr(parallel, "_is_initialized", False):
        return
    if str(config.THREADING_LAYER).lower() != "default":  # type: ignore[attr-defined]
        return
    if tuple(config.THREADING_LAYER_PRIORITY) != NUMBA_DEFAULT_ORDER:  # type: ignore[attr-defined]
        return
    config.THREADING_LAYER_PRIORITY = list(THREADING_LAYERS)  # type: ignore[attr-defined]


def kernel_threads() -> int:
    """Threads regopack's parallel kernels may use here; numba's threads start now.

    ``numba.get_num_threads()``, after :func:`prefer_layers`; 1 in a child
    forked after its parent ran a GNU OpenMP kernel, which cannot start
    OpenMP threads (numba would end it): its kernels give the same packings
    on one thread.
    """
    prefer_layers()
    if _ONE_THREAD:
        return 1
    import numba

    return int(numba.get_num_threads())


def _gnu_openmp_started() -> bool:
    """Whether this process started numba's threads on GNU OpenMP (takes no lock)."""
    parallel = sys.modules.get("numba.np.ufunc.parallel")
    if parallel is None or not getattr(parallel, "_is_initialized", False):
        return False
    omppool = sys.modules.get("numba.np.ufunc.omppool")
    if omppool is None or getattr(omppool, "openmp_vendor", "") != "GNU":
        return False
    return getattr(parallel, "_threading_layer", None) == "omp"


def _before_fork() -> None:
    global _PARENT_ON_GNU_OPENMP
    _PARENT_ON_GNU_OPENMP = _gnu_openmp_started()


def _after_fork_in_child() -> None:
    """Mark a child of a GNU OpenMP parent (a flag only: no lock is taken in a fork hook)."""
    global _ONE_THREAD
    _ONE_THREAD = _ONE_THREAD or _PARENT_ON_GNU_OPENMP


def configure() -> None:
    """Apply the settings read from the environment (once per process; called on import)."""
    configure_threads()


configure()
if hasattr(os, "register_at_fork"):
    os.register_at_fork(before=_before_fork, after_in_child=_after_fork_in_child)
