"""Output folders that always hold one complete, consistent set of files.

A run, ``regopack analyze --out DIR`` and the plots of a sweep write their
files into a fresh temporary folder beside the output folder,
``<out>.tmp-<random>`` in the same parent, and only when every file is complete
swap it into place with :func:`replace_folder`: the previous folder, if any,
and the new one trade places in one atomic exchange (``renameat2`` on Linux,
``renamex_np`` on macOS; elsewhere two renames, the old folder first moved to
``<out>.old-<random>``), then the previous folder is deleted. A reader (or a
kill at any moment) therefore sees the complete previous folder or the
complete new one, never a mix. Temporary and old folders left by a killed
process, ``<out>.tmp-*`` and ``<out>.old-*`` beside ``<out>``, are removed by
the next write into ``<out>``.

Replacing a folder deletes whatever it held, so a folder is replaced only
when it does not exist, is empty, or holds the marker file :data:`MARKER`
of the same kind (``run``, ``analysis`` or ``plots``) that regopack writes
into every folder it swaps in. Any other folder is refused with one line, and
so is the current directory (or a folder containing it).

The names a scene gives its outputs are plain file names inside the run
folder (:func:`name_problem` says what is wrong with one).
"""

from __future__ import annotations

import ctypes
import errno
import functools
import json
import os
import re
import secrets
import shutil
import sys
import tempfile
import threading
import time
import unicodedata
from collections.abc import Callable, Iterator
from contextlib import contextmanager
from pathlib import Path
from typing import Any

from regopack.base.errors import ConfigError

__all__ = [
    "MARKER",
    "NAME_RULE",
    "PAUSE_ENV",
    "check_replaceable",
    "checkpoint",
    "folder_kind",
    "fsync_directory",
    "mark_folder",
    "name_key",
    "name_problem",
    "raise_or_defer",
    "rebase",
    "remove_folder",
    "remove_leftovers",
    "replace_folder",
]

MARKER = ".regopack"
"""File that marks a folder written (and so replaceable) by regopack.

It holds one JSON object: ``{"format": "regopack-folder", "kind": ..., "regopack": ...}``.
"""

NAME_RULE = "not empty, no '/', '\\' or ':', not '.' or '..', no control characters"
"""What a plain file or folder name may be, for messages."""

PAUSE_ENV = "REGOPACK_TEST_PAUSE_BEFORE"
"""Test hook: a step name; the process stops before that step and waits for a signal."""

_FORBIDDEN = ("/", "\\", ":")
_TOKEN = r"[A-Za-z0-9_]{8}"


def name_problem(name: str) -> str | None:
    r"""Say what makes ``name`` not a plain file name, or return ``None`` when it is one.

    A plain name is not empty, is not ``.`` or ``..``, has no path separator
    (``/``, ``\``) and no ``:`` (which makes a drive-relative path on
    Windows), and has no control character (such as NUL or a newline).

    Examples
    --------
    >>> name_problem("packing.npz") is None
    True
    >>> name_problem("../x.npz")
    "contains '/'"
    """
    if not name:
        return "is empty"
    if name in (".", ".."):
        return f"is {name!r}"
    for char in _FORBIDDEN:
        if char in name:
            return f"contains '{char}'"
    if any(unicodedata.category(c) == "Cc" for c in name):
        return "contains a control character"
    return None


def name_key(name: str) -> str:
    """Key under which two names are the same file on every file system.

    Names that differ only in case, or in Unicode normalisation, are one file
    on case-insensitive (macOS, Windows) or normalising file systems.
    """
    return unicodedata.normalize("NFC", name).casefold()


# ---------------------------------------------------------------------------
# the test hook


def checkpoint(step: str) -> None:
    """Stop before ``step`` when the environment variable :data:`PAUSE_ENV` names it.

    For the test suite: the process prints ``regopack: paused before <step>``
    to standard error and sleeps until a signal ends it, so that a test can
    kill it at a known moment. Without the variable this does nothing.
    """
    if os.environ.get(PAUSE_ENV) != step:
        return
    sys.stderr.write(f"regopack: paused before {step} ({PAUSE_ENV})\n")
    sys.stderr.flush()
    while True:
        time.sleep(0.05)


