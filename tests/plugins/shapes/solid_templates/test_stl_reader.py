"""The STL reader: binary and ASCII round trips, and every malformed file refused in one line."""

from __future__ import annotations

import struct
from pathlib import Path

import numpy as np
import pytest
from stl_helpers import CUBE, ascii_text, hull_triangles, write_ascii, write_binary

from regopack.base.errors import ConfigError
from regopack.plugins.shapes.solid_templates import stl
from regopack.plugins.shapes.solid_templates.stl import read_stl

TRIS = hull_triangles(CUBE * 0.3 + [1.25, -2.5, 7.0])


def test_binary_round_trip_is_exact_in_float32(tmp_path: Path) -> None:
    mesh = read_stl(write_binary(tmp_path / "c.stl", TRIS))
    assert mesh.binary and mesh.stored_as is np.float32
    assert mesh.triangles.dtype == np.float64
    assert np.array_equal(mesh.triangles, TRIS.astype(np.float32).astype(np.float64))


def test_a_binary_header_starting_with_solid_is_still_binary(tmp_path: Path) -> None:
    mesh = read_stl(write_binary(tmp_path / "c.stl", TRIS, header=b"solid exported by a CAD tool"))
    assert mesh.binary and mesh.triangles.shape == (12, 3, 3)


def test_ascii_round_trip_is_exact_in_float64(tmp_path: Path) -> None:
    mesh = read_stl(write_ascii(tmp_path / "c.stl", TRIS, name="grain 7 (measured)"))
    assert not mesh.binary and mesh.stored_as is np.float64
    assert np.array_equal(mesh.triangles, TRIS)


def test_ascii_keywords_in_any_case_blank_lines_and_a_bare_endsolid(tmp_path: Path) -> None:
    text = "\n\n" + ascii_text(TRIS).upper().replace("ENDSOLID TEST", "endsolid")
    (tmp_path / "c.stl").write_text(text.replace("E+", "e+"), encoding="ascii")
    assert np.array_equal(read_stl(tmp_path / "c.stl").triangles, TRIS)


def test_an_ascii_name_in_utf8_is_text(tmp_path: Path) -> None:
    path = tmp_path / "c.stl"
    path.write_bytes(ascii_text(TRIS, name="Körnchen 7 µm").encode("utf-8"))
    assert not read_stl(path).binary


def test_a_truncated_binary_file_with_a_solid_header_is_called_binary(tmp_path: Path) -> None:
    path = write_binary(tmp_path / "c.stl", TRIS, header=b"solid exported by a CAD tool")
    path.write_bytes(path.read_bytes()[:-10])
    with pytest.raises(ConfigError, match=r"truncated or damaged binary STL"):
        read_stl(path)


def test_a_large_ascii_file_is_parsed_in_chunks(tmp_path: Path, monkeypatch) -> None:  # type: ignore[no-untyped-def]
    monkeypatch.setattr(stl, "ASCII_CHUNK", 100)  # a chunk ends inside most facets
    many = np.concatenate([TRIS + k for k in range(20)])
    assert np.array_equal(read_stl(write_ascii(tmp_path / "m.stl", many)).triangles, many)


def _binary(count: int, n_written: int) -> bytes:
    facet = struct.pack("<12fH", *[0.5] * 12, 0)
    return b"x" * 80 + struct.pack("<I", count) + facet * n_written


def _ascii_with(old: str, new: str) -> str:
    return ascii_text(TRIS[:2]).replace(old, new, 1)


