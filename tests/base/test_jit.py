"""The kernel cache folder follows the kernel sources."""

from __future__ import annotations

from pathlib import Path

import pytest

from regopack.base import jit


def test_cache_folder_changes_with_the_sources(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    src = tmp_path / "kernel.py"
    src.write_text("x = 1\n")
    monkeypatch.setattr(jit, "_sources", lambda: [src])
    monkeypatch.setenv("XDG_CACHE_HOME", str(tmp_path / "cache"))
    first = jit.kernel_cache_dir()
    assert first.parent == tmp_path / "cache" / "regopack" / "numba"
    assert jit.kernel_cache_dir() == first
    src.write_text("x = 2\n")
    assert jit.kernel_cache_dir() != first


def test_a_folder_chosen_by_the_user_is_kept(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    monkeypatch.setenv("NUMBA_CACHE_DIR", str(tmp_path / "mine"))
    jit.configure_cache()
    import os

    assert os.environ["NUMBA_CACHE_DIR"] == str(tmp_path / "mine")


def test_sources_are_the_plugin_modules() -> None:
    names = {p.name for p in jit._sources()}
    assert {"kernel.py", "geometry.py", "octagon.py", "contact_kernel.py"} <= names


def test_the_kernel_packages_come_from_the_distribution_metadata() -> None:
    from importlib import metadata

    values = {e.value for e in metadata.entry_points(group=jit.KERNEL_SOURCES_GROUP)}
    assert "regopack.plugins" in values
    assert jit._names() == ["regopack.plugins"]


def test_the_cache_key_is_found_without_importing_a_plugin() -> None:
    import subprocess
    import sys

    code = (
        "import sys, regopack.base.jit as jit; "
        "assert jit._sources(); "
        "assert not [m for m in sys.modules if m.startswith('regopack.plugins')], sys.modules"
    )
    subprocess.run([sys.executable, "-c", code], check=True)


def test_an_unknown_kernel_package_adds_no_sources(monkeypatch: pytest.MonkeyPatch) -> None:
    assert jit._source_files("regopack_no_such_package") == []


def test_a_one_file_module_is_hashed_too() -> None:
    files = jit._source_files("regopack.base.jit")
    assert [p.name for p in files] == ["jit.py"]


def test_third_party_kernel_modules_change_the_key(tmp_path, monkeypatch) -> None:
    """A package and a one-file module named in the entry points, with the ``module:attr`` form."""
    import sys
    from importlib import metadata

    (tmp_path / "kpkg").mkdir()
    (tmp_path / "kpkg" / "__init__.py").write_text("X = 1\n")
    (tmp_path / "single.py").write_text("Y = 1\n")
    monkeypatch.syspath_prepend(str(tmp_path))
    entries = [
        metadata.EntryPoint("a", "kpkg:plugin", jit.KERNEL_SOURCES_GROUP),
        metadata.EntryPoint("b", "single", jit.KERNEL_SOURCES_GROUP),
    ]
    real = metadata.entry_points
    monkeypatch.setattr(
        metadata,
        "entry_points",
        lambda group=None, **kw: (
            entries if group == jit.KERNEL_SOURCES_GROUP else real(group=group, **kw)
        ),
    )
    monkeypatch.setenv("XDG_CACHE_HOME", str(tmp_path / "cache"))
    first = jit.kernel_cache_dir()
    (tmp_path / "single.py").write_text("Y = 2\n")
    second = jit.kernel_cache_dir()
    (tmp_path / "kpkg" / "__init__.py").write_text("X = 2\n")
    third = jit.kernel_cache_dir()
    assert len({first, second, third}) == 3
    assert "kpkg" not in sys.modules and "single" not in sys.modules


def test_kernel_threads_sleep_while_they_wait_unless_the_user_chose(
    monkeypatch: pytest.MonkeyPatch,
) -> None:
    import os

    monkeypatch.delenv("OMP_WAIT_POLICY", raising=False)
    jit.configure_threads()
    assert os.environ["OMP_WAIT_POLICY"] == "PASSIVE"
    monkeypatch.setenv("OMP_WAIT_POLICY", "ACTIVE")
    jit.configure_threads()
    assert os.environ["OMP_WAIT_POLICY"] == "ACTIVE"


def test_cache_saves_hold_a_lock_and_keep_every_entry(tmp_path) -> None:
    # two processes that save signatures of one function at once could otherwise
    # give both the same data file (regopack.base.jit.lock_cache_saves)
    import multiprocessing

    from numba.core import caching

    import regopack.base.jit  # noqa: F401

    pytest.importorskip("fcntl")  # the lock is taken on POSIX systems only

    assert getattr(caching.IndexDataCacheFile.save, "regopack_locked", False)
    ctx = multiprocessing.get_context("fork")
    procs = [ctx.Process(target=_save_entries, args=(str(tmp_path), k)) for k in range(4)]
    for proc in procs:
        proc.start()
    for proc in procs:
        proc.join(60)
        assert proc.exitcode == 0
    cache = caching.IndexDataCacheFile(str(tmp_path), "f", ("stamp", 1))
    for k in range(4):
        for j in range(25):
            assert cache.load(("key", k, j)) == ("data", k, j)
    assert (tmp_path / "f.nbi.lock").exists()


def _save_entries(folder: str, k: int) -> None:
    from numba.core import caching

    cache = caching.IndexDataCacheFile(folder, "f", ("stamp", 1))
    for j in range(25):
        cache.save(("key", k, j), ("data", k, j))


# ---------------------------------------------------------------------------
# the threading layer


def _child_env(**extra: str) -> dict[str, str]:
    import os

    env = {k: v for k, v in os.environ.items() if not k.startswith("NUMBA_THREADING_LAYER")}
    env.update(NUMBA_NUM_THREADS="2", **extra)
    return env


def _python(code: str, env: dict[str, str], timeout: float = 300.0) -> str:
    import subprocess
    import sys

    done = subprocess.run(
        [sys.executable, "-c", code], env=env, capture_output=True, text=True, timeout=timeout
    )
    assert done.returncode == 0, done.stderr[-2000:]
    return done.stdout


def _tbb_loads() -> bool:
    code = "from numba.np.ufunc import parallel; parallel._check_tbb_version_compatible();"
    code += "from numba.np.ufunc import tbbpool"
    try:
        _python(code, _child_env(), timeout=60.0)
    except AssertionError:
        return False
    return True


LAYER = (
    "import numba, numpy as np\n"
    "@numba.njit(parallel=True)\n"
    "def total(a):\n"
    "    s = 0.0\n"
    "    for i in numba.prange(a.shape[0]):\n"
    "        s += a[i]\n"
    "    return s\n"
    "total(np.ones(1000))\n"
    "print(numba.threading_layer())\n"
)


TINY = "regopack.pack('dem', domain__width=120, domain__height=120, insertion__strip=120)\n"


def test_regopack_prefers_openmp_then_the_workqueue_to_tbb() -> None:
    code = "import regopack, numba, os\n" + TINY
    code += "print(numba.threading_layer(), os.environ.get('NUMBA_THREADING_LAYER_PRIORITY'))\n"
    layer, env = _python(code, _child_env()).split()
    assert layer in {"omp", "workqueue"}
    assert env == "None"  # set in this process's numba only: its children keep numba's order


def test_a_threading_layer_chosen_by_the_user_is_kept() -> None:
    check = TINY + "import numba; print(numba.threading_layer())\n"
    env = _child_env(NUMBA_THREADING_LAYER="workqueue")
    assert _python("import regopack\n" + check, env).strip() == "workqueue"
    env = _child_env(NUMBA_THREADING_LAYER_PRIORITY="workqueue omp tbb")
    assert _python("import regopack\n" + check, env).strip() == "workqueue"
    # numba's documented way in code, before or after importing regopack
    code = "import numba\nnumba.config.THREADING_LAYER = 'workqueue'\nimport regopack\n" + check
    assert _python(code, _child_env()).strip() == "workqueue"
    code = "import regopack, numba\nnumba.config.THREADING_LAYER = 'workqueue'\n" + check
    assert _python(code, _child_env()).strip() == "workqueue"


PACK_AND_ANALYSE = """
import threading, numba, regopack
from regopack.plugins.inserters.available_arc import batches
from regopack.plugins.inserters.available_arc import sweep
def work(out):
    # the sweep's exact scans run on two threads (a parallel kernel)
    p = regopack.pack("dem", domain__width=160, domain__height=160,
                      insertion__strip=160, seed=SEED)
    r = regopack.analyze(p, ["contacts", "coordination"])
    out.append((p.n_placed, sorted(r["contacts"].scalars.items())))
mine = []
t = threading.Thread(target=work, args=(mine,))   # as a Dask worker thread does
t.start(); t.join()
work(mine)
assert mine[0] == mine[1], mine
layer = numba.threading_layer()
print("last line", layer, flush=True)
"""


@pytest.mark.skipif(not _tbb_loads(), reason="numba finds no TBB here (pip install tbb)")
@pytest.mark.parametrize(
    "pairs", [1, pytest.param(5, marks=pytest.mark.slow, id="ten")], ids=lambda v: str(v)
)
def test_processes_with_tbb_present_exit_after_their_last_line(tmp_path: Path, pairs: int) -> None:
    """With TBB installed, packing and analysing from threads never hangs a process at exit.

    Two processes in the default run, ten with ``-m slow`` (a hang that
    comes one time in several).
    """
    import subprocess
    import sys
    import time

    def start(seed: int) -> subprocess.Popen[str]:
        code = PACK_AND_ANALYSE.replace("SEED", str(seed))
        return subprocess.Popen(
            [sys.executable, "-c", code],
            env=_child_env(),
            stdout=subprocess.PIPE,
            stderr=subprocess.PIPE,
            text=True,
        )

    lags = []
    for pair in range(pairs):  # two at a time, one per core
        procs = [start(2 * pair + k + 1) for k in range(2)]
        for proc in procs:
            assert proc.stdout is not None
            line = proc.stdout.readline()
            last = time.monotonic()
            try:
                code = proc.wait(timeout=60.0)
            except subprocess.TimeoutExpired:
                proc.kill()
                pytest.fail(f"a process still ran 60 s after its last line {line!r}")
            lags.append(time.monotonic() - last)
            assert code == 0, proc.stderr.read()[-2000:] if proc.stderr else code
            assert line.split()[:2] == ["last", "line"]
            assert line.split()[2] in {"omp", "workqueue"}
    assert max(lags) < 10.0, lags


@pytest.mark.skipif(not hasattr(__import__("os"), "fork"), reason="no fork here")
def test_a_child_forked_after_the_parallel_kernels_ran_packs_the_same() -> None:
    """In the child, from the forking thread and from a new one (as a thread pool would)."""
    code = """
import os, threading, numba, regopack
def key():
    p = regopack.pack("dem", domain__width=160, domain__height=160, insertion__strip=160)
    return p.centre.tobytes()
first = key()
pid = os.fork()
if pid == 0:
    out = []
    t = threading.Thread(target=lambda: out.append(key()))
    t.start(); t.join()
    os._exit(0 if key() == first and out == [first] else 3)
_, status = os.waitpid(pid, 0)
print(numba.threading_layer(), os.waitstatus_to_exitcode(status))
"""
    out = _python(code, _child_env()).split()
    assert out[1] == "0", out
