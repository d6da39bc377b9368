"""How numba runs regopack's parallel kernels: the threading layer and its threads.

Imported with the package root (it imports nothing heavy), so that its
settings reach numba before numba starts its threads, whoever's kernel runs
first. What it sets goes through environment variables, as numba reads
them; each one the user set already is kept:

- ``OMP_WAIT_POLICY=PASSIVE`` (:func:`configure_threads`);
- ``NUMBA_THREADING_LAYER_PRIORITY``: OpenMP, then numba's workqueue, then
  TBB (:func:`configure_threading_layer`);
- a child forked after the parent ran a GNU OpenMP kernel runs its kernels on
  one thread (:func:`_one_thread_after_fork`).
"""

from __future__ import annotations

import os
import sys

__all__ = ["THREADING_LAYERS", "configure", "configure_threading_layer", "configure_threads"]


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
"""numba's threading layers in regopack's order of preference (see
:func:`configure_threading_layer`)."""


def configure_threading_layer() -> None:
    """Prefer OpenMP, then numba's own workqueue, to TBB, unless the user chose a layer.

    numba takes TBB first when it finds it (``pip install tbb``, Debian's
    ``libtbb12``, which YADE brings, many conda environments). With TBB, a
    process that ran a parallel kernel from a thread other than the main one
    (a Dask worker thread, a thread pool) can spin for ever at exit, in TBB's
    blocking finalisation. regopack's one parallel kernel (the sweep's exact
    scans) runs from any thread but one at a time, so it needs no thread-safe
    layer: OpenMP (what numba takes without TBB) or else the workqueue serve
    it, and neither has that exit. The order goes to numba through
    ``NUMBA_THREADING_LAYER_PRIORITY`` (child processes inherit it); setting
    ``NUMBA_THREADING_LAYER`` or that variable yourself keeps your choice.
    Nothing changes once numba has started its threads.
    """
    if os.environ.get("NUMBA_THREADING_LAYER") or os.environ.get("NUMBA_THREADING_LAYER_PRIORITY"):
        return
    os.environ["NUMBA_THREADING_LAYER_PRIORITY"] = " ".join(THREADING_LAYERS)
    if "numba" in sys.modules:
        from numba.core import config

        # read when the first parallel kernel starts numba's threads
        config.THREADING_LAYER_PRIORITY = list(THREADING_LAYERS)  # type: ignore[attr-defined]


def _gnu_openmp_started() -> bool:
    """Whether this process started numba's threads on GNU OpenMP."""
    parallel = sys.modules.get("numba.np.ufunc.parallel")
    if parallel is None or not getattr(parallel, "_is_initialized", False):
        return False
    try:
        import importlib

        omppool = importlib.import_module("numba.np.ufunc.omppool")
        layer = parallel.threading_layer()
    except (ImportError, ValueError):
        return False
    return bool(layer == "omp" and getattr(omppool, "openmp_vendor", "") == "GNU")


def _one_thread_after_fork() -> None:
    """Keep a forked child's kernels on one thread when its parent used GNU OpenMP.

    GNU OpenMP cannot start a parallel region in a child forked after the
    parent ran one (numba ends such a child). The kernels give the same
    packings on one thread, so the child runs them there instead.
    """
    if _gnu_openmp_started():
        import numba

        numba.set_num_threads(1)


def configure() -> None:
    """Apply every setting of this module (once per process; called on import)."""
    configure_threads()
    configure_threading_layer()


configure()
if hasattr(os, "register_at_fork"):
    os.register_at_fork(after_in_child=_one_thread_after_fork)
