"""Running the scenes of a sweep: in this process, in worker processes, or on Dask.

A run travels as a picklable job; :func:`_run_job` runs one and returns its
summary or its one-line error, so a failed run never stops the others. Local
worker processes ignore Ctrl-C (the sweep stops them) and end when the sweep
process is gone; a Dask cluster is reached through ``distributed.Client``.
"""

from __future__ import annotations

import ctypes
import json
import os
import signal
import sys
import threading
import time
import uuid
from collections.abc import Iterator, Sequence
from concurrent.futures import FIRST_COMPLETED, Future, ProcessPoolExecutor, wait
from concurrent.futures.process import BrokenProcessPool
from dataclasses import dataclass
from typing import Any

import numpy as np

from regopack.base.errors import ConfigError, RegopackError
from regopack.base.messages import install_hint
from regopack.base.threads import kernel_threads
from regopack.experiments.grid import SCENE_JSON
from regopack.packing.core import Packing
from regopack.packing.voids import void_metrics
from regopack.registry.manager import default_registry
from regopack.run.pipeline import run_scene
from regopack.scenes.model import ResolvedScene, load_scene, resolve_scene
from regopack.verification.polygons import verify

__all__ = ["PARENT_POLL_S", "verify_metrics"]


@dataclass(frozen=True)
class _Job:
    """What a worker needs to run one scene (plain, picklable data)."""

    run_id: str
    base: str
    overrides: tuple[str, ...]
    out_dir: str
    figures: bool
    verify: bool = False
    voids: bool = False
    scene_text: str = ""


def verify_metrics(packing: Packing) -> dict[str, Any]:
    """Compute the ``verify`` metrics of one packing.

    ``overlap_pairs`` and ``outside`` count the overlapping pairs and the
    particles leaving the domain, ``worst_overlap`` is the largest overlap as a
    fraction of the smaller area (0 when none), ``any_nan`` tells whether a
    placed particle has a NaN centre or outline, and ``ok`` sums it up.
    """
    placed = packing.placed
    any_nan = bool(
        np.isnan(packing.centre[placed]).any()
        or np.isnan(packing.vertices).any()
        or np.isnan(packing.radius).any()
    )
    report = verify(packing)
    worst = report.worst_overlap[2] if report.worst_overlap is not None else 0.0
    return {
        "overlap_pairs": report.n_overlapping_pairs,
        "worst_overlap": float(worst),
        "outside": report.n_outside,
        "any_nan": any_nan,
        "ok": bool(report.ok and not any_nan),
    }


def _one_line(exc: BaseException) -> str:
    text = str(exc)
    if not isinstance(exc, RegopackError):
        text = f"{type(exc).__name__}: {text}" if text else type(exc).__name__
    return " ".join(text.split())


WARM_COUNT = 20
"""Particles of the untimed run that loads a scene's kernels in a process (:func:`_warm_up`)."""

_WARMED: set[str] = set()
"""Kinds of scene whose kernels this process has loaded (:func:`_kernel_key`)."""


def _kernel_key(resolved: ResolvedScene) -> str:
    """Return what decides which compiled kernels a run of ``resolved`` loads.

    The plugins and their parameters, less the sizes and counts, which
    change no kernel.
    """
    data = resolved.to_dict()
    domain = data.get("domain", {})
    key = {
        "domain": domain.get("kind") if isinstance(domain, dict) else None,
        "phases": [p.get("shape") for p in data.get("phases", []) if isinstance(p, dict)],
        "insertion": data.get("insertion"),
        "density": data.get("density"),
        "size": (data.get("size") or {}).get("kind"),
    }
    return json.dumps(key, sort_keys=True, default=str)


def _warm_up(resolved: ResolvedScene) -> None:
    """Load the kernels of ``resolved`` once per process, in an untimed run of a few particles.

    The first run of a worker process would otherwise count the loading of
    its kernels from the cache (a second or more) as insertion time, and a
    sweep's fit of time against N would mix the two. A warm-up that fails
    is ignored: the run itself reports what is wrong.
    """
    key = _kernel_key(resolved)
    if key in _WARMED:
        return
    _WARMED.add(key)
    try:
        count = resolved.scene.count
        few = WARM_COUNT if not isinstance(count, int) else min(count, WARM_COUNT)
        run_scene(resolved.with_(count=max(1, few)), None, figures=False, verify=False)
    except Exception:  # the timed run reports the same error
        pass


