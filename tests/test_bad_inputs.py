"""Bad inputs end in one line on stderr and a non-zero exit, and write nothing.

Each case is a command a user could type: a value of the wrong type in a scene
or experiment file or in ``--set``, an empty ``--out``, a negative or NaN
``--rel-tol``, a scene that cannot be drawn (too many particles for the
memory, sizes that overflow 64-bit floats, particles larger than the domain),
a sweep that expands to too many runs, a full disk. None may print a
traceback or leave a file behind.
"""

from __future__ import annotations

import errno
import os
from collections.abc import Callable
from importlib.resources import files
from pathlib import Path

import numpy as np
import pytest

import regopack.analysis.pipeline
import regopack.experiments.file
import regopack.run.pipeline
from regopack.base.errors import PackingError
from regopack.cli import main
from regopack.packing.core import save
from regopack.testing import packing_from_polygons
from regopack.verification.polygons import verify

GIB = 1024**3
SQUARE = [(0.0, 0.0), (1.0, 0.0), (1.0, 1.0), (0.0, 1.0)]

UNIFORM_SCENE = """\
name = "huge"
count = 5
[size]
kind = "uniform"
d_min = 1e300
d_max = 2e300
[[phases]]
name = "a"
fraction = 1
shape = { kind = "octagon", psi = 1, a = 0.3, m = 8 }
[insertion]
kind = "available-arc"
[density]
kind = "eta"
"""


def small_with(old: str, new: str) -> str:
    """The built-in ``small`` scene with one piece of text replaced."""
    text = files("regopack.scenes").joinpath("small.toml").read_text(encoding="utf-8")
    assert old in text
    return text.replace(old, new, 1)


FILES: dict[str, Callable[[Path], None]] = {
    "width.toml": lambda p: p.write_text(small_with("width = 200.0", 'width = "200"')),
    "lists.toml": lambda p: p.write_text(
        small_with('search = "indexed"', 'search = "indexed"\nneighbour_lists = "yes"')
    ),
    "uniform.toml": lambda p: p.write_text(UNIFORM_SCENE),
    "verify.toml": lambda p: p.write_text('base = "small"\nverify = "yes"\n[set]\ncount = 5\n'),
    "grid.toml": lambda p: p.write_text(
        'base = "small"\n[sweep]\nseed = "1..1000000000000"\n"density.eta" = [0, 1]\n'
    ),
    "huge-max-runs.toml": lambda p: p.write_text(
        'base = "small"\nmax_runs = 100000000000000000\n[sweep]\nseed = "1..100000000"\n'
    ),
    "grid-memory.toml": lambda p: p.write_text(
        'base = "small"\nmax_runs = 1000000\n[sweep]\nseed = "1..500000"\n'
    ),
    "deep.toml": lambda p: p.write_text("x = " + "[" * 50_000 + "]" * 50_000 + "\n"),
    "deep.json": lambda p: p.write_text("[" * 50_000 + "]" * 50_000),
    "packing.npz": lambda p: save(
        packing_from_polygons([SQUARE, [(x + 2, y) for x, y in SQUARE]], domain=(0, 4, 0, 2)),
        p,
    ),
}
"""Input files every case finds in its working directory."""


@pytest.fixture(autouse=True)
def workdir(tmp_path: Path, monkeypatch: pytest.MonkeyPatch) -> Path:
    """Run in a temporary directory holding the input files, on a machine with 16 GiB."""
    monkeypatch.chdir(tmp_path)
    monkeypatch.setattr(
        regopack.run.pipeline, "memory_limit", lambda: (16 * GIB, "memory"), raising=False
    )
    monkeypatch.setattr(
        regopack.experiments.file, "memory_limit", lambda: (16 * GIB, "memory"), raising=False
    )
    for name, write in FILES.items():
        write(tmp_path / name)
    return tmp_path


