"""Worker processes of an experiment share the machine's cores."""

from __future__ import annotations

import pytest

from regopack.experiment_workers import threads_per_worker


@pytest.mark.parametrize(
    ("workers", "cores", "threads"),
    [(1, 8, 8), (2, 8, 4), (3, 8, 2), (8, 8, 1), (16, 8, 1), (2, 2, 1), (2, None, 1), (0, 4, 4)],
)
def test_workers_share_the_cores(workers: int, cores: int | None, threads: int) -> None:
    assert threads_per_worker(workers, cores) == threads
