"""Thread settings of worker processes (ttbpipe.threads).

Reference: numba's own rule (numba.core.config): NUMBA_NUM_THREADS is re-read at every
compilation and may not change once the thread pool runs. Each scenario runs in a fresh
interpreter, because the state it sets up cannot be undone in this one.
"""

import os
import subprocess
import sys

# numba imported with two threads, its pool started (single_threaded sets the count), then the
# worker's initializer, then a compilation: what a forked worker of a process pool does.
_SCENARIO = """
import numba
from ttbpipe.threads import single_threaded, WORKER_ENV, apply_worker_environment
with single_threaded():
    pass
{initializer}
@numba.njit
def add_one(x):
    return x + 1
assert add_one(1) == 2
with single_threaded():
    assert numba.get_num_threads() == 1
import os
print(os.environ.get("OPENBLAS_NUM_THREADS"))
"""


def _run(initializer: str) -> subprocess.CompletedProcess:
    env = {k: v for k, v in os.environ.items()
           if k not in ("NUMBA_NUM_THREADS", "OPENBLAS_NUM_THREADS")}
    env["NUMBA_NUM_THREADS"] = "2"
    return subprocess.run([sys.executable, "-c", _SCENARIO.format(initializer=initializer)],
                          env=env, capture_output=True, text=True, timeout=300)


def test_plain_environment_update_after_numba_started_breaks_compilation():
    """The hazard itself: setting the variable in a process whose numba pool runs makes the next
    compilation fail (if numba ever drops the rule, this test says so)."""
    proc = _run("import os; os.environ.update(WORKER_ENV)")
    assert proc.returncode != 0
    assert "Cannot set NUMBA_NUM_THREADS" in proc.stderr


def test_worker_environment_keeps_numba_compiling_and_pins_blas():
    proc = _run("apply_worker_environment()")
    assert proc.returncode == 0, proc.stderr[-2000:]
    assert proc.stdout.split() == ["1"]      # the BLAS variable for libraries loaded later


def test_session_environment_is_set_before_numba_loads():
    """tests/conftest.py: numba sees the worker's thread count (or the caller's) from its import."""
    import numba

    assert numba.config.NUMBA_NUM_THREADS == int(os.environ["NUMBA_NUM_THREADS"])


def test_nested_entries_keep_the_outer_limits_and_scan_once(monkeypatch):
    """A pinned sample calling a pinned run scans the loaded libraries once (threadpoolctl's
    scan reads /proc/self/maps, 1-3 ms), holds one thread in every BLAS/OpenMP pool at every
    depth, and the outer exit restores what was there before. Later entries reuse the scan
    until a module is imported, then scan again."""
    import types

    import threadpoolctl

    from ttbpipe import threads as ttb_threads
    from ttbpipe.threads import SAMPLE_THREADS, single_threaded

    import scipy.linalg  # noqa: F401  (a BLAS library loaded, whatever ran before)

    scans = []
    real = threadpoolctl.ThreadpoolController

    def threads():   # a scan of its own, not counted
        return {lib["filepath"]: lib["num_threads"] for lib in real().info()}

    class Counted(real):
        def __init__(self):
            scans.append(1)
            super().__init__()

    monkeypatch.setattr(ttb_threads, "_CONTROLLER", {})
    with threadpoolctl.threadpool_limits(limits=2):   # so that the restore shows
        before = threads()
        monkeypatch.setattr(threadpoolctl, "ThreadpoolController", Counted)
        with single_threaded():
            assert set(threads().values()) == {SAMPLE_THREADS}
            with single_threaded():
                with single_threaded():
                    assert set(threads().values()) == {SAMPLE_THREADS}
            assert set(threads().values()) == {SAMPLE_THREADS}
        after = threads()
        assert 2 in before.values()
        assert {lib: after[lib] for lib in before} == before
        assert len(scans) == 1
        with single_threaded():   # again after the outer exit: the same libraries, no scan
            assert set(threads().values()) == {SAMPLE_THREADS}
        assert len(scans) == 1
        assert {lib: threads()[lib] for lib in before} == before
        monkeypatch.setitem(sys.modules, "ttbpipe_test_new_module", types.ModuleType("m"))
        with single_threaded():   # a module imported since: scanned again
            assert set(threads().values()) == {SAMPLE_THREADS}
        assert len(scans) == 2