def tree(folder: Path) -> dict[str, bytes]:
    """Every file below ``folder`` with its content."""
    return {str(p.relative_to(folder)): p.read_bytes() for p in folder.rglob("*") if p.is_file()}


def one_line(capsys: pytest.CaptureFixture[str], prefix: str = "regopack: error: ") -> str:
    """The single line on stderr, without its prefix; no traceback."""
    err = capsys.readouterr().err
    assert "Traceback" not in err
    lines = err.splitlines()
    assert len(lines) == 1, err
    assert lines[0].startswith(prefix), err
    return lines[0].removeprefix(prefix)


def usage(command: str, option: str, text: str) -> str:
    return f"{command}: argument {option}: {text} (see 'regopack {command} --help')"


EMPTY_OUT = "'' is an empty path; give a folder or file name, e.g. runs/mine"

CASES: list[tuple[str, list[str], str]] = [
    # 1. strict types: no string or boolean is taken for a number, nor a string for a boolean
    (
        "scene-file-string-for-float",
        ["run", "width.toml", "--set", "count=5", "--quiet"],
        'width.toml: domain.width = "200": Input should be a valid number',
    ),
    (
        "scene-file-string-for-bool",
        ["run", "lists.toml", "--set", "count=5", "--quiet"],
        'lists.toml: insertion.neighbour_lists = "yes": Input should be a valid boolean',
    ),
    (
        "set-string-for-float",
        ["run", "small", "--set", "count=5", "--set", 'domain.width="200"', "--quiet"],
        '--set: domain.width = "200": Input should be a valid number',
    ),
    (
        "set-bare-word-for-float",
        ["run", "small", "--set", "domain.width=abc", "--quiet"],
        '--set: domain.width = "abc": Input should be a valid number',
    ),
    (
        "set-bool-for-float",
        ["run", "small", "--set", "count=5", "--set", "domain.width=true", "--quiet"],
        "--set: domain.width = true: Input should be a valid number",
    ),
    (
        "set-string-in-point",
        ["config", "small", "--set", 'domain.center=["1", 2]'],
        '--set: domain.center.0 = "1": Input should be a valid number',
    ),
    (
        "set-string-for-plugin-float",
        ["run", "small", "--set", "count=5", "--set", 'insertion.t="0.9"', "--quiet"],
        '--set: insertion.t = "0.9": Input should be a valid number',
    ),
    (
        "set-unknown-lag",
        ["run", "dem", "--set", "count=5", "--set", "insertion.lag=pilots", "--quiet"],
        "--set: insertion.lag = \"pilots\": Input should be 'pilot' or 'none'",
    ),
    (
        "set-centre-beyond-float-precision",
        ["run", "small", "--set", "domain.center=[1e20, 0]", "--quiet"],
        "--set: domain: center = [1e+20, 0] is too far from the origin for a domain whose "
        "smallest side is 200: 64-bit floats are 1.6e+04 apart there, more than 1e-09 of that "
        "side; put the centre within 9e+08 of the origin",
    ),
    (
        "set-centre-beyond-float-precision-3d",
        ["config", "dem3d", "--set", "domain.center=[0, 3e9, 0]"],
        "--set: domain: center = [0, 3e+09, 0] is too far from the origin for a domain whose "
        "smallest side is 150: 64-bit floats are 4.8e-07 apart there, more than 1e-09 of that "
        "side; put the centre within 6.8e+08 of the origin",
    ),
    (
        "set-unknown-lag-3d",
        ["run", "dem3d", "--set", "count=5", "--set", "insertion.lag=pilots", "--quiet"],
        "--set: insertion.lag = \"pilots\": Input should be 'pilot' or 'none'",
    ),
    (
        "set-string-for-size-float",
        ["config", "small", "--set", 'size.d_min="2"'],
        '--set: size.d_min = "2": Input should be a valid number',
    ),
    (
        "experiment-string-for-bool",
        ["sweep", "verify.toml", "--out", "sweep", "--quiet", "--no-plots"],
        'verify.toml: verify = "yes": Input should be a valid boolean',
    ),
    # 2. an empty --out would mean the current directory
    (
        "run-empty-out",
        ["run", "small", "--set", "count=5", "--out", ""],
        usage("run", "--out", EMPTY_OUT),
    ),
    (
        "analyze-empty-out",
        ["analyze", "packing.npz", "--out", "", "--no-figures"],
        usage("analyze", "--out", EMPTY_OUT),
    ),
    (
        "export-empty-out",
        ["export", "packing.npz", "--to", "csv", "--out", ""],
        usage("export", "--out", EMPTY_OUT),
    ),
    ("sweep-empty-out", ["sweep", "verify.toml", "--out", ""], usage("sweep", "--out", EMPTY_OUT)),
    # 3. --rel-tol
    (
        "negative-rel-tol",
        ["verify", "packing.npz", "--rel-tol", "-1"],
        usage("verify", "--rel-tol", "'-1': must be a finite number >= 0, e.g. 1e-9"),
    ),
    (
        "nan-rel-tol",
        ["verify", "packing.npz", "--rel-tol", "nan"],
        usage("verify", "--rel-tol", "'nan': must be a finite number >= 0, e.g. 1e-9"),
    ),
    # 4. more particles than the memory holds
    (
        "count-beyond-memory",
        ["run", "small", "--set", f"count={10**12}", "--quiet"],
        "--set: count = 1000000000000: 1,000,000,000,000 particles (2D paper order runs: "
        "about 3,200 bytes a particle) need about 2.8 PiB of memory; this machine's memory "
        "is 16.0 GiB",
    ),
    # 5. huge domains with count = "auto"
    (
        "domain-area-overflows",
        ["run", "small", "--set", "domain.width=1e200", "--set", "domain.height=1e200"],
        "--set: domain: width x height = 1e+200 x 1e+200 gives a rectangle whose area "
        "overflows 64-bit floats (inf); give a smaller domain",
    ),
    (
        "domain-beyond-coordinates",
        ["run", "small", "--set", "domain.width=1e100", "--set", "domain.height=1e100"],
        "--set: domain.width = 1e+100: the domain's extent (1e+100) is 5e+99 times the "
        "smallest particle diameter (2); at most 1e+08 times, or 64-bit coordinates do not "
        "resolve the particles and the neighbour grids grow without bound; give a smaller "
        "domain or larger particles",
    ),
    (
        "count-beyond-measured-memory",
        ["run", "small", "--set", "count=50000000", "--quiet"],
        "--set: count = 50000000: 50,000,000 particles (2D paper order runs: about 3,200 "
        "bytes a particle) need about 149.0 GiB of memory; this machine's memory is 16.0 GiB",
    ),
    (
        "auto-count-beyond-measured-memory",
        ["run", "small", "--set", "size.d_min=0.05", "--set", "size.d0=0", "--quiet"],
        'small.toml: count = "auto": gives 13,466,127 particles (domain area 40000 / mean '
        "particle area 0.00297042), which (2D paper order runs: about 3,200 bytes a particle) "
        "need about 40.1 GiB of memory; this machine's memory is 16.0 GiB",
    ),
    (
        "config-checks-as-run-does",
        ["config", "small", "--set", "count=50000000"],
        "--set: count = 50000000: 50,000,000 particles (2D paper order runs: about 3,200 "
        "bytes a particle) need about 149.0 GiB of memory; this machine's memory is 16.0 GiB",
    ),
    # 5b. a box far deeper than its particles (once a grid of no finite size: a segfault)
    (
        "box-beyond-coordinates",
        [
            "run",
            "table1-3d",
            "--set",
            "domain.depth=1e300",
            "--set",
            "count=30",
            "--set",
            'size={kind="uniform", d_min=2, d_max=4}',
            "--quiet",
        ],
        "--set: domain.depth = 1e+300: the domain's extent (1e+300) is 5e+299 times the "
        "smallest particle diameter (2); at most 1e+08 times, or 64-bit coordinates do not "
        "resolve the particles and the neighbour grids grow without bound; give a smaller "
        "domain or larger particles",
    ),
    # 5c. sizes that imply work beyond any bound
    (
        "zone-beyond-bins",
        [
            "run",
            "small",
            "--set",
            "count=5",
            "--set",
            "insertion.order=sweep",
            "--set",
            "insertion.zone=1e300",
            "--quiet",
        ],
        "--set: insertion.zone = 1e+300: gives 4e+299 bins of the sweep's zone; at most "
        "1,048,576; a zone of at most 13,107 times the domain's height (200)",
    ),
    (
        "shift-beyond-floats",
        ["config", "small", "--set", "size.d0=1e300"],
        "--set: size: d0 (1e+300) is 2.63e+298 times d_max - d_min over d_min + d0; at most "
        "1e+09 times, or the distribution cannot be computed in 64-bit floats",
    ),
    (
        "polygon-area-overflows",
        [
            "config",
            "small",
            "--set",
            'domain={kind="polygon", vertices=[[0, 0], [1e200, 0], [0, 1e200]]}',
        ],
        "--set: domain: vertices: the corners are so far apart that the polygon's area "
        "overflows 64-bit floats; give smaller coordinates",
    ),
    (
        "periodic-too-small-names-set",
        [
            "run",
            "small",
            "--set",
            "count=5",
            "--set",
            'domain.kind="periodic"',
            "--set",
            "domain.width=10",
            "--quiet",
        ],
        "--set: domain.width = 10.0: a periodic domain must be wider and higher than 4 x the "
        "largest particle circumradius (36.7839); give a larger domain or smaller particles",
    ),
    (
        "scene-nested-too-deep",
        ["config", "deep.toml"],
        "deep.toml: arrays or tables nested too deeply to read (more than Python's recursion "
        "limit); a scene nests a few levels",
    ),
    (
        "template-nested-too-deep",
        ["config", "small", "--set", 'phases.0.shape={kind="template", path="deep.json"}'],
        "--set: phases.0.shape: deep.json: lists nested too deeply to read; a template file "
        "holds outlines of [x, y] pairs",
    ),
    # 5d. analyzer settings that imply bins or rings beyond any bound
    (
        "rdf-bins-from-set",
        [
            "analyze",
            "packing.npz",
            "--only",
            "rdf",
            "--set",
            "rdf.near=[0, 10]",
            "--set",
            "rdf.near_bin=1e-9",
            "--out",
            "a",
        ],
        "--set: rdf.near_bin = 1e-09: gives 1e+10 bins over near = [0, 10]; at most 65,536; "
        "give a bin width of at least 0.000152588 (the range / 65,536) or a shorter range",
    ),
    (
        "rdf-bins-in-scene",
        [
            "config",
            "small",
            "--set",
            'outputs.analyses=[{kind="rdf", near=[0, 10], near_bin=1e-9}]',
        ],
        "--set: outputs.analyses.0.near_bin = 1e-09: gives 1e+10 bins over near = [0, 10]; at "
        "most 65,536; give a bin width of at least 0.000152588 (the range / 65,536) or a "
        "shorter range",
    ),
    (
        "homogeneity-rings-from-set",
        [
            "analyze",
            "packing.npz",
            "--only",
            "homogeneity",
            "--set",
            "homogeneity.ring_width=1e-9",
            "--set",
            "homogeneity.margin=0",
            "--out",
            "a",
        ],
        "--set: homogeneity.ring_width = 1e-09: gives 2.24e+09 rings; at most 1,000; give a "
        "ring width of at least 0.00223607 or set rings",
    ),
    # 6. sizes whose area (and vertices) overflow
    (
        "sizes-overflow",
        ["run", "uniform.toml"],
        "uniform.toml: size: the largest particle (diameter 2e+300) has an area of inf: its "
        "size overflows 64-bit floats; give smaller sizes",
    ),
    (
        "sizes-underflow",
        [
            "run",
            "small",
            "--set",
            'size={kind="uniform", d_min=2e-200, d_max=4e-200}',
            "--set",
            "domain.width=1e-198",
            "--set",
            "domain.height=1e-198",
            "--set",
            "count=5",
        ],
        "--set: size: the smallest particle (diameter 2e-200) has an area of 0: its size "
        "underflows 64-bit floats; give larger sizes",
    ),
    (
        "tiny-sizes-config",
        ["config", "small", "--set", "size.d_min=1e-300", "--set", "size.d_max=2e-300"],
        "--set: size: d0 (16) is 1.6e+301 times d_max - d_min over d_min + d0; at most 1e+09 "
        "times, or the distribution cannot be computed in 64-bit floats",
    ),
    # 7. no particle fits the domain
    (
        "particles-larger-than-domain",
        ["run", "small", "--set", "domain.width=1", "--set", "domain.height=1", "--set", "count=5"],
        "--set: domain: the smallest particle (diameter 2, area 3.14159) is larger than the "
        "domain (area 1), so no particle can be placed; give smaller sizes or a larger domain",
    ),
    # 10. a sweep expanding to more runs than max_runs
    (
        "sweep-too-many-runs",
        ["sweep", "grid.toml", "--out", "sweep"],
        "grid.toml: the sweep expands to 2,000,000,000,000 runs (sweep.seed has "
        "1,000,000,000,000, sweep.density.eta has 2), more than max_runs = 10,000; set "
        "max_runs in the experiment file to allow more",
    ),
    (
        "max-runs-beyond-bound",
        ["sweep", "huge-max-runs.toml", "--out", "sweep"],
        "huge-max-runs.toml: max_runs = 1e+17: at most 1,000,000 runs (every run's scene is "
        "checked and held before the first run starts); split the sweep into several "
        "experiments",
    ),
    (
        "sweep-grid-beyond-memory",
        ["sweep", "grid-memory.toml", "--out", "sweep"],
        "grid-memory.toml: the sweep expands to 500,000 runs, whose scenes (about 64,000 bytes "
        "a run, checked before the first run starts) need about 29.8 GiB of memory; this "
        "machine's memory is 16.0 GiB; split the sweep into several experiments",
    ),
]


