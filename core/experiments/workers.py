"""Running the scenes of a sweep: in this process, in worker processes, or on Dask.

A run travels as a picklable job; :func:`_run_job` runs one and returns its
summary or its one-line error, so a failed run never stops the others. Local
worker processes ignore Ctrl-C (the sweep stops them) and end when the sweep
process is gone; a Dask cluster is reached through ``distributed.Client``.
"""

from __future__ import annotations

import json
import uuid
from collections.abc import Iterator, Sequence
from concurrent.futures import FIRST_COMPLETED, Future, ProcessPoolExecutor, wait
from concurrent.futures.process import BrokenProcessPool
from dataclasses import dataclass
from typing import Any

import numpy as np

from regopack.base.errors import ConfigError, RegopackError
from regopack.base.messages import install_hint
from regopack.base.worker_processes import PARENT_POLL_S as PARENT_POLL_S
from regopack.base.worker_processes import init_worker as _init_worker
from regopack.base.worker_processes import stop_workers as _stop_workers
from regopack.base.worker_processes import threads_per_worker as threads_per_worker
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
        run_scene(
            resolved.with_(count=max(1, few)), None, figures=False, verify=False,
            tiled=_tiled(resolved),
        )  # fmt: skip
    except Exception:  # the timed run reports the same error
        pass


def _tiled(resolved: ResolvedScene) -> Any:
    """Return the packer of a tiled scene's tiles in this worker (``None``: no tiles)."""
    if resolved.scene.tiles is None:
        return None
    from regopack.tiling.executors import InProcess
    from regopack.tiling.run import check_tiled, packer_for

    check_tiled(resolved)
    return packer_for(InProcess())


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
            tiled=_tiled(resolved),
        )
    except Exception as exc:  # a failed run is recorded; the others go on
        return None, _one_line(exc)
    return outcome.summary, None


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