# ---------------------------------------------------------------------------
# signals during a swap


class _SwapState(threading.local):
    """Per thread: how deep in folder swaps it is, and the signals kept for later."""

    depth = 0

    def __init__(self) -> None:
        self.pending: list[BaseException] = []


_state = _SwapState()


def raise_or_defer(exc: BaseException) -> None:
    """Raise ``exc`` from a signal handler, or after the folder swap in progress.

    The command line's handlers of SIGINT and SIGTERM call this, so that a
    signal never lands between the two renames of a swap. Handlers run in the
    main thread, so only a swap of the main thread defers them.
    """
    if _state.depth:
        _state.pending.append(exc)
        return
    raise exc


@contextmanager
def _signals_deferred() -> Iterator[None]:
    """Within the block, :func:`raise_or_defer` keeps its exception for later."""
    _state.depth += 1
    try:
        yield
    finally:
        _state.depth -= 1


def _raise_pending() -> None:
    """Raise the exception a signal handler deferred, if any."""
    if not _state.depth and _state.pending:
        exc = _state.pending[0]
        _state.pending.clear()
        raise exc


# ---------------------------------------------------------------------------
# the folder


def _real(path: Path) -> Path:
    return Path(os.path.realpath(path))


def folder_kind(folder: str | Path) -> str | None:
    """Return the kind written in ``folder``'s :data:`MARKER` file, or ``None``."""
    try:
        data = json.loads((Path(folder) / MARKER).read_text(encoding="utf-8"))
    except (OSError, UnicodeDecodeError, ValueError):
        return None
    if isinstance(data, dict) and data.get("format") == "regopack-folder":
        kind = data.get("kind")
        return kind if isinstance(kind, str) else None
    return None


def mark_folder(folder: str | Path, kind: str) -> None:
    """Write the :data:`MARKER` file of ``kind`` into ``folder``."""
    from regopack._version import __version__

    text = json.dumps({"format": "regopack-folder", "kind": kind, "regopack": __version__})
    (Path(folder) / MARKER).write_text(text + "\n", encoding="utf-8")


def check_replaceable(target: str | Path, kind: str) -> None:
    """Refuse, in one line, a folder that :func:`replace_folder` must not replace.

    ``target`` may be replaced when it does not exist, is an empty folder, or
    holds a :data:`MARKER` of ``kind``. It must not be the current directory
    or contain it.

    Raises
    ------
    ConfigError
        Naming the folder and what is allowed.
    """
    target = Path(target)
    real = _real(target)
    try:
        cwd = Path.cwd().resolve()
    except OSError:
        cwd = None
    if real.parent == real or (cwd is not None and (real == cwd or real in cwd.parents)):
        raise ConfigError(
            f"output folder {target}: is the current directory or contains it; the {kind} "
            "replaces its whole output folder, so give a folder below it, e.g. runs/mine"
        )
    ancestor = real.parent
    while not os.path.lexists(ancestor) and ancestor.parent != ancestor:
        ancestor = ancestor.parent
    if not ancestor.is_dir():
        raise ConfigError(
            f"cannot create the output directory {target}: {ancestor} is not a folder"
        )
    if not os.access(ancestor, os.W_OK | os.X_OK):
        raise ConfigError(
            f"cannot create the output directory {target}: no permission to write in {ancestor}"
        )
    if not os.path.lexists(real):
        return
    if not real.is_dir():
        raise ConfigError(f"output folder {target}: exists and is not a folder")
    found = folder_kind(real)
    if found == kind:
        return
    if found is not None:
        raise ConfigError(
            f"output folder {target}: holds a regopack {found}, not a {kind}; give another folder"
        )
    try:
        empty = not any(real.iterdir())
    except OSError as err:
        raise ConfigError(f"output folder {target}: cannot be read: {_why(err)}") from err
    if not empty:
        raise ConfigError(
            f"output folder {target}: exists and was not written by regopack (it has no "
            f"{MARKER} file); the {kind} replaces its whole output folder, so give a new or "
            "empty folder, or remove this one"
        )


