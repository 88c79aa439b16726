"""Measurement: what the second track of a double-track deck changes for one train.

The reference case (config/reference_case.yaml: 5-car train at 300 km/h over five 32 m spans,
130 m ballasted approaches, TB/T 3352 irregularity, seed 20261121) with its track 2.5 m off the
girders' axis, once on a single-track deck (``girder.track_offset_m: 2.5``) and once on a
double-track deck (``layout.tracks: 2``, the train on track 0 at +2.5 m, track 1 at -2.5 m
empty); then two such trains meeting (the second on track 1 running -x, entering from the far
end, the same irregularity profile on both tracks). Prints the structure's lowest girder
frequencies of a single span (``modal_analysis``) and the run's peaks side by side; the
numbers are regression values of the model (docs/structure.md section 9), not references.

    NUMBA_NUM_THREADS=1 python benchmarks/double_track_effect.py
"""

from __future__ import annotations

import copy
import os
from pathlib import Path

os.environ.setdefault("NUMBA_NUM_THREADS", "1")

import yaml  # noqa: E402

from ttbpipe.simulation.coupled import run_coupled  # noqa: E402
from ttbpipe.structure import build_structure  # noqa: E402
from ttbpipe.structure.modal import modal_analysis  # noqa: E402

ROOT = Path(__file__).resolve().parents[1]
PEAKS = ("girder_span3_mid_z_disp_mm", "girder_span3_mid_z_acc_m_s2", "girder_span3_mid_y_acc_m_s2")


def frequencies(tracks: int) -> dict[str, float]:
    girder = {"track_offsets_m": [2.5, -2.5]} if tracks == 2 else {"track_offset_m": 2.5}
    m = build_structure({"layout": {"approach_length_m": 0.0, "spans_m": [32.0],
                                    "tracks": tracks}, "girder": girder})
    r = modal_analysis(m, n_modes=12)
    return {c: r.first(c, 0.3) for c in ("girder_vertical", "girder_lateral", "girder_torsion")}


def main() -> None:
    for tracks in (1, 2):
        f = frequencies(tracks)
        print(f"one 32 m span, {tracks} track(s): first vertical {f['girder_vertical']:.3f} Hz, "
              f"lateral {f['girder_lateral']:.3f} Hz, torsion {f['girder_torsion']:.3f} Hz")
    case = yaml.safe_load((ROOT / "config" / "reference_case.yaml").read_text())
    single = copy.deepcopy(case)
    single["structure"]["girder"] = {"track_offset_m": 2.5}
    double = copy.deepcopy(case)
    double["structure"]["layout"]["tracks"] = 2
    meeting = copy.deepcopy(double)
    meeting["second_train"] = {}
    rows = {}
    for name, c in (("single-track deck", single), ("double-track deck", double),
                    ("double, two trains meeting", meeting)):
        _, s = run_coupled(c)
        p = s["monitor_peaks"]
        deck = "deck_left_span3_mid" if name.startswith("single") else \
            "deck_track1_left_span3_mid"
        rows[name] = {**{k: p[k] for k in PEAKS},
                      "deck under the train's left rail, span 3, z acc (m/s2)":
                          p[f"{deck}_z_acc_m_s2"],
                      "max_deck_vertical_acc_m_s2 (30 Hz)": s["max_deck_vertical_acc_m_s2"],
                      "max_deck_lateral_acc_m_s2 (30 Hz)": s["max_deck_lateral_acc_m_s2"],
                      "max_girder_vertical_disp_m": s["max_girder_vertical_disp_m"],
                      "max_wheel_vertical_force_N": s["max_wheel_vertical_force_N"],
                      "max_wheel_lateral_force_N": s["max_wheel_lateral_force_N"],
                      "max_derailment_coefficient": s["max_derailment_coefficient"],
                      "max_carbody_vertical_acc_m_s2": s["max_carbody_vertical_acc_m_s2"]}
    names = list(rows)
    print(f"{'peak':58s}" + "".join(f"{n:>28s}" for n in names) + f"{'double/single':>16s}")
    for key in rows[names[0]]:
        vals = [rows[n][key] for n in names]
        print(f"{key:58s}" + "".join(f"{v:28.4g}" for v in vals) + f"{vals[1] / vals[0]:16.3f}")


if __name__ == "__main__":
    main()
