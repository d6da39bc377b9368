"""Progress display on the terminal: a rich bar fed by ``progress(done, placed, total)``."""

from __future__ import annotations

from collections.abc import Iterator
from contextlib import contextmanager

from rich.console import Console
from rich.progress import (
    BarColumn,
    Progress,
    ProgressColumn,
    Task,
    TextColumn,
    TimeElapsedColumn,
    TimeRemainingColumn,
)
from rich.text import Text

from regopack.registry.interfaces import ProgressCallback

__all__ = ["progress_bar", "shown_until_error"]


class _RateColumn(ProgressColumn):
    """Particles handled per second."""

    def render(self, task: Task) -> Text:
        speed = task.finished_speed or task.speed
        return Text("-- particles/s" if speed is None else f"{speed:,.0f} particles/s")


class _PlacedColumn(ProgressColumn):
    """Particles placed out of the total drawn."""

    def render(self, task: Task) -> Text:
        placed = int(task.fields.get("placed", 0))
        total = "?" if task.total is None else f"{int(task.total):,}"
        return Text(f"{placed:,}/{total} placed")


@contextmanager
def progress_bar(console: Console, enabled: bool, label: str) -> Iterator[ProgressCallback | None]:
    """Show a rich progress bar fed by ``progress(done, placed, total)`` calls."""
    if not enabled:
        yield None
        return
    columns = (
        TextColumn("{task.description}"),
        BarColumn(bar_width=30),
        _PlacedColumn(),
        _RateColumn(),
        TimeElapsedColumn(),
        TimeRemainingColumn(),
    )
    with shown_until_error(Progress(*columns, console=console, transient=False)) as bar:
        task = bar.add_task(label, total=None, placed=0)

        def update(done: int, placed: int, total: int) -> None:
            bar.update(task, completed=done, total=total, placed=placed)

        yield update


@contextmanager
def shown_until_error(progress: Progress) -> Iterator[Progress]:
    """Show ``progress`` during the block; an error removes it, leaving only the error's line.

    On a terminal the display is erased; into a file or pipe (where it is
    drawn once, at the end) it is not drawn at all.
    """
    console = progress.console
    was_quiet = console.quiet
    try:
        with progress:
            try:
                yield progress
            except BaseException:
                if console.is_terminal:
                    progress.live.transient = True
                else:
                    console.quiet = True
                raise
    finally:
        console.quiet = was_quiet
