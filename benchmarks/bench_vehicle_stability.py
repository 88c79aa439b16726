"""Cost of the vehicle step limit (ttbpipe.vehicle.stability) and the default cars' limits.

    python benchmarks/bench_vehicle_stability.py

Times :func:`vehicle_time_step_limit` with an empty cache (the cost paid once per process, per
train and speed: every sample of a study shares it) for the reference case's 5-car train and
for one car, the cached call, and the one-eigenvalue check of a given step
(:func:`vehicle_step_is_stable`), best of 5; prints the limits with ``FIGURE`` lines for
benchmarks/run_all.py.
"""

from __future__ import annotations

import os
import time

os.environ.setdefault("NUMBA_NUM_THREADS", "1")

from ttbpipe.vehicle import stability  # noqa: E402
from ttbpipe.vehicle.contact import build_geometry  # noqa: E402
from ttbpipe.vehicle.model import build_train_model  # noqa: E402
from ttbpipe.vehicle.parameters import train_from_config  # noqa: E402

SPEED = 300.0 / 3.6


def best(fn, repeat=5, clear=True):
    t_best, out = float("inf"), None
    for _ in range(repeat):
        if clear:
            stability._CACHE.clear()
        t0 = time.perf_counter()
        out = fn()
        t_best = min(t_best, time.perf_counter() - t0)
    return t_best, out


def main() -> None:
    stability.vehicle_time_step_limit(*_train(["trailer"]), SPEED)   # imports, warm-up
    for label, comp in (("train5", ["motor", "trailer", "trailer", "trailer", "motor"]),
                        ("car1", ["trailer"])):
        model, geom = _train(comp)
        t_cold, lim = best(lambda: stability.vehicle_time_step_limit(model, geom, SPEED))
        t_hot, _ = best(lambda: stability.vehicle_time_step_limit(model, geom, SPEED), clear=False)
        t_one, _ = best(lambda: stability.vehicle_step_is_stable(model, geom, SPEED, 1.25e-4 / 0.9))
        print(f"{label}: limit {lim['dt_vehicle_limit_s']:.4g} s ({lim['vehicle_mode']}), "
              f"enforced {lim['dt_vehicle_s']:.4g} s; bisection {1e3 * t_cold:.1f} ms, cached "
              f"{1e6 * t_hot:.1f} us, one check at a given step {1e3 * t_one:.1f} ms")
        print(f"FIGURE vehicle_limit_{label}_s = {lim['dt_vehicle_limit_s']:.4g} s")
        print(f"FIGURE vehicle_limit_{label}_bisection_ms = {1e3 * t_cold:.4g} ms")
        print(f"FIGURE vehicle_limit_{label}_step_check_ms = {1e3 * t_one:.4g} ms")


def _train(composition):
    train = train_from_config({"composition": composition})
    return build_train_model(train), build_geometry(train.contact)


if __name__ == "__main__":
    main()
