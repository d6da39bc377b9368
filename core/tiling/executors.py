"""Where the tiles' tasks run: in this process, in local worker processes, or on Dask.

An executor maps a task function over a list of tasks and returns the
results in the tasks' order; the schedule (:mod:`.run`) waits for one
colour's tasks before it hands out the next colour's. Results do not depend
on the executor: a task reads only what it is given.
"""

from __future__ import annotations

import importlib
import os
import uuid
from collections.abc import Callable, Iterator, Sequence
from concurrent.futures import ProcessPoolExecutor, as_completed
from concurrent.futures.process import BrokenProcessPool
from contextlib import contextmanager
from typing import Any, Protocol, TypeVar

from regopack.base.errors import ConfigError, RegopackError
from regopack.base.messages import install_hint

T = TypeVar("T")
R = TypeVar("R")


Done = Callable[[int, Any], None]
"""Called as ``done(position, result)`` as each task finishes, in the order they finish."""


class TileExecutor(Protocol):
    """Runs tasks; the results come back in the tasks' order."""

    def map(self, fn: Callable[[T], R], items: Sequence[T], done: Done | None = None) -> list[R]:
        """Return ``[fn(item) for item in items]``, computed wherever the executor runs.

        ``done`` hears of each task as it finishes (for progress; the order
        of the results does not depend on it).
        """
        ...


class InProcess:
    """Every task in this process, one after another."""

    def map(self, fn: Callable[[T], R], items: Sequence[T], done: Done | None = None) -> list[R]:
        """Run the tasks here, in order."""
        out = []
        for k, item in enumerate(items):
            out.append(fn(item))
            if done is not None:
                done(k, out[-1])
        return out


def _init_tile_worker(threads: int) -> None:
    """Start a local worker: its share of the kernel threads; it ends with the parent."""
    from regopack.base.worker_processes import init_worker

    init_worker(threads=threads)


class LocalProcesses:
    """Tasks in ``workers`` local processes (started on first use, stopped by :meth:`close`).

    Each process runs its compiled kernels on ``threads`` threads (its share
    of the cores by default) and ends when the process that started it ends.
    """

    def __init__(self, workers: int, threads: int | None = None) -> None:
        if workers < 1:
            raise ConfigError(f"--workers {workers}: give one worker or more")
        self.workers = workers
        cores = os.cpu_count() or 1
        self.threads = threads if threads is not None else max(1, cores // workers)
        self._pool: ProcessPoolExecutor | None = None

    def map(self, fn: Callable[[T], R], items: Sequence[T], done: Done | None = None) -> list[R]:
        """Run the tasks on the workers; a task's error is raised here."""
        if self._pool is None:
            import multiprocessing

            self._pool = ProcessPoolExecutor(
                max_workers=self.workers,
                mp_context=multiprocessing.get_context("spawn"),
                initializer=_init_tile_worker,
                initargs=(self.threads,),
            )
        futures = [self._pool.submit(fn, item) for item in items]
        position = {f: k for k, f in enumerate(futures)}
        try:
            for f in as_completed(futures):
                result = f.result()
                if done is not None:
                    done(position[f], result)
            return [f.result() for f in futures]
        except BrokenProcessPool as err:
            raise RegopackError(f"a tile's worker process died: {err}") from None
        except BaseException:
            for f in futures:
                f.cancel()
            raise

    def close(self) -> None:
        """Stop the worker processes."""
        pool, self._pool = self._pool, None
        if pool is not None:
            from regopack.base.worker_processes import stop_workers

            stop_workers(pool)

    def __enter__(self) -> LocalProcesses:
        return self

    def __exit__(self, *exc: object) -> None:
        self.close()


class DaskClient:
    """Tasks on a Dask cluster through a ``distributed.Client`` (or a scheduler's address)."""

    def __init__(self, client: Any, flag: str = "--scheduler") -> None:
        self._own = None
        if isinstance(client, str):
            try:
                distributed: Any = importlib.import_module("distributed")
            except ImportError as err:
                raise ConfigError(
                    f"{flag} {client}: Dask is not installed; install it with: "
                    f"{install_hint('dask')}"
                ) from err
            try:
                client = distributed.Client(client, timeout="20s")
            except (OSError, TimeoutError, ValueError) as err:
                raise ConfigError(
                    f"{flag} {client}: cannot connect to the Dask scheduler: {err}"
                ) from err
            self._own = client
        self.client = client

    def map(self, fn: Callable[[T], R], items: Sequence[T], done: Done | None = None) -> list[R]:
        """Submit the tasks (keys of their own) and gather their results in order."""
        distributed: Any = importlib.import_module("distributed")
        tag = uuid.uuid4().hex
        futures = [
            self.client.submit(fn, item, pure=False, key=f"regopack-tile-{tag}-{k}")
            for k, item in enumerate(items)
        ]
        position = {f.key: k for k, f in enumerate(futures)}
        try:
            if done is not None:
                for f in distributed.as_completed(futures):
                    done(position[f.key], f.result())
            return list(self.client.gather(futures))
        except BaseException:
            self.client.cancel(futures)
            raise

    def close(self) -> None:
        """Close the client this executor opened (a client it was given stays open)."""
        own, self._own = self._own, None
        if own is not None:
            own.close()


@contextmanager
def executor_for(
    tiled: bool,
    workers: int | None = None,
    threads: int | None = None,
    client: Any = None,
    *,
    flags: tuple[str, str, str] = ("workers", "threads_per_worker", "client"),
) -> Iterator[TileExecutor | None]:
    """Yield the executor the options ask for; ``None`` packs in this process.

    ``client`` is a ``distributed.Client`` or a scheduler's address;
    ``workers`` local processes (one: this process). A tiled scene may be
    packed anywhere; a scene without tiles is one task, refused with more
    than this process. ``flags`` name the options in messages (the CLI's
    ``--workers`` and the API's ``workers``).
    """
    w_flag, t_flag, c_flag = flags
    for flag, value, what in ((w_flag, workers, "workers"), (t_flag, threads, "threads")):
        whole = isinstance(value, int) and not isinstance(value, bool)
        if value is not None and not (whole and value >= 1):
            raise ConfigError(f"{flag} {value!r}: give a whole number of {what}, 1 or more")
    wants = client is not None or (workers or 1) > 1 or threads is not None
    if wants and not tiled:
        what = (
            f"{c_flag} {client}"
            if client is not None
            else f"{w_flag} {workers}"
            if (workers or 1) > 1
            else f"{t_flag} {threads}"
        )
        raise ConfigError(
            f"{what}: the scene is packed as one task in one process; give it tiles to "
            "pack on several workers, e.g. --set tiles.side=60 (a side of several "
            "largest particles)"
        )
    if client is not None:
        dask = DaskClient(client, c_flag)
        try:
            yield dask
        finally:
            dask.close()
        return
    if (workers or 1) > 1:
        assert workers is not None
        with LocalProcesses(workers, threads) as local:
            yield local
        return
    yield None