def _leftover_pattern(name: str) -> re.Pattern[str]:
    return re.compile(re.escape(name) + r"\.(?:tmp|old)-" + _TOKEN)


def _written_here(folder: str) -> bool:
    """Whether ``folder`` is one regopack made: it holds a :data:`MARKER`, or is empty."""
    if folder_kind(folder) is not None:
        return True
    try:
        with os.scandir(folder) as entries:
            return next(entries, None) is None
    except OSError:
        return False


def remove_folder(folder: str | Path) -> None:
    """Delete a folder regopack made, its :data:`MARKER` last (best effort).

    A deletion cut short (a kill, a file that cannot go) leaves a folder that
    still holds its marker, which the next write into its output folder
    removes (:func:`remove_leftovers`).
    """
    marker = os.path.join(folder, MARKER)
    try:
        entries = list(os.scandir(folder))
    except OSError:
        return
    for entry in entries:
        if entry.name == MARKER:
            continue
        if entry.is_dir(follow_symlinks=False):
            shutil.rmtree(entry.path, ignore_errors=True)
        else:
            try:
                os.unlink(entry.path)
            except OSError:
                pass
    try:
        if any(e.name != MARKER for e in os.scandir(folder)):
            return  # something could not go: the marker stays for the next write
        os.unlink(marker)
    except OSError:
        pass
    try:
        os.rmdir(folder)
    except OSError:
        pass


def remove_leftovers(target: str | Path) -> list[Path]:
    """Remove the temporary and old folders a killed write left beside ``target``.

    These are the folders ``<name>.tmp-<random>`` and ``<name>.old-<random>``
    (eight letters, digits or ``_``) in ``target``'s parent that regopack
    made: each holds a :data:`MARKER` (a temporary folder gets one when it is
    made) or is empty. A folder of the user's that only has such a name is
    kept. Returns the folders removed.
    """
    real = _real(Path(target))
    pattern = _leftover_pattern(real.name)
    removed: list[Path] = []
    try:
        entries = list(os.scandir(real.parent))
    except OSError:
        return removed
    for entry in entries:
        if (
            pattern.fullmatch(entry.name)
            and entry.is_dir(follow_symlinks=False)
            and _written_here(entry.path)
        ):
            remove_folder(entry.path)
            removed.append(Path(entry.path))
    return removed


def _why(err: OSError) -> str:
    return err.strerror or str(err) or type(err).__name__


def _umask() -> int:
    mask = os.umask(0)
    os.umask(mask)
    return mask


def _fsync_tree(folder: Path) -> None:
    """Flush every file and folder under ``folder`` to disk (best effort)."""
    for root, _dirs, files in os.walk(folder):
        for name in [*files, "."]:
            fsync_directory(Path(root, name))


def fsync_directory(directory: Path) -> None:
    """Flush a folder's entries (or a file) to disk (best effort; a failure is ignored)."""
    try:
        fd = os.open(directory, os.O_RDONLY)
    except OSError:
        return
    try:
        os.fsync(fd)
    except OSError:
        pass
    finally:
        os.close(fd)


@functools.cache
def _load_exchange() -> Callable[[bytes, bytes], int] | None:
    """Return a function exchanging two paths atomically (``0`` on success), if libc has one."""
    found: Callable[[bytes, bytes], int] | None = None
    try:
        libc = ctypes.CDLL(None, use_errno=True)
        if sys.platform.startswith("linux") and hasattr(libc, "renameat2"):
            renameat2 = libc.renameat2
            renameat2.argtypes = (
                ctypes.c_int,
                ctypes.c_char_p,
                ctypes.c_int,
                ctypes.c_char_p,
                ctypes.c_uint,
            )
            renameat2.restype = ctypes.c_int
            at_fdcwd, rename_exchange = -100, 2

            def found(a: bytes, b: bytes) -> int:
                return int(renameat2(at_fdcwd, a, at_fdcwd, b, rename_exchange))

        elif sys.platform == "darwin" and hasattr(libc, "renamex_np"):
            renamex_np = libc.renamex_np
            renamex_np.argtypes = (ctypes.c_char_p, ctypes.c_char_p, ctypes.c_uint)
            renamex_np.restype = ctypes.c_int
            rename_swap = 2

            def found(a: bytes, b: bytes) -> int:
                return int(renamex_np(a, b, rename_swap))

    except (OSError, AttributeError, TypeError):
        found = None
    return found


