"""Where the coupled loop's step goes: the loop with one part left out at a time.

    NUMBA_NUM_THREADS=1 python benchmarks/loop_ablation.py [--case config/reference_case.yaml]
        [--duration 0.5] [--rounds 4]

A copy of the single-train loop (:func:`ttbpipe.simulation.loop._coupled_loop`, without its
checks and stops) that can leave out the structure kernel, the monitors, the decimated history
channels or the structure's Zhai update; the variants run alternately in one process and the
wall time per step of each is printed (median and minimum over the rounds after the first).
A part's cost in the loop is the difference to the full variant: it includes the cache misses
the part causes the others, which timing it alone in a warm loop does not show. Timings only;
the left-out variants do not compute the same motion.
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

from ttbpipe.jit import KERNEL_OPTIONS  # noqa: E402
from ttbpipe.simulation import loop as L  # noqa: E402
from ttbpipe.simulation.coupled import prepare  # noqa: E402
from ttbpipe.simulation.recorder import (record_step_channels, record_vehicle_output,  # noqa: E402
                                         record_wheel_output, record_wheel_step)
from ttbpipe.structure.kernels import windowed_structure_accelerations  # noqa: E402
from ttbpipe.structure.monitors import record_monitors  # noqa: E402
from ttbpipe.structure.window import no_window  # noqa: E402
from ttbpipe.vehicle.contact import N_COLS  # noqa: E402
from ttbpipe.vehicle.dynamics import _work  # noqa: E402
from ttbpipe.vehicle.kernels import RAIL_KIN_COLS  # noqa: E402

ROOT = Path(__file__).resolve().parents[1]
VARIANTS = {0: "full", 1: "no structure kernel", 2: "no monitors", 3: "no decimated channels",
            4: "no structure update"}


# compiled as the loop it copies is (not cached: a benchmark)
@njit(error_model=KERNEL_OPTIONS["error_model"])
def loop(state, placed, packed, window, mesh, monitors, train, dt, n_steps, out_every, mode):
    """The coupled loop's step, leaving out the part ``mode`` names (:data:`VARIANTS`)."""
    vehicle = placed.vehicle
    n_ws = vehicle.ws_dofs.shape[0]
    ws_x = np.zeros(n_ws)
    rail_kin = np.zeros((n_ws, 2, RAIL_KIN_COLS))
    work = _work(state.q.shape[0], n_ws, N_COLS, max(vehicle.zones.shape[0], 1))
    q, v, a, a_prev = state.q, state.v, state.a, state.a_prev
    disp, vel, acc, acc_prev = state.disp, state.vel, state.acc, state.acc_prev
    L._evaluate(0.0, state, placed, work, packed, window, mesh, ws_x, rail_kin, True)
    out_row = 0
    for n in range(n_steps):
        psi = 0.0 if n == 0 else 0.5
        L._advance(q, v, a, a_prev, dt, psi)
        if mode != 4:
            L._advance(disp, vel, acc, acc_prev, dt, psi)
        t = (n + 1) * dt
        nf = state.nodal_force
        for i in range(nf.shape[0]):
            nf[i] = 0.0
        L._train_loads(t, state, placed, work, mesh, ws_x, rail_kin, False)
        if mode != 1:
            windowed_structure_accelerations(packed, window, disp, vel, nf, acc)
        step = n + 1
        record_wheel_step(train, work.wheel, step)
        if mode != 2:
            record_monitors(monitors, disp, vel, acc)
        if mode != 3:
            record_step_channels(train, monitors.current, work.wheel, q, a)
        if step % out_every == 0 and out_row < train.t_out.shape[0]:
            record_vehicle_output(train, out_row, step * dt, q, a)
            record_wheel_output(train, out_row, work.wheel)
            out_row += 1
    return 0


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--case", default=str(ROOT / "config" / "reference_case.yaml"))
    parser.add_argument("--duration", type=float, default=0.5)
    parser.add_argument("--rounds", type=int, default=4)
    args = parser.parse_args()
    case = yaml.safe_load(Path(args.case).read_text())
    case["simulation"]["duration_s"] = args.duration
    setup = prepare(case)
    res = {k: [] for k in VARIANTS}
    for rnd in range(args.rounds):
        for mode in VARIANTS:
            n_v, n_s = setup.model.n_dof, setup.disp0.shape[0]
            state = L.CoupledState(setup.q0.copy(), setup.v0.copy(), np.zeros(n_v), np.zeros(n_v),
                                   setup.disp0.copy(), np.zeros(n_s), np.zeros(n_s),
                                   np.zeros(n_s), np.zeros(n_s))
            mon = setup.monitors.recorder()
            train = L._recorder(setup, mon.qty.shape[0])
            t0 = time.perf_counter()
            loop(state, L._placed(setup), setup.packed, no_window(setup.packed), setup.mesh, mon,
                 train, setup.dt, setup.n_steps, setup.out_every, mode)
            if rnd > 0:             # the first round compiles
                res[mode].append((time.perf_counter() - t0) / setup.n_steps * 1e6)
    print(f"case {args.case}: {setup.n_steps} steps, load {os.getloadavg()[0]:.1f}")
    full = np.median(res[0])
    for mode, name in VARIANTS.items():
        med = np.median(res[mode])
        print(f"{name:24s} {med:6.1f} us per step (min {min(res[mode]):6.1f}); "
              f"the part left out: {full - med:6.1f} us")


if __name__ == "__main__":
    main()
