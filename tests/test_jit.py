"""Every compiled kernel of the package takes the options of ``ttbpipe.jit`` (one home).

* no module of the package calls numba's ``njit`` itself; every numba dispatcher found in the
  package's modules is cached and has numpy's error model;
* numpy's error model, as documented in ``ttbpipe.jit``: a float division by zero gives inf or
  NaN (numpy's rule, the reference), an integer division by zero 0; without a zero divisor the
  result is the same as Python's;
* the kernels of the coupled time step are compiled without reference counting
  (``creates_arrays=False``): their compiled code calls none of numba's ``NRT_incref`` and
  ``NRT_decref``, a kernel marked so that creates an array is refused at compile time, and the
  same kernel with reference counting gives the same numbers.
"""

import importlib
import math
import pkgutil
import re
from pathlib import Path

import numpy as np
import pytest
from numba.core.errors import NumbaError
from numba.core.registry import CPUDispatcher

import ttbpipe
from ttbpipe.jit import KERNEL_OPTIONS, kernel

PACKAGE = Path(ttbpipe.__file__).resolve().parent


def test_no_module_calls_njit_itself():
    offenders = []
    for path in PACKAGE.rglob("*.py"):
        if path.name == "jit.py":
            continue
        code = "\n".join(line.split("#")[0] for line in path.read_text().splitlines())
        code = re.sub(r'"""[\s\S]*?"""', "", code)
        if re.search(r"\bnjit\b|numba\.jit\b", code):
            offenders.append(str(path.relative_to(PACKAGE)))
    assert not offenders, f"use ttbpipe.jit.kernel instead of njit in {offenders}"


def test_every_dispatcher_has_the_kernel_options():
    dispatchers = {}
    for info in pkgutil.walk_packages([str(PACKAGE)], prefix="ttbpipe."):
        if info.name.endswith("__main__"):
            continue
        module = importlib.import_module(info.name)
        for name, value in vars(module).items():
            if isinstance(value, CPUDispatcher) and value.py_func.__module__ == info.name:
                dispatchers[f"{info.name}.{name}"] = value
    assert len(dispatchers) >= 60          # the package's kernels (79 when written)
    for name, dispatcher in dispatchers.items():
        assert dispatcher.targetoptions["error_model"] == KERNEL_OPTIONS["error_model"], name
        assert dispatcher._cache.__class__.__name__ == "FunctionCache", name   # cache=True
        # set, not inherited from the kernel whose compilation first calls it (ttbpipe.jit)
        assert dispatcher.targetoptions["_nrt"] in (True, False), name


def test_division_by_zero_follows_numpy():
    @kernel
    def divide(a, b, i, j):
        return a / b, i // j, i % j

    with np.errstate(divide="ignore", invalid="ignore"):
        for a in (1.0, -2.5, 0.0):
            got = divide(a, 0.0, 7, 0)[0]
            ref = np.float64(a) / np.float64(0.0)
            assert (math.isnan(got) and math.isnan(ref)) or got == ref
    assert divide(1.0, 0.0, 7, 0)[1:] == (0, 0)
    assert divide(7.5, 2.5, 7, 2) == (7.5 / 2.5, 7 // 2, 7 % 2)
    assert divide(-7.0, 2.0, -7, 2) == (-3.5, -7 // 2, -7 % 2)     # Python's floor rules kept


#: The kernels the coupled loop calls at every time step (``ttbpipe.simulation.loop``) and the
#: moving-load loop, which borrow the arrays they are given (``@kernel(creates_arrays=False)``).
STEP_KERNELS = {
    "ttbpipe.simulation.loop": ["placed_track_kinematics", "add_wheel_loads", "_train_loads",
                                "_move_window", "_evaluate", "_advance", "_evaluate_pair"],
    "ttbpipe.vehicle.dynamics": ["vehicle_accelerations"],
    "ttbpipe.vehicle.kernels": ["csr_matvec_sub", "train_contact"],
    "ttbpipe.vehicle.contact": ["_creep_forces", "_table_row", "_wheel_contact", "_lerp2",
                                "_wheel_contact_points"],
    "ttbpipe.vehicle.curving": ["_knot_segment", "_pose_on_segment", "_frame_at", "curve_frame"],
    "ttbpipe.structure.kernels": ["structure_accelerations", "structure_accelerations_in_place",
                                  "windowed_accelerations_in_place", "_accelerations",
                                  "_beam_forces", "_link_forces", "_triple_forces", "_pad_forces",
                                  "_slab_pads", "_sleeper_pads", "_rigid_pads", "_ballast_forces"],
    "ttbpipe.structure.window": ["_element_ranges", "update_window"],
    "ttbpipe.structure.monitors": ["record_monitors"],
    "ttbpipe.simulation.recorder": ["record_step_channels", "record_wheel_step",
                                    "record_vehicle_output", "record_wheel_output"],
    "ttbpipe.decimation": ["_add_sample", "push"],
    "ttbpipe.timestepping.zhai": ["zhai_predict"],
    "ttbpipe.structure.moving_loads": ["_moving_load_loop"],
}


def test_the_step_kernels_borrow_their_arrays():
    for module_name, names in STEP_KERNELS.items():
        module = importlib.import_module(module_name)
        for name in names:
            options = getattr(module, name).targetoptions
            assert options.get("_nrt") is False, f"{module_name}.{name}: {options}"


@kernel(inline="always", cache=False)
def _point_value(values, node, weight):
    """A helper of the kind the step inlines at every wheel: it reads an array it is handed."""
    if weight > 0.5:
        return values[node] * weight
    return values[node + 1] * (1.0 - weight)


def _sum_points(values, nodes, weights, out):
    for i in range(nodes.shape[0]):
        out[i] = _point_value(values, nodes[i], weights[i])


def _refcount_calls(dispatcher):
    llvm_ir = dispatcher.inspect_llvm(dispatcher.signatures[0])
    return len(re.findall(r"call void @NRT_(?:incref|decref)\(", llvm_ir))


def test_a_borrowing_kernel_counts_no_references():
    counting = kernel(cache=False)(_sum_points)
    borrowing = kernel(creates_arrays=False, cache=False)(_sum_points)
    values, nodes, weights = np.arange(10.0), np.array([1, 3, 5]), np.array([0.2, 0.7, 0.9])
    out_counting, out_borrowing = np.zeros(3), np.zeros(3)
    counting(values, nodes, weights, out_counting)
    borrowing(values, nodes, weights, out_borrowing)
    assert np.array_equal(out_counting, out_borrowing)
    assert np.array_equal(out_borrowing, [values[2] * 0.8, values[3] * 0.7, values[5] * 0.9])
    assert _refcount_calls(counting) > 0           # numba's default: the calls the option removes
    assert _refcount_calls(borrowing) == 0


def test_a_borrowing_kernel_may_not_create_arrays():
    def zeros_like(values):
        return np.zeros(values.shape[0])

    with pytest.raises(NumbaError, match="NRT required|Only accept returning of array"):
        kernel(creates_arrays=False, cache=False)(zeros_like)(np.ones(3))
