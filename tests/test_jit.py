"""Every compiled kernel of the package takes the options of ``ttbpipe.jit`` (one home).

* no module of the package calls numba's ``njit`` itself; every numba dispatcher found in the
  package's modules is cached and has numpy's error model;
* numpy's error model, as documented in ``ttbpipe.jit``: a float division by zero gives inf or
  NaN (numpy's rule, the reference), an integer division by zero 0; without a zero divisor the
  result is the same as Python's.
"""

import importlib
import math
import pkgutil
import re
from pathlib import Path

import numpy as np
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