@pytest.mark.parametrize(("argv", "expected"), [c[1:] for c in CASES], ids=[c[0] for c in CASES])
def test_refused_in_one_line_and_nothing_written(
    workdir: Path, capsys: pytest.CaptureFixture[str], argv: list[str], expected: str
) -> None:
    before = tree(workdir)
    assert main(argv) == 2
    assert one_line(capsys) == expected
    assert tree(workdir) == before


def test_integers_stay_valid_floats(capsys: pytest.CaptureFixture[str]) -> None:
    assert main(["config", "small", "--set", "domain.width=200", "--set", "insertion.t=1"]) == 0


def test_nothing_placed_is_a_loud_warning(
    workdir: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    argv = ["run", "small", "--set", "domain.width=100", "--set", "domain.height=1"]
    assert main([*argv, "--set", "count=3", "--out", "out", "--quiet"]) == 0
    assert one_line(capsys, "regopack: warning: ") == (
        "no particle was placed: none of the 3 particles drawn fits into the domain; "
        "the packing in out/packing.npz is empty"
    )


def _disk_full(*args: object, **kwargs: object) -> None:
    raise OSError(errno.ENOSPC, os.strerror(errno.ENOSPC), "somewhere")


@pytest.mark.parametrize(
    ("module", "writer", "argv", "out"),
    [
        (
            regopack.run.pipeline,
            "save",
            ["run", "small", "--set", "count=5", "--quiet"],
            "runs/x",
        ),
        (
            regopack.analysis.pipeline,
            "write_json_atomic",
            ["analyze", "packing.npz", "--no-figures"],
            "a",
        ),
    ],
    ids=["run", "analyze"],
)
def test_a_full_disk_is_one_line_and_leaves_nothing(
    workdir: Path,
    capsys: pytest.CaptureFixture[str],
    monkeypatch: pytest.MonkeyPatch,
    module: object,
    writer: str,
    argv: list[str],
    out: str,
) -> None:
    monkeypatch.setattr(module, writer, _disk_full)
    before = tree(workdir)
    assert main([*argv, "--out", out]) == 2
    assert one_line(capsys) == f"cannot write the output folder {out}: No space left on device"
    assert tree(workdir) == before
    assert not any(p.name.startswith(Path(out).name) for p in (workdir / out).parent.iterdir())


BREAK: dict[str, Callable[..., None]] = {
    "nan-centre": lambda p: p.centre.__setitem__((0, 0), np.nan),
    "inf-centre": lambda p: p.centre.__setitem__((1, 1), np.inf),
    "nan-vertex": lambda p: p.vertices.__setitem__((0, 0), np.nan),
    "zero-vertex-particle": lambda p: p.offsets.__setitem__(1, 0),
}
"""Changes in place that make a packing built in Python break the packing format."""


@pytest.mark.parametrize("change", BREAK.values(), ids=list(BREAK))
def test_verify_and_save_refuse_a_broken_packing(
    workdir: Path, change: Callable[..., None]
) -> None:
    packing = packing_from_polygons([SQUARE, [(x + 2, y) for x, y in SQUARE]], (0, 4, 0, 2))
    change(packing)
    with pytest.raises(PackingError) as info:
        verify(packing)
    assert "\n" not in str(info.value) and str(info.value).startswith("array ")
    before = tree(workdir)
    with pytest.raises(PackingError):
        save(packing, workdir / "broken.npz")
    assert tree(workdir) == before


@pytest.mark.parametrize("rel_tol", [-1.0, float("nan"), float("inf")])
def test_verify_refuses_a_bad_tolerance(rel_tol: float) -> None:
    packing = packing_from_polygons([SQUARE], (0, 4, 0, 2))
    with pytest.raises(Exception, match=r"^rel_tol = .*: must be a finite number >= 0$"):
        verify(packing, rel_tol=rel_tol)


@pytest.mark.skipif(not hasattr(os, "mkfifo"), reason="named pipes are POSIX")
@pytest.mark.parametrize(
    ("argv", "expected"),
    [
        (["config", "pipe.toml"], "pipe.toml: is a named pipe (FIFO), not a scene file"),
        (
            ["config", "small", "--set", 'phases.0.shape={kind="template", path="pipe.json"}'],
            "--set: phases.0.shape: pipe.json: is a named pipe (FIFO), not a template file",
        ),
    ],
    ids=["scene", "template"],
)
def test_a_named_pipe_is_refused_without_waiting(
    workdir: Path, capsys: pytest.CaptureFixture[str], argv: list[str], expected: str
) -> None:
    os.mkfifo(workdir / "pipe.toml")
    os.mkfifo(workdir / "pipe.json")
    assert main(argv) == 2
    assert one_line(capsys).startswith(expected)


def test_a_domain_that_holds_no_particle_warns(
    workdir: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    argv = ["run", "small", "--set", 'domain={kind="circle", radius=1}', "--set", "size.d_min=2"]
    assert main([*argv, "--out", "out", "--quiet"]) == 0
    assert one_line(capsys, "regopack: warning: ").startswith(
        "no particle was placed: the scene gives no particle to draw"
    )


def test_a_template_warning_is_one_clean_line(
    workdir: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    (workdir / "l.json").write_text("[[[0, 0], [2, 0], [2, 2], [1, 0.5], [0, 2]]]")
    shape = 'phases.0.shape={kind="template", path="l.json"}'
    assert main(["config", "small", "--set", shape]) == 0
    assert one_line(capsys, "regopack: warning: ") == (
        "l.json: 1 of 1 template outlines were not convex; their convex hulls are used"
    )
