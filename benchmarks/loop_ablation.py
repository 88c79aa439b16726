"""Where the coupled loop's step goes: the loop with one part left out at a time.

    NUMBA_NUM_THREADS=1 python benchmarks/loop_ablation.py [--case config/reference_case.yaml]
        [--duration 0.5] [--rounds 4]

A copy of the single-train loop (:func:`ttbpipe.simulation.loop._coupled_loop`) that can leave
out the structure kernel, the monitors, the decimated history channels, the structure's Zhai
update, the wheel-step records (peaks, contact loss) or the sampled output rows; the variants
run alternately in one process and the wall time per step of each is printed (median and
minimum over the rounds after the first). A part's cost in the loop is the difference to the
full variant: it includes the cache misses the part causes the others, which timing it alone in
a warm loop does not show. The left-out variants do not compute the same motion; the full
variant must: before timing, the script runs the case through both loops and stops unless
every output array and the final state are equal bit for bit (a copy that drifted from the loop
it copies would time another loop).
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

from ttbpipe.decimation import flush  # noqa: E402
from ttbpipe.jit import KERNEL_OPTIONS  # noqa: E402
from ttbpipe.simulation import loop as L  # noqa: E402
from ttbpipe.simulation.coupled import prepare  # noqa: E402
from ttbpipe.simulation.recorder import (record_step_channels, record_vehicle_output,  # noqa: E402
                                         record_wheel_output, record_wheel_step)
from ttbpipe.structure.kernels import windowed_accelerations_in_place  # noqa: E402
from ttbpipe.structure.monitors import record_monitors  # noqa: E402
from ttbpipe.structure.window import clear_moving, no_window  # noqa: E402
from ttbpipe.vehicle.contact import N_COLS  # noqa: E402
from ttbpipe.vehicle.dynamics import _work  # noqa: E402
from ttbpipe.vehicle.kernels import RAIL_KIN_COLS  # noqa: E402

ROOT = Path(__file__).resolve().parents[1]
VARIANTS = {0: "full", 1: "no structure kernel", 2: "no monitors", 3: "no decimated channels",
            4: "no structure update", 5: "no wheel-step records", 6: "no output rows"}


# compiled as the loop it copies is (not cached: a benchmark)
@njit(error_model=KERNEL_OPTIONS["error_model"])
def loop(state, placed, packed, window, mesh, monitors, train, dt, n_steps, out_every, mode):
    """The coupled loop's step (:func:`ttbpipe.simulation.loop._coupled_loop`, its statuses and
    stops included), leaving out the part ``mode`` names (:data:`VARIANTS`); mode 0 is the loop."""
    vehicle = placed.vehicle
    n_ws = vehicle.ws_dofs.shape[0]
    ws_x = np.zeros(n_ws)
    rail_kin = np.zeros((n_ws, 2, RAIL_KIN_COLS))
    work = _work(state.q.shape[0], n_ws, N_COLS, max(vehicle.zones.shape[0], 1))
    q, v, a, a_prev = state.q, state.v, state.a, state.a_prev
    disp, vel, acc, acc_prev = state.disp, state.vel, state.acc, state.acc_prev
    L._evaluate(0.0, state, placed, work, packed, window, mesh, ws_x, rail_kin, 0.0)
    out_row = np.int64(0)
    for n in range(-1, n_steps):
        if n >= 0:
            psi = 0.0 if n == 0 else 0.5
            L._advance(q, v, a, a_prev, dt, psi)
            if mode != 4:
                L._advance_moving(window, disp, vel, acc, acc_prev, dt, psi)
            t = (n + 1) * dt
            clear_moving(window, acc)
            L._move_window(t, state, placed, window)
            L._train_loads(t, state, placed, work, mesh, ws_x, rail_kin, 1.0)
            if mode != 1:
                windowed_accelerations_in_place(packed, window, disp, vel, acc)
            else:   # without the kernel the loads must not stand in for accelerations
                for i in range(acc.shape[0]):
                    acc[i] = 0.0
        step = n + 1
        if mode != 5 and record_wheel_step(train, work.wheel, step) == 0:
            return 2, n
        if mode != 2:
            record_monitors(monitors, disp, vel, acc)
        if mode != 3:
            record_step_channels(train, monitors.current, work.wheel, q, a)
        if step % out_every == 0 and mode != 6:
            finite, big = record_vehicle_output(train, out_row, step * dt, q, a)
            if not finite:
                return 1, n
            for i in range(disp.shape[0]):
                if not np.isfinite(disp[i]):
                    return 1, n
            if big > 0.5:
                return 3, n
            record_wheel_output(train, out_row, work.wheel)
            out_row += 1
    flush(train.dec)
    return 0, n_steps


def _fresh(setup):
    """A run's initial state, monitors and recorder, as :func:`ttbpipe.simulation.loop.integrate`
    makes them."""
    n_v, n_s = setup.model.n_dof, setup.disp0.shape[0]
    state = L.CoupledState(setup.q0.copy(), setup.v0.copy(), np.zeros(n_v), np.zeros(n_v),
                           setup.disp0.copy(), np.zeros(n_s), np.zeros(n_s), np.zeros(n_s))
    monitors = setup.monitors.recorder()
    return state, monitors, L._recorder(setup, monitors.qty.shape[0])


def _arrays(obj, prefix=""):
    """Every numpy array in a (nested) namedtuple, by dotted name."""
    if isinstance(obj, np.ndarray):
        return {prefix: obj}
    out = {}
    if isinstance(obj, tuple) and hasattr(obj, "_fields"):
        for name, value in zip(obj._fields, obj):
            out.update(_arrays(value, f"{prefix}.{name}" if prefix else name))
    return out


def check_full_variant_is_the_loop(setup) -> None:
    """Run the case through :func:`ttbpipe.simulation.loop._coupled_loop` and through
    :func:`loop` (mode 0); raise unless the statuses, the final states, the monitors and every
    recorder array are equal bit for bit."""
    runs = []
    for use_copy in (False, True):
        state, monitors, train = _fresh(setup)
        args = (state, L._placed(setup), setup.packed, no_window(setup.packed), setup.mesh,
                monitors, train, setup.dt, setup.n_steps, setup.out_every)
        status = loop(*args, 0) if use_copy else L._coupled_loop(*args)
        runs.append((tuple(status), {**_arrays(state, "state"), **_arrays(monitors, "monitors"),
                                     **_arrays(train, "train")}))
    (status_loop, loop_arrays), (status_copy, copy_arrays) = runs
    differ = [name for name in loop_arrays
              if not np.array_equal(loop_arrays[name], copy_arrays[name], equal_nan=True)]
    if status_loop != status_copy or differ or loop_arrays.keys() != copy_arrays.keys():
        raise SystemExit(f"the benchmark's loop is not ttbpipe.simulation.loop._coupled_loop: "
                         f"status {status_copy} against {status_loop}, arrays that differ: "
                         f"{', '.join(differ) or 'none'}; update loop() to the loop as it is")
    print(f"full variant checked: {len(loop_arrays)} arrays equal to _coupled_loop's bit for bit "
          f"(status {status_loop})")


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--case", default=str(ROOT / "config" / "reference_case.yaml"))
    parser.add_argument("--duration", type=float, default=0.5)
    parser.add_argument("--rounds", type=int, default=4)
    args = parser.parse_args()
    case = yaml.safe_load(Path(args.case).read_text())
    case["simulation"]["duration_s"] = args.duration
    setup = prepare(case)
    check_full_variant_is_the_loop(setup)
    res = {k: [] for k in VARIANTS}
    for rnd in range(args.rounds):
        for mode in VARIANTS:
            state, mon, train = _fresh(setup)
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
