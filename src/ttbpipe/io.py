"""Table and file input/output with provenance and atomic writes.

Every table ttbpipe writes goes through :func:`write_table`, which

* writes to a temporary file in the destination folder and renames it into place, so that an
  interrupted job never leaves a partial output behind;
* stores, in the Parquet schema metadata under the key ``ttbpipe``, a JSON document with the
  ttbpipe version, the resolved configuration that produced the table, the table's kind and any
  extra fields the caller passes.

:func:`read_provenance` reads that document back; :func:`jsonable` makes numpy values and paths
JSON-ready (for the provenance, the cleaning reports and every other JSON or YAML output).
"""

from __future__ import annotations

import contextlib
import datetime as _dt
import json
import math
import os
import tempfile
from pathlib import Path
from typing import Any, Iterator, Mapping

import numpy as np
import pandas as pd
import pyarrow as pa
import pyarrow.parquet as pq

from . import __version__, code_version

PROVENANCE_KEY = b"ttbpipe"


def jsonable(obj: Any, *, nan_as_none: bool = False) -> Any:
    """``obj`` with numpy scalars and arrays, paths and tuples made plain Python values, so that
    ``json.dumps`` (and ``yaml.safe_dump``) accept it.

    Mappings become dicts with string keys, lists and tuples lists, numpy arrays nested lists,
    numpy scalars Python scalars, paths strings; other values are returned unchanged. With
    ``nan_as_none``, non-finite floats become ``None`` (JSON has no NaN or infinity: strict
    readers reject ``json.dumps``'s ``NaN``); without, they stay floats (the provenance keeps them).
    """
    if isinstance(obj, Mapping):
        return {str(k): jsonable(v, nan_as_none=nan_as_none) for k, v in obj.items()}
    if isinstance(obj, (list, tuple)):
        return [jsonable(v, nan_as_none=nan_as_none) for v in obj]
    if isinstance(obj, np.ndarray):
        return jsonable(obj.tolist(), nan_as_none=True) if nan_as_none else obj.tolist()
    if isinstance(obj, np.generic):
        obj = obj.item()
    if isinstance(obj, Path):
        return str(obj)
    if nan_as_none and isinstance(obj, float) and not math.isfinite(obj):
        return None
    return obj


def provenance(config: Mapping[str, Any] | None = None, kind: str | None = None,
               **extra: Any) -> dict[str, Any]:
    """Return the provenance document stored with every table."""
    doc: dict[str, Any] = {
        "ttbpipe_version": __version__,
        "code_version": code_version(),
        "created_utc": _dt.datetime.now(_dt.timezone.utc).isoformat(timespec="seconds"),
        "kind": kind,
        "config": jsonable(dict(config)) if config is not None else None,
    }
    doc.update(jsonable(extra))
    return doc


@contextlib.contextmanager
def atomic_path(path: str | os.PathLike[str]) -> Iterator[Path]:
    """Yield a temporary path beside ``path``; rename it onto ``path`` only on success.

    The temporary file lives in the destination folder so that the final ``os.replace`` is an
    atomic rename on the same file system. On any exception the temporary file is removed and the
    destination is left untouched.
    """
    path = Path(path)
    path.parent.mkdir(parents=True, exist_ok=True)
    fd, tmp_name = tempfile.mkstemp(prefix=f".{path.name}.", suffix=".tmp", dir=path.parent)
    os.close(fd)
    tmp = Path(tmp_name)
    try:
        yield tmp
        # mkstemp creates the file private (0600); give the output ordinary permissions.
        umask = os.umask(0)
        os.umask(umask)
        os.chmod(tmp, 0o666 & ~umask)
        os.replace(tmp, path)
    except BaseException:
        with contextlib.suppress(FileNotFoundError):
            tmp.unlink()
        raise


def write_table(df: pd.DataFrame, path: str | os.PathLike[str], *,
                config: Mapping[str, Any] | None = None, kind: str | None = None,
                row_group_size: int | None = None, **extra: Any) -> Path:
    """Write ``df`` to Parquet atomically, with the provenance document in its metadata
    (``row_group_size``: rows per row group, pyarrow's default when None)."""
    table = pa.Table.from_pandas(df, preserve_index=False)
    meta = dict(table.schema.metadata or {})
    meta[PROVENANCE_KEY] = json.dumps(provenance(config, kind, **extra)).encode()
    table = table.replace_schema_metadata(meta)
    path = Path(path)
    with atomic_path(path) as tmp:
        pq.write_table(table, tmp, row_group_size=row_group_size)
    return path


def read_table(path: str | os.PathLike[str]) -> pd.DataFrame:
    """Read a Parquet table written by :func:`write_table`."""
    return pq.read_table(path).to_pandas()


def read_provenance(path: str | os.PathLike[str]) -> dict[str, Any]:
    """Return the provenance document of a table written by :func:`write_table`."""
    meta = pq.read_schema(path).metadata or {}
    if PROVENANCE_KEY not in meta:
        raise KeyError(f"{path}: no ttbpipe provenance in the Parquet metadata")
    return json.loads(meta[PROVENANCE_KEY])


def write_text(text: str, path: str | os.PathLike[str]) -> Path:
    """Write a text file atomically."""
    path = Path(path)
    with atomic_path(path) as tmp:
        tmp.write_text(text)
    return path


def save_figure(fig: Any, path: str | os.PathLike[str], **kwargs: Any) -> Path:
    """Save a matplotlib figure atomically (format from the destination's suffix).

    A figure without a layout engine is cropped to its drawn content (``bbox_inches="tight"``);
    one laid out by constrained layout already fits its canvas, and cropping it would draw it a
    second time (a third of the study figures' rendering time)."""
    path = Path(path)
    kwargs.setdefault("dpi", 150)
    if fig.get_layout_engine() is None:
        kwargs.setdefault("bbox_inches", "tight")
    with atomic_path(path) as tmp:
        fig.savefig(tmp, format=path.suffix.lstrip(".") or "png", **kwargs)
    return path
