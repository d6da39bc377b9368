"""Worker processes that end with their parent: start-up, and stopping them.

Local workers (a sweep's runs, a tiled packing's tiles) ignore Ctrl-C (the
process that started them stops them), end the moment that process ends,
and run their compiled kernels on their share of the cores.
"""

from __future__ import annotations

import ctypes
import os
import signal
import sys
import threading
import time
from concurrent.futures import ProcessPoolExecutor

from regopack.base.threads import kernel_threads

__all__ = [
    "PARENT_POLL_S",
    "init_worker",
    "stop_workers",
    "threads_per_worker",
]


def threads_per_worker(workers: int, cores: int | None) -> int:
    """Compiled-kernel threads for each of ``workers`` processes sharing ``cores`` cores.

    A thread that waits for a core makes the whole batch it belongs to wait, so
    the workers share the cores instead of each starting one thread per core.
    """
    return max(1, (cores or 1) // max(1, workers))


def init_worker(workers: int = 1, threads: int | None = None) -> None:
    """Start a worker process: Ctrl-C goes to the main process, which stops the workers.

    SIGTERM keeps its default action (the process ends at once); the main
    process removes what a stopped worker left. The worker's compiled kernels
    use ``threads`` threads, or its share of the cores (:func:`threads_per_worker`).
    """
    import numba

    share = threads if threads is not None else threads_per_worker(workers, os.cpu_count())
    numba.set_num_threads(max(1, min(kernel_threads(), share)))
    signal.signal(signal.SIGINT, signal.SIG_IGN)
    signal.signal(signal.SIGTERM, signal.SIG_DFL)
    parent = os.getppid()
    _killed_with_parent(parent)
    threading.Thread(target=_exit_with_parent, args=(parent,), daemon=True).start()


PR_SET_PDEATHSIG = 1
"""Linux ``prctl`` option: the signal a process gets when its parent ends."""


def _killed_with_parent(parent: int) -> None:
    """Have Linux end this worker (SIGKILL) the moment its parent ``parent`` ends.

    Unlike the watchdog thread (:func:`_exit_with_parent`), this needs no
    Python thread to run: a worker inside a compiled kernel or the compiler,
    which hold Python's lock for long, dies too. Elsewhere, and if the call
    fails, the watchdog alone remains.
    """
    if not sys.platform.startswith("linux"):
        return
    try:
        libc = ctypes.CDLL(None, use_errno=True)
        if libc.prctl(PR_SET_PDEATHSIG, int(signal.SIGKILL), 0, 0, 0) != 0:
            return
    except (OSError, AttributeError):
        return
    if os.getppid() != parent:  # the parent ended before the call
        os._exit(1)


PARENT_POLL_S = 0.5
"""How often a worker process checks that the sweep that started it is still alive."""


def _exit_with_parent(parent: int) -> None:
    """End this worker as soon as its parent is gone (e.g. killed with SIGKILL).

    A worker whose parent died is re-parented and would otherwise go on taking
    runs; its half-written run folder stays a temporary that the next sweep
    removes.
    """
    while os.getppid() == parent:
        time.sleep(PARENT_POLL_S)
    os._exit(1)


def stop_workers(pool: ProcessPoolExecutor) -> None:
    """End the pool's worker processes now (SIGTERM), and wait until they are gone."""
    # no public way before Python 3.14 (ProcessPoolExecutor.terminate_workers)
    processes = list((getattr(pool, "_processes", None) or {}).values())
    for process in processes:
        if process.is_alive():
            process.terminate()
    for process in processes:
        process.join(timeout=10)
        if process.is_alive():
            process.kill()
            process.join(timeout=10)
    pool.shutdown(wait=True, cancel_futures=True)
