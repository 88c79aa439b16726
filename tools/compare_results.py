"""Compare two study result folders bit for bit (tools/slurm_check.sh, docs/cluster.md §7).

    python tools/compare_results.py REFERENCE/results OTHER/results \
        [--ignore-config-key simulation.executor ...] [--skip study/report/configuration.html ...]

Every file under the two folders is compared, and both must hold the same files:

* Parquet tables (per-sample batch files, designs, PSDs, TIPM tables, the aggregated study
  tables): the schema (names, types) and every column's values, bit for bit (float columns by
  their bytes, so NaN equals NaN only with the same payload and -0.0 differs from 0.0), and the
  ttbpipe provenance document in the Parquet metadata except ``created_utc`` (the write time) and
  the configuration keys given with ``--ignore-config-key`` (dotted paths: settings that select
  how a run executes, e.g. ``simulation.executor``, and that the batch settings digest excludes).
  Other Parquet metadata (pandas' schema description, Arrow's) is compared as is.
* every other file (JSON repair records, reST/HTML report pages, PNG figures): the bytes;
* except the records of how a job ran rather than what it computed (:data:`RUN_RECORDS`): only
  their listed keys (``study/kernels.json``, the numba compilation run: its code version, not its
  wall time or how many kernels the cache already held).
* ``.snakemake_timestamp`` markers of directory outputs are skipped (their mtime is the content),
  and so are the files given with ``--skip`` (paths relative to the folders, e.g. the report's
  rendering of the configuration when the runs' executors differ); they must still exist in both.

Prints one line per difference and a summary; exit status 1 on any difference.
"""

from __future__ import annotations

import argparse
import json
import sys
from pathlib import Path

import numpy as np
import pyarrow as pa
import pyarrow.parquet as pq

PROVENANCE_KEY = b"ttbpipe"
SKIP_NAMES = {".snakemake_timestamp"}
ALWAYS_IGNORED = ("created_utc",)
#: JSON records of how a job ran (timings, cache state): relative path -> the keys compared.
RUN_RECORDS = {"study/kernels.json": ("code_version",)}


def _provenance_key() -> bytes:
    try:
        from ttbpipe.io import PROVENANCE_KEY as key
    except ImportError:   # the comparison does not need the package
        return PROVENANCE_KEY
    return key.encode() if isinstance(key, str) else key


def _drop(doc: dict, dotted: str) -> None:
    *head, last = dotted.split(".")
    node = doc
    for part in head:
        node = node.get(part) if isinstance(node, dict) else None
        if node is None:
            return
    if isinstance(node, dict):
        node.pop(last, None)


def _provenance(meta: dict, key: bytes, ignore_config: list[str]) -> dict | None:
    if key not in meta:
        return None
    doc = json.loads(meta[key])
    for name in ALWAYS_IGNORED:
        doc.pop(name, None)
    config = doc.get("config")
    if isinstance(config, dict):
        for dotted in ignore_config:
            _drop(config, dotted)
    # provenance documents may embed the configuration of the inputs (batch settings, ...)
    settings = doc.get("settings")
    if isinstance(settings, dict):
        for dotted in ignore_config:
            _drop(settings, dotted)
    return doc


def _column_equal(a: pa.ChunkedArray, b: pa.ChunkedArray) -> bool:
    if a.type != b.type or len(a) != len(b):
        return False
    a, b = a.combine_chunks(), b.combine_chunks()
    if pa.types.is_floating(a.type) or pa.types.is_integer(a.type) or pa.types.is_boolean(a.type):
        if a.null_count != b.null_count or not a.is_null().equals(b.is_null()):
            return False
        x = a.to_numpy(zero_copy_only=False)
        y = b.to_numpy(zero_copy_only=False)
        return x.dtype == y.dtype and np.ascontiguousarray(x).tobytes() == np.ascontiguousarray(y).tobytes()
    return a.equals(b)


