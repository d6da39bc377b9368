"""Output folders written as a whole (:mod:`regopack.base.outdir`)."""

from __future__ import annotations

from pathlib import Path

import pytest

from regopack.base import outdir
from regopack.base.errors import ConfigError, Terminated
from regopack.base.outdir import MARKER, folder_kind, mark_folder, remove_leftovers, replace_folder


def names(folder: Path) -> list[str]:
    return sorted(p.name for p in folder.iterdir())


def write(target: Path, text: str, kind: str = "run") -> None:
    with replace_folder(target, kind) as tmp:
        (tmp / "data.txt").write_text(text)


@pytest.fixture(params=["exchange", "two renames"])
def swap(request: pytest.FixtureRequest, monkeypatch: pytest.MonkeyPatch) -> str:
    """Both ways of swapping: one atomic exchange, or two renames where it is missing."""
    if request.param == "two renames":
        monkeypatch.setattr(outdir, "_exchange", lambda a, b: False)
    return str(request.param)


def test_a_new_folder_replaces_the_old_one_as_a_whole(tmp_path: Path, swap: str) -> None:
    target = tmp_path / "out"
    with replace_folder(target, "run") as tmp:
        (tmp / "old.txt").write_text("old")
        assert tmp.parent == tmp_path and tmp.name.startswith("out.tmp-")
        assert not target.exists()
    write(target, "new")
    assert names(target) == [MARKER, "data.txt"]
    assert folder_kind(target) == "run"
    assert names(tmp_path) == ["out"]


def test_an_error_inside_the_block_leaves_the_old_folder(tmp_path: Path, swap: str) -> None:
    target = tmp_path / "out"
    write(target, "old")
    for exc in (RuntimeError("a bug"), Terminated()):
        with pytest.raises(type(exc)):
            with replace_folder(target, "run") as tmp:
                (tmp / "data.txt").write_text("half")
                raise exc
        assert (target / "data.txt").read_text() == "old"
        assert names(tmp_path) == ["out"]


def test_a_signal_during_the_swap_is_raised_after_it(
    tmp_path: Path, swap: str, monkeypatch: pytest.MonkeyPatch
) -> None:
    target = tmp_path / "out"
    write(target, "old")
    real_swap = outdir._swap

    def interrupted_swap(new: Path, old: Path) -> Path | None:
        outdir.raise_or_defer(Terminated())  # what the SIGTERM handler does
        return real_swap(new, old)

    monkeypatch.setattr(outdir, "_swap", interrupted_swap)
    with pytest.raises(Terminated):
        write(target, "new")
    assert (target / "data.txt").read_text() == "new"
    assert names(tmp_path) == ["out"]
    with pytest.raises(Terminated):  # outside a swap, the handler raises at once
        outdir.raise_or_defer(Terminated())


def test_a_symlinked_output_folder_keeps_its_link(tmp_path: Path, swap: str) -> None:
    (tmp_path / "real").mkdir()
    (tmp_path / "link").symlink_to(tmp_path / "real")
    write(tmp_path / "link", "one")
    write(tmp_path / "link", "two")
    assert (tmp_path / "link").is_symlink()
    assert (tmp_path / "real" / "data.txt").read_text() == "two"
    assert names(tmp_path) == ["link", "real"]


def test_a_folder_of_another_kind_is_refused(tmp_path: Path) -> None:
    write(tmp_path / "a", "x", kind="analysis")
    with pytest.raises(ConfigError, match="holds a regopack analysis, not a run"):
        write(tmp_path / "a", "y")
    (tmp_path / "file").write_text("x")
    with pytest.raises(ConfigError, match="exists and is not a folder"):
        write(tmp_path / "file", "y")


def test_only_leftovers_of_the_same_folder_are_removed(tmp_path: Path) -> None:
    for name in ("out.tmp-abcdefgh", "out.old-12345678", "out.tmp-short", "out2.tmp-abcdefgh"):
        (tmp_path / name).mkdir()
    (tmp_path / "out.old-abcdefgh").write_text("a file, not a folder")
    removed = remove_leftovers(tmp_path / "out")
    assert sorted(p.name for p in removed) == ["out.old-12345678", "out.tmp-abcdefgh"]
    assert names(tmp_path) == ["out.old-abcdefgh", "out.tmp-short", "out2.tmp-abcdefgh"]


def test_a_users_folder_named_like_a_leftover_is_kept(tmp_path: Path) -> None:
    """Only folders regopack made (a marker, or empty) go: a user's backup stays."""
    mine = tmp_path / "x.old-backup01"
    mine.mkdir()
    (mine / "thesis.tex").write_text("mine")
    killed = tmp_path / "x.tmp-abcdefgh"
    killed.mkdir()
    (killed / "packing.npz").write_bytes(b"half")
    mark_folder(killed, "run")
    assert remove_leftovers(tmp_path / "x") == [killed]
    assert (mine / "thesis.tex").read_text() == "mine"


def test_a_temporary_folder_is_marked_from_the_start(tmp_path: Path) -> None:
    """A write killed at any moment leaves a folder the next write knows as its own."""
    with replace_folder(tmp_path / "out", "run") as tmp:
        assert folder_kind(tmp) == "run"
        (tmp / "a").write_text("x")
        assert remove_leftovers(tmp_path / "elsewhere") == []


def test_a_deletion_cut_short_leaves_a_folder_the_next_write_removes(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    """The marker goes last: a folder whose deletion stopped half-way is still regopack's."""
    import shutil

    from regopack.base.outdir import remove_folder

    left = tmp_path / "out.old-abcdefgh"
    left.mkdir()
    (left / "big").mkdir()
    (left / "big" / "f").write_text("x")
    (left / "packing.npz").write_text("x")
    mark_folder(left, "run")
    with monkeypatch.context() as m:
        m.setattr(shutil, "rmtree", lambda *a, **k: None)  # killed while deleting "big"
        remove_folder(left)
    assert folder_kind(left) == "run" and (left / "big" / "f").exists()
    assert remove_leftovers(tmp_path / "out") == [left]
    assert not left.exists()