def _run_job(job: _Job) -> tuple[dict[str, Any] | None, str | None]:
    """Run one scene; return ``(summary, None)`` or ``(None, error message)``.

    The run folder is written as a whole (see :func:`regopack.run.pipeline.run_scene`),
    with the run's ``scene.json`` and the ``verify`` and ``voids`` metrics in
    its summary.
    """

    def extras(packing: Packing) -> dict[str, Any]:
        out: dict[str, Any] = {}
        if job.verify:
            out["verify"] = verify_metrics(packing)
        if job.voids:
            out["voids"] = void_metrics(packing)
        return out

    try:
        scene = load_scene(job.base, job.overrides)
        resolved = resolve_scene(scene, default_registry())
        _warm_up(resolved)
        outcome = run_scene(
            resolved,
            job.out_dir,
            figures=job.figures,
            summary_extras=extras,
            extra_files={SCENE_JSON: job.scene_text},
        )
    except Exception as exc:  # a failed run is recorded; the others go on
        return None, _one_line(exc)
    return outcome.summary, None


def threads_per_worker(workers: int, cores: int | None) -> int:
    """Compiled-kernel threads for each of ``workers`` processes sharing ``cores`` cores.

    A thread that waits for a core makes the whole batch it belongs to wait, so
    the workers share the cores instead of each starting one thread per core.
    """
    return max(1, (cores or 1) // max(1, workers))


def _init_worker(workers: int = 1) -> None:
    """Start a worker process: Ctrl-C goes to the main process, which stops the workers.

    SIGTERM keeps its default action (the process ends at once); the main
    process removes what a stopped worker left. The worker's compiled kernels
    use its share of the cores (:func:`threads_per_worker`).
    """
    import numba

    numba.set_num_threads(min(kernel_threads(), threads_per_worker(workers, os.cpu_count())))
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


def _stop_workers(pool: ProcessPoolExecutor) -> None:
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


def _submit_local(
    jobs: Sequence[_Job], workers: int
) -> Iterator[tuple[_Job, tuple[dict[str, Any] | None, str | None]]]:
    if workers == 1:
        for job in jobs:
            yield job, _run_job(job)
        return
    import multiprocessing

    context = multiprocessing.get_context("spawn")
    with ProcessPoolExecutor(
        max_workers=workers, mp_context=context, initializer=_init_worker, initargs=(workers,)
    ) as pool:
        pending: dict[Future[tuple[dict[str, Any] | None, str | None]], _Job] = {
            pool.submit(_run_job, job): job for job in jobs
        }
        try:
            while pending:
                done, _ = wait(pending, return_when=FIRST_COMPLETED)
                for future in sorted(done, key=lambda f: pending[f].run_id):
                    job = pending.pop(future)
                    try:
                        outcome = future.result()
                    except BrokenProcessPool as exc:
                        outcome = (None, f"worker process died: {_one_line(exc)}")
                    yield job, outcome
        except BaseException:  # Ctrl-C, SIGTERM, or the caller stopped early
            _stop_workers(pool)
            raise


def _dask(scheduler: str) -> Any:
    """Import ``distributed``, with a one-line error when it is missing."""
    try:
        import distributed
    except ImportError as err:
        raise ConfigError(
            f"--scheduler {scheduler}: Dask is not installed; "
            f"install it with: {install_hint('dask')}"
        ) from err
    return distributed


def _submit_dask(
    jobs: Sequence[_Job], scheduler: str
) -> Iterator[tuple[_Job, tuple[dict[str, Any] | None, str | None]]]:
    distributed = _dask(scheduler)
    try:
        client = distributed.Client(scheduler, timeout="20s")
    except (OSError, TimeoutError, ValueError) as err:
        raise ConfigError(
            f"--scheduler {scheduler}: cannot connect to the Dask scheduler: {_one_line(err)}"
        ) from err
    futures: dict[Any, _Job] = {}
    try:
        futures = {
            client.submit(
                _run_job, job, pure=False, key=f"regopack-{job.run_id}-{uuid.uuid4().hex}"
            ): job
            for job in jobs
        }
        for future in distributed.as_completed(list(futures)):
            job = futures[future]
            try:
                outcome = future.result()
            except Exception as exc:  # the worker was lost, or the task was cancelled
                outcome = (None, f"Dask task failed: {_one_line(exc)}")
            yield job, outcome
    except BaseException:
        client.cancel(list(futures))  # a task already running finishes its run folder
        raise
    finally:
        client.close()