def compare_parquet(p: Path, q: Path, ignore_config: list[str]) -> list[str]:
    key = _provenance_key()
    ta, tb = pq.read_table(p), pq.read_table(q)
    out = []
    if ta.schema.remove_metadata() != tb.schema.remove_metadata():
        return [f"schema differs: {ta.schema.remove_metadata()} vs {tb.schema.remove_metadata()}"]
    if ta.num_rows != tb.num_rows:
        return [f"{ta.num_rows} vs {tb.num_rows} rows"]
    for name in ta.column_names:
        if not _column_equal(ta[name], tb[name]):
            out.append(f"column {name!r} differs")
    ma, mb = dict(ta.schema.metadata or {}), dict(tb.schema.metadata or {})
    pa_doc, pb_doc = (_provenance(ma, key, ignore_config), _provenance(mb, key, ignore_config))
    if pa_doc != pb_doc:
        out.append("provenance differs: " + _first_difference(pa_doc, pb_doc))
    for k in sorted(set(ma) | set(mb)):
        if k != key and ma.get(k) != mb.get(k):
            out.append(f"Parquet metadata {k.decode(errors='replace')!r} differs")
    return out


def _first_difference(a, b, path: str = "") -> str:
    if isinstance(a, dict) and isinstance(b, dict):
        for k in sorted(set(a) | set(b)):
            if a.get(k, "<missing>") != b.get(k, "<missing>"):
                return _first_difference(a.get(k, "<missing>"), b.get(k, "<missing>"),
                                         f"{path}.{k}" if path else k)
    return f"{path or '<root>'}: {json.dumps(a)[:200]} vs {json.dumps(b)[:200]}"


def files(root: Path) -> set[str]:
    return {str(p.relative_to(root)) for p in root.rglob("*")
            if p.is_file() and p.name not in SKIP_NAMES}


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("reference", type=Path)
    ap.add_argument("other", type=Path)
    ap.add_argument("--ignore-config-key", action="append", default=[],
                    help="dotted configuration key left out of the provenance comparison")
    ap.add_argument("--skip", action="append", default=[],
                    help="file (relative path) whose content is not compared")
    args = ap.parse_args(argv)
    fa, fb = files(args.reference), files(args.other)
    problems = [f"only in {args.reference}: {n}" for n in sorted(fa - fb)]
    problems += [f"only in {args.other}: {n}" for n in sorted(fb - fa)]
    counts = {"parquet": 0, "other": 0}
    for name in sorted(fa & fb):
        if name in args.skip:
            continue
        p, q = args.reference / name, args.other / name
        if name.endswith(".parquet"):
            counts["parquet"] += 1
            problems += [f"{name}: {d}" for d in compare_parquet(p, q, args.ignore_config_key)]
        elif name in RUN_RECORDS:
            counts["other"] += 1
            ra, rb = json.loads(p.read_text()), json.loads(q.read_text())
            problems += [f"{name}: {k} {ra.get(k)!r} != {rb.get(k)!r}"
                         for k in RUN_RECORDS[name] if ra.get(k) != rb.get(k)]
        else:
            counts["other"] += 1
            if p.read_bytes() != q.read_bytes():
                problems.append(f"{name}: bytes differ")
    for line in problems:
        print(f"DIFF {line}")
    print(f"compare_results: {args.reference} vs {args.other}: {counts['parquet']} Parquet tables "
          f"and {counts['other']} other files compared, {len(problems)} differences "
          f"(ignored: provenance {', '.join(ALWAYS_IGNORED)}"
          + (f"; config {', '.join(args.ignore_config_key)}" if args.ignore_config_key else "")
          + (f"; content of {', '.join(args.skip)}" if args.skip else "")
          + f"; of {', '.join(RUN_RECORDS)} all but {', '.join(sorted({k for v in RUN_RECORDS.values() for k in v}))}"
          + ")")
    return 1 if problems else 0


if __name__ == "__main__":
    sys.exit(main())
