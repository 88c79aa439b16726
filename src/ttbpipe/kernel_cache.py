"""numba's on-disk cache of ttbpipe's kernels, kept in step with the code.

numba keys a cached kernel on the time stamp of its own source file only: a kernel that calls a
kernel of another module, or reads a constant from one, keeps the old machine code after that
module changes ("Cache invalidation fails to recognize changes in symbols defined in a different
file. Global variables are treated as constants", numba documentation, "Cache" notes; numba
issues #1833, #9483). A checkout that changes ``vehicle/contact.py`` but not
``vehicle/dynamics.py`` would run stale code -- with a changed array-size constant, writes past
the end of an array. So on import ttbpipe compares the digest of its code
(:func:`ttbpipe.code_version`) with the one its kernel cache was built from and, when they
differ, removes the cached kernels (numba compiles them again on first use) and records the new
digest.

The cache lies next to the sources (``__pycache__``), or under ``NUMBA_CACHE_DIR`` when that is
set (:func:`cache_dirs`). A fresh installation changes every file's time stamp
and needs none of this; a development checkout does.
"""

from __future__ import annotations

import hashlib
import logging
import os
from pathlib import Path

log = logging.getLogger(__name__)

#: Name of the file, in the cache's top folder, holding the code digest the cache belongs to.
STAMP_NAME = "numba_kernels.code_version"
CACHE_SUFFIXES = (".nbi", ".nbc")


def cache_dirs(package_root: Path) -> list[Path]:
    """Where numba caches the kernels of each folder of the package, the package's own first:
    ``__pycache__`` next to the sources, or under ``NUMBA_CACHE_DIR`` the folder's name and the
    SHA-1 of its absolute path (numba.core.caching, ``get_suitable_cache_subpath``)."""
    folders = [package_root] + sorted(p for p in package_root.rglob("*")
                                      if p.is_dir() and p.name != "__pycache__"
                                      and "__pycache__" not in p.parts and any(p.glob("*.py")))
    user_dir = os.environ.get("NUMBA_CACHE_DIR")
    if user_dir:
        out = []
        for folder in folders:
            path = os.path.abspath(str(folder))
            digest = hashlib.sha1(path.encode()).hexdigest()
            out.append(Path(user_dir) / f"{os.path.split(path)[-1]}_{digest}")
        return out
    return [folder / "__pycache__" for folder in folders]


def refresh(package_root: Path | None = None, current: str | None = None) -> int:
    """Remove the cached kernels of ``package_root`` (default: ttbpipe's folder) when they were
    built from other code than ``current`` (default: :func:`ttbpipe.code_version`); returns how
    many cache files were removed. File errors (a read-only installation) are ignored: then
    nothing can be stale that a reinstallation did not already invalidate."""
    from . import code_version

    package_root = Path(__file__).resolve().parent if package_root is None else package_root
    current = code_version() if current is None else current
    dirs = cache_dirs(package_root)
    stamp = dirs[0] / STAMP_NAME
    try:
        if stamp.read_text() == current:
            return 0
    except OSError:
        pass
    removed = 0
    for folder in dirs:
        for path in (folder.iterdir() if folder.is_dir() else ()):
            if path.suffix in CACHE_SUFFIXES:
                try:
                    path.unlink()
                    removed += 1
                except OSError:
                    pass
    try:
        stamp.parent.mkdir(parents=True, exist_ok=True)
        tmp = stamp.with_name(f"{STAMP_NAME}.{os.getpid()}.tmp")
        tmp.write_text(current)
        os.replace(tmp, stamp)
    except OSError:
        pass
    if removed:
        log.info("ttbpipe's code changed since its kernels were cached: %d cached kernel files "
                 "removed (numba compiles them again on first use)", removed)
    return removed