BAD_FILES = [
    ("empty", b"", r"not an STL file: 0 bytes is shorter than the 84-byte header"),
    ("short binary", b"\x00" * 50, r"not an STL file: 50 bytes"),
    (
        "truncated binary",
        _binary(12, 11),
        r"truncated or damaged binary STL: its header declares 12 triangles, which take "
        r"84 \+ 50 x 12 = 684 bytes, but the file has 634 bytes",
    ),
    ("binary with extra bytes", _binary(1, 2), r"declares 1 triangles, .* the file has 184 bytes"),
    ("absurd count", _binary(4_000_000_000, 1), r"declares 4,000,000,000 triangles"),
    (
        "misspelt keyword",
        _ascii_with("vertex", "vertx"),
        r"ASCII STL: facet 0: expected 'vertex', found 'vertx'",
    ),
    (
        "bad number",
        _ascii_with("vertex 1.55", "vertex 1,55"),
        r"ASCII STL: facet 0: '1,55' is not a number",
    ),
    (
        "missing coordinate",
        _ascii_with(" 7.0\n      vertex", "\n      vertex"),
        r"ASCII STL: facet 0: .*expected",
    ),
    (
        "second facet broken",
        ascii_text(TRIS[:3]).replace("outer loop", "outer lop", 2).replace("lop", "loop", 1),
        r"ASCII STL: facet 1: expected 'loop', found 'lop'",
    ),
    ("no endsolid", ascii_text(TRIS[:2]).replace("endsolid test\n", ""), r"without 'endsolid'"),
    (
        "ends inside a facet",
        ascii_text(TRIS[:2]).rsplit("    endloop", 1)[0],
        r"ASCII STL: facet 1: .*(endloop|ends inside the facet)",
    ),
    (
        "two solids",
        ascii_text(TRIS[:1]) + ascii_text(TRIS[1:2]),
        r"ASCII STL: facet 1: 'endsolid' before the end of the file \(one solid per file",
    ),
    (
        "nan coordinate",
        _ascii_with("vertex 1.55", "vertex nan"),
        r"triangle 0 has a coordinate that is not a finite number \(nan\)",
    ),
    ("infinite coordinate", _ascii_with("vertex 1.55", "vertex -inf"), r"triangle 0 .*\(-inf\)"),
    ("binary nan", _binary(1, 0)[:84] + struct.pack("<12fH", *[0.0] * 5, np.nan, *[0.0] * 6, 0),
     r"triangle 0 has a coordinate that is not a finite number"),
]  # fmt: skip


@pytest.mark.parametrize(("what", "content", "message"), BAD_FILES, ids=[b[0] for b in BAD_FILES])
def test_malformed_files_are_refused_in_one_line(
    tmp_path: Path, what: str, content: bytes | str, message: str
) -> None:
    path = tmp_path / "grain.stl"
    if isinstance(content, str):
        path.write_text(content, encoding="ascii")
    else:
        path.write_bytes(content)
    with pytest.raises(ConfigError, match=message) as err:
        read_stl(path, name="grains/grain.stl")
    text = str(err.value)
    assert text.startswith("grains/grain.stl: ") and "\n" not in text


def test_an_ascii_coordinate_is_checked_in_the_fixture() -> None:
    # the replacements above must hit: the fixture's first coordinate is 1.55
    assert "vertex 1.55 " in ascii_text(TRIS[:2])


def test_too_many_triangles_are_refused(tmp_path: Path, monkeypatch) -> None:  # type: ignore[no-untyped-def]
    monkeypatch.setattr(stl, "MAX_TRIANGLES", 5)
    for path in (write_binary(tmp_path / "b.stl", TRIS), write_ascii(tmp_path / "a.stl", TRIS)):
        with pytest.raises(ConfigError, match=r"at most 5 are allowed .*decimate the mesh"):
            read_stl(path)


def test_a_huge_file_is_refused_before_it_is_read(tmp_path: Path, monkeypatch) -> None:  # type: ignore[no-untyped-def]
    monkeypatch.setattr(stl, "MAX_TRIANGLES", 1)
    monkeypatch.setattr(stl, "ASCII_BYTES_PER_TRIANGLE", 100)
    path = write_ascii(tmp_path / "a.stl", TRIS)
    with pytest.raises(ConfigError, match=r"bytes is more than an STL of at most 1 triangles"):
        read_stl(path)


def test_missing_and_unreadable_files(tmp_path: Path) -> None:
    with pytest.raises(ConfigError, match=r"nope\.stl: no such STL file"):
        read_stl(tmp_path / "nope.stl")
    with pytest.raises(ConfigError, match=r"cannot read the STL file"):
        read_stl(tmp_path)  # a folder cannot be opened as a file
