"""The structure kernel with its coefficient arrays in single precision: is it bandwidth-bound?

    NUMBA_NUM_THREADS=1 python benchmarks/structure_kernel_precision.py [--case config/reference_case.yaml]
        [--calls 2000] [--rounds 7]

The reference case's packed structure (``ttbpipe.structure.kernels.StructurePacked``, about
0.7 MiB of arrays beside the 9 182-DOF state) is timed in ``structure_accelerations`` as built
(float64 coefficients, int64 indices) and with copies of its arrays narrowed: the CA triples'
coefficients to float32 (the largest array, 136 KiB), those and their DOF indices to int32, and
every coefficient and index array of the beams, pads, links and span blocks. The state stays
float64 (the explicit integration needs it). The variants alternate in one process; the script
prints each one's median and minimum time per call and the largest difference of its
accelerations from the float64 kernel's, relative to their peak. Timings only.
"""

from __future__ import annotations

import argparse
import os
import time
from pathlib import Path

os.environ.setdefault("NUMBA_NUM_THREADS", "1")

import numpy as np  # noqa: E402
import yaml  # noqa: E402
from numba import njit  # noqa: E402

from ttbpipe.simulation.coupled import prepare  # noqa: E402
from ttbpipe.structure.kernels import structure_accelerations  # noqa: E402

ROOT = Path(__file__).resolve().parents[1]
#: Coefficient and index arrays narrowed in the last variant.
FLOAT_ARRAYS = ("tri_kernel_coef", "pad_k", "pad_c", "pad_geom", "span_K", "span_C", "span_Minv",
                "beam_L", "beam_EIv", "beam_EIl", "beam_GK", "link_coef", "link_k", "link_c")
INDEX_ARRAYS = ("tri_kernel_dof", "pad_rail", "pad_seat_a", "pad_seat_b", "beam_dof_a",
                "beam_dof_b", "link_dof")


@njit
def _repeat(packed, disp, vel, nodal_force, acc, calls):
    for _ in range(calls):
        structure_accelerations(packed, disp, vel, nodal_force, acc)


def variants(packed):
    """{figure name: packed structure} of the precisions compared (module docstring); the
    first is the structure as built."""
    narrow = lambda names, dtype: {k: getattr(packed, k).astype(dtype) for k in names}  # noqa: E731
    return {
        "float64": packed,
        "ca_coef_float32": packed._replace(**narrow(["tri_kernel_coef"], np.float32)),
        "ca_coef_float32_dof_int32": packed._replace(**narrow(["tri_kernel_coef"], np.float32),
                                                     **narrow(["tri_kernel_dof"], np.int32)),
        "all_coef_float32_index_int32": packed._replace(**narrow(FLOAT_ARRAYS, np.float32),
                                                        **narrow(INDEX_ARRAYS, np.int32)),
    }


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--case", default=str(ROOT / "config" / "reference_case.yaml"))
    parser.add_argument("--calls", type=int, default=2000)
    parser.add_argument("--rounds", type=int, default=7)
    args = parser.parse_args()
    case = yaml.safe_load(Path(args.case).read_text())
    case["simulation"]["duration_s"] = 0.01
    setup = prepare(case)
    n = setup.packed.n_dof
    rng = np.random.default_rng(0)
    disp = setup.disp0 + 1e-5 * rng.standard_normal(n)   # a moving state, not the static one
    vel = 1e-3 * rng.standard_normal(n)
    nodal_force = np.zeros(n)
    cases = variants(setup.packed)
    acc = {}
    for name, packed in cases.items():              # compiles each variant
        acc[name] = np.zeros(n)
        _repeat(packed, disp, vel, nodal_force, acc[name], 1)
    times = {name: [] for name in cases}
    for _ in range(args.rounds):
        for name, packed in cases.items():
            out = np.zeros(n)
            t0 = time.perf_counter()
            _repeat(packed, disp, vel, nodal_force, out, args.calls)
            times[name].append((time.perf_counter() - t0) / args.calls * 1e6)
    ref = acc["float64"]
    print(f"case {args.case}: {n} DOF, {args.rounds} rounds of {args.calls} calls, "
          f"load {os.getloadavg()[0]:.1f}")
    for name in cases:
        diff = np.max(np.abs(acc[name] - ref)) / np.max(np.abs(ref))
        print(f"{name:30s} median {np.median(times[name]):6.2f} us  min {min(times[name]):6.2f} us"
              f"  accelerations off by {diff:.1e} of their peak")
        print(f"FIGURE structure_kernel_{name}_us = {np.median(times[name]):.4g} us")


if __name__ == "__main__":
    main()
