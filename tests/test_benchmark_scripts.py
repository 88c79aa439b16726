"""`python benchmarks/run_all.py` runs every `benchmarks/bench_*.py` without arguments
(docs/dev/contributing.md): none of them may require a positional argument or a required
option, or run_all records it as failed instead of timing it. Read from the scripts' source
(their argparse calls), without running them."""

import ast
from pathlib import Path

BENCHMARKS = Path(__file__).resolve().parents[1] / "benchmarks"


def required_arguments(source: str) -> list[str]:
    """The arguments an argparse script declares required: positional names without a default
    or ``nargs`` that allows none, and options with ``required=True``."""
    found = []
    for node in ast.walk(ast.parse(source)):
        if not (isinstance(node, ast.Call) and isinstance(node.func, ast.Attribute)
                and node.func.attr == "add_argument" and node.args
                and isinstance(node.args[0], ast.Constant)):
            continue
        name = node.args[0].value
        keywords = {k.arg: k.value for k in node.keywords}
        if not name.startswith("-"):
            nargs = keywords.get("nargs")
            if not (isinstance(nargs, ast.Constant) and nargs.value in ("?", "*")):
                found.append(name)
        elif isinstance(keywords.get("required"), ast.Constant) and keywords["required"].value:
            found.append(name)
    return found


def test_the_check_sees_required_arguments():
    source = ("p.add_argument('root')\np.add_argument('--out', required=True)\n"
              "p.add_argument('extra', nargs='?')\np.add_argument('--rounds', type=int)\n")
    assert required_arguments(source) == ["root", "--out"]


def test_every_bench_script_runs_without_arguments():
    scripts = sorted(BENCHMARKS.glob("bench_*.py"))
    assert len(scripts) >= 10
    needing = {p.name: required_arguments(p.read_text()) for p in scripts}
    assert {name: args for name, args in needing.items() if args} == {}