def _exchange(a: Path, b: Path) -> bool:
    """Exchange the folders ``a`` and ``b`` atomically; ``False`` when the system cannot."""
    function = _load_exchange()
    if function is None:
        return False
    if function(os.fsencode(a), os.fsencode(b)) == 0:
        return True
    code = ctypes.get_errno()
    if code in (errno.EINVAL, errno.ENOSYS, errno.ENOTSUP, errno.EOPNOTSUPP, errno.EXDEV):
        return False
    raise OSError(code, os.strerror(code), str(b))


def _swap(new: Path, target: Path) -> Path | None:
    """Put the folder ``new`` at ``target``; return where the previous folder now is."""
    if not os.path.lexists(target):
        os.rename(new, target)
        fsync_directory(target.parent)
        return None
    if _exchange(new, target):
        fsync_directory(target.parent)
        return new
    old = target.with_name(f"{target.name}.old-{secrets.token_hex(4)}")
    os.rename(target, old)
    try:
        os.rename(new, target)
    except BaseException:
        os.rename(old, target)
        raise
    fsync_directory(target.parent)
    return old


@contextmanager
def replace_folder(target: str | Path, kind: str) -> Iterator[Path]:
    """Write a folder as a whole: yield a fresh temporary folder, then swap it in.

    Parameters
    ----------
    target
        The output folder. Its parent is created if needed; the temporary
        folder ``<name>.tmp-<random>`` is made in that parent.
    kind
        What the folder holds (``"run"``, ``"analysis"``, ``"plots"``),
        written into its :data:`MARKER` file.

    When the ``with`` block ends normally, the temporary folder gets its
    marker, is flushed to disk and replaces ``target`` (see the module
    documentation); the previous folder is deleted. When the block raises
    (including ``KeyboardInterrupt``), the temporary folder is deleted and
    ``target`` is left as it was.

    Raises
    ------
    ConfigError
        When ``target`` may not be replaced (:func:`check_replaceable`) or
        its parent cannot be created or written.
    """
    target = Path(target)
    check_replaceable(target, kind)
    real = _real(target)
    try:
        real.parent.mkdir(parents=True, exist_ok=True)
    except OSError as err:
        raise ConfigError(f"cannot create the output directory {target}: {_why(err)}") from err
    remove_leftovers(real)
    try:
        tmp = Path(tempfile.mkdtemp(prefix=f"{real.name}.tmp-", dir=real.parent))
    except OSError as err:
        raise ConfigError(f"cannot create the output directory {target}: {_why(err)}") from err
    old: Path | None = None
    try:
        os.chmod(tmp, 0o777 & ~_umask())
        mark_folder(tmp, kind)  # a leftover of a killed write is known as regopack's
        yield tmp
        mark_folder(tmp, kind)
        _fsync_tree(tmp)
        checkpoint("swap")
        try:
            with _signals_deferred():
                old = _swap(tmp, real)
        except OSError as err:
            raise ConfigError(f"cannot move the new output into {target}: {_why(err)}") from err
        _raise_pending()
    except OSError as err:  # e.g. the disk is full: one line, and nothing half-written
        remove_folder(tmp)
        raise ConfigError(f"cannot write the output folder {target}: {_why(err)}") from err
    except BaseException:
        remove_folder(tmp)
        raise
    finally:
        if old is not None:
            remove_folder(old)


def rebase(path: Any, old: Path, new: Path) -> Any:
    """``path`` under ``old`` moved under ``new`` (other values unchanged)."""
    if isinstance(path, Path):
        try:
            return new / path.relative_to(old)
        except ValueError:
            return path
    return path
