"""The kernel cache is emptied when the package's code changes (ttbpipe.kernel_cache)."""

from __future__ import annotations

from pathlib import Path

from ttbpipe.kernel_cache import STAMP_NAME, cache_dirs, refresh


def _fake_package(root: Path, caches: list[Path] | None = None) -> list[Path]:
    files = []
    for k, sub in enumerate(("", "simulation", "vehicle")):
        (root / sub).mkdir(parents=True, exist_ok=True)
        (root / sub / "mod.py").write_text("")
        cache = root / sub / "__pycache__" if caches is None else caches[k]
        cache.mkdir(parents=True, exist_ok=True)
        for name in ("kern-12.py311.nbi", "kern-12.py311.1.nbc"):
            (cache / name).write_bytes(b"x")
            files.append(cache / name)
        (cache / "mod.cpython-311.pyc").write_bytes(b"x")
    return files


def test_changed_code_removes_cached_kernels_and_records_the_digest(tmp_path, monkeypatch):
    monkeypatch.delenv("NUMBA_CACHE_DIR", raising=False)
    files = _fake_package(tmp_path)
    assert refresh(tmp_path, current="1.0+aaa") == 6      # no stamp yet: the cache is unknown
    assert not any(f.exists() for f in files)
    assert (tmp_path / "vehicle" / "__pycache__" / "mod.cpython-311.pyc").exists()
    assert (tmp_path / "__pycache__" / STAMP_NAME).read_text() == "1.0+aaa"
    files = _fake_package(tmp_path)
    assert refresh(tmp_path, current="1.0+aaa") == 0      # same code: kept
    assert all(f.exists() for f in files)
    assert refresh(tmp_path, current="1.0+bbb") == 6      # changed code: removed
    assert not any(f.exists() for f in files)


def test_user_cache_directory_as_numba_names_it(tmp_path, monkeypatch):
    """Under NUMBA_CACHE_DIR numba caches a source folder's kernels in <name>_<sha1 of its
    absolute path> (numba.core.caching.get_suitable_cache_subpath)."""
    package = tmp_path / "site" / "ttbpipe"
    monkeypatch.setenv("NUMBA_CACHE_DIR", str(tmp_path / "numba"))
    _fake_package(package)
    dirs = cache_dirs(package)
    from numba.core.caching import _CacheLocator

    subpath = _CacheLocator.get_suitable_cache_subpath(str(package / "vehicle" / "mod.py"))
    assert dirs[2] == tmp_path / "numba" / subpath
    files = _fake_package(package, dirs)
    assert refresh(package, current="1.0+ccc") == 6
    assert not any(f.exists() for f in files)
