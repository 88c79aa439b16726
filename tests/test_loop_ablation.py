"""benchmarks/loop_ablation.py times copies of the coupled loop with one part left out; the
performance notes quote its differences to the full variant (docs/performance.md, "Where the step
goes in the loop"). The full variant must be the loop itself, or the benchmark times another
loop: the copy is checked against :func:`ttbpipe.simulation.loop._coupled_loop` on a short run
of the reference case (every output array and the final state equal bit for bit; the second
method here is the loop it copies), and the check must see a copy that drifted."""

import importlib.util
from pathlib import Path

import pytest
import yaml

from ttbpipe.simulation.coupled import prepare

_ROOT = Path(__file__).resolve().parents[1]
_spec = importlib.util.spec_from_file_location("loop_ablation",
                                               _ROOT / "benchmarks" / "loop_ablation.py")
ablation = importlib.util.module_from_spec(_spec)
_spec.loader.exec_module(ablation)


@pytest.fixture(scope="module")
def short_reference_case():
    case = yaml.safe_load((_ROOT / "config" / "reference_case.yaml").read_text())
    case["simulation"]["duration_s"] = 0.02
    return prepare(case)


def test_full_variant_is_the_coupled_loop_bit_for_bit(short_reference_case, capsys):
    ablation.check_full_variant_is_the_loop(short_reference_case)
    assert "equal to _coupled_loop's bit for bit" in capsys.readouterr().out


def test_check_sees_a_variant_that_is_not_the_loop(short_reference_case):
    """Mode 1 leaves out the structure kernel: the check must name the arrays that differ."""
    setup = short_reference_case
    full = ablation.loop
    try:
        ablation.loop = lambda *args: full(*args[:-1], 1)
        with pytest.raises(SystemExit, match="state.acc"):
            ablation.check_full_variant_is_the_loop(setup)
    finally:
        ablation.loop = full
