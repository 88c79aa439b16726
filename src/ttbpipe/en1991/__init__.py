"""EN 1991-2 dynamic analysis of railway bridges: trains over the speed range, the standard's
checks (docs/en1991.md).

* :mod:`ttbpipe.en1991.limits`: Figure 6.9 (need for a dynamic analysis), Figure 6.10 (n0
  limits), the design speed and the resonance speeds;
* :mod:`ttbpipe.en1991.dynamic`: the simply supported span model and one train's speed sweep;
* :mod:`ttbpipe.en1991.study`: every train on every span, envelopes, checks, the report page.
"""

from .dynamic import SpanModel, span_model, sweep_train
from .limits import dynamic_analysis_need, n0_limits_hz, resonance_speeds_kmh
from .study import run_train, summarise

__all__ = ["SpanModel", "span_model", "sweep_train", "dynamic_analysis_need", "n0_limits_hz",
           "resonance_speeds_kmh", "run_train", "summarise"]
