"""EN 1990 Annex A2 (A2.4.4) deck checks of a railway bridge from a coupled run.

Clauses and values (docs/reference/standards.md: [V] a national annex extract quoting the
recommended values, [M] not re-read):

* A2.4.4.2.1, deck vertical acceleration: peak <= 3.5 m/s^2 (ballasted track) or 5.0 m/s^2
  (direct fastening) [V], for frequencies up to the greater of 30 Hz, 1.5 f0 and f3 [M: the band
  rule], f0 and f3 the first and third vertical frequencies of the member (the span), from
  ttbpipe's modal analysis of the run's structure (:mod:`.modal`). Processing: the span's
  midspan deck acceleration on the deck surface under each rail (monitors
  ``deck_left|right_spanS_mid_z_acc_m_s2``; the girder's shear centre
  ``girder_spanS_mid_z_acc_m_s2`` for runs without them) low-passed at
  max(30 Hz, 1.5 f0, f3) (Butterworth order 4, zero phase, as the run's own deck filter,
  :func:`ttbpipe.simulation.outputs.lowpass_peak`), largest |a|. The limits are
  :data:`ttbpipe.stats.limits.DECK_VERTICAL_ACC_M_S2` (their one home); the track type follows the
  structure's ``bridge_track`` (slab: direct fastening).
* A2.4.4.2.2, deck twist over 3 m: t <= 4.5 / 3.0 / 1.5 mm for V <= 120 / 120-200 / > 200 km/h
  [V] (the total twist with the track's design twist, 7.5 mm, needs a track transition, not
  modelled). t(x) = (z_left - z_right)(x) - (z_left - z_right)(x + 3 m) from the rails' vertical
  displacements at the sections of :func:`.monitors.deck_check_monitors`, which a run must
  record (its case lists them; else this profile stops, or skips the twist with ``twist: false``).
  The rails' displacement includes the rail's own deflection on its fasteners under each wheel;
  left and right wheels load both rails alike, so it largely cancels in z_left - z_right.
* A2.4.4.2.3, vertical deflection <= L/600 [V]. EN 1990 A2 evaluates it under the
  characteristic Load Model 71 (with its dynamic factor), not under a real train; the run gives
  the simulated train's largest midspan deflection (``girder_spanS_mid_z_disp_mm``), far below
  LM71's (LM71: 250 kN axles and 80 kN/m). Its utilisation is therefore not the code check.
* A2.4.4.3, passenger comfort: vertical acceleration b_v in the coach, 1.0 / 1.3 / 2.0 m/s^2
  for very good / good / acceptable comfort [V]. A2.4.4.3.2 gives it as a chart of the span to
  deflection ratio L/delta for b_v = 1 m/s^2 (not reproduced here; which load model its
  deflections assume [M]); A2.4.4.3.3 allows b_v to be taken from a dynamic vehicle-bridge
  interaction analysis of the real train [M], which is what the run is: b_v is the largest
  |vertical car-body floor acceleration| (raw, the model's car body is rigid), and L/delta of
  the simulated deflection is reported for comparison with the chart.
"""

from __future__ import annotations

import logging
import math

import numpy as np

from ..stats.limits import DECK_VERTICAL_ACC_M_S2
from .base import Profile, Row, governing, speed_band_value, speed_bands_text
from .modal import span_frequencies
from .monitors import TWIST_BASE_M, TWIST_COLUMN
from .processing import Butterworth
from .run import RunData

log = logging.getLogger(__name__)

STANDARD = "EN 1990:2002 Annex A2"

#: A2.4.4.2.1: the band goes up to max(MIN_CUTOFF_HZ, F0_FACTOR f0, f3).
MIN_CUTOFF_HZ = 30.0
F0_FACTOR = 1.5
#: A2.4.4.2.2 deck twist limits (m over 3 m) by speed: (upper speed km/h, limit) [V].
TWIST_LIMITS_M = ((120.0, 4.5e-3), (200.0, 3.0e-3), (math.inf, 1.5e-3))
#: The rule of the twist limit (the run's speed and limit go to the row's notes: a study's
#: samples share one limit source).
_TWIST_SOURCE = (f"{speed_bands_text(TWIST_LIMITS_M, 1e3, 'mm')}, over {TWIST_BASE_M:g} m "
                 "(EN 1990 A2 A2.4.4.2.2) [V]")
#: A2.4.4.2.3 vertical deflection limit L / DEFLECTION_RATIO [V].
DEFLECTION_RATIO = 600.0
#: A2.4.4.3.1 comfort levels of the in-coach vertical acceleration b_v (m/s^2) [V].
COMFORT_B_V_M_S2 = {"very good": 1.0, "good": 1.3, "acceptable": 2.0}

DEFAULTS = {
    "f0_hz": None,              # None: from the modal analysis of the run's structure
    "f3_hz": None,
    "span_lengths_m": None,     # None: from the run's structure
    "filter_order": 4,
    "deck_track_type": None,    # None: from structure.layout.bridge_track (slab: ballastless)
    "twist": True,              # False: skip the twist when the run lacks its monitors
    "comfort_level": "very good",
}


def band_cutoff_hz(f0_hz: float, f3_hz: float) -> float:
    """A2.4.4.2.1: max(30 Hz, 1.5 f0, f3)."""
    return max(MIN_CUTOFF_HZ, F0_FACTOR * float(f0_hz), float(f3_hz))


def deck_filter(f0_hz: float, f3_hz: float, order: int = DEFAULTS["filter_order"]) -> Butterworth:
    """The deck accelerations' low-pass at :func:`band_cutoff_hz`."""
    return Butterworth("lowpass", band_cutoff_hz(f0_hz, f3_hz), int(order))


def twist_limit_m(speed_kmh: float) -> float:
    return speed_band_value(TWIST_LIMITS_M, speed_kmh)


def _spans(run: RunData, options, n_spans: int) -> list[tuple[float, float, float]]:
    """(length, f0, f3) of each span: the options where given, else the modal analysis."""
    f0, f3, lengths = options["f0_hz"], options["f3_hz"], options["span_lengths_m"]
    modal = None
    if f0 is None or f3 is None or lengths is None:
        if not run.config or "structure" not in run.config:
            raise ValueError("EN 1990 A2 needs the run's structure (the result's provenance "
                             "config) or the options f0_hz, f3_hz and span_lengths_m")
        modal = span_frequencies(run.config.get("structure"), run.config.get("properties"))
        if len(modal) != n_spans:
            raise ValueError(f"the structure has {len(modal)} spans, the run's table {n_spans}")

    def per_span(value, name):
        if value is None:
            return [getattr(m, name) for m in modal]
        v = np.atleast_1d(np.asarray(value, dtype=float))
        if v.size not in (1, n_spans):
            raise ValueError(f"option for {name}: {v.size} values for {n_spans} spans")
        return [float(x) for x in np.broadcast_to(v, (n_spans,))]

    return list(zip(per_span(lengths, "length_m"), per_span(f0, "f0_hz"), per_span(f3, "f3_hz")))


def _track_type(run: RunData, options) -> str:
    if options["deck_track_type"] is not None:
        kind = str(options["deck_track_type"])
    else:
        layout = ((run.config or {}).get("structure") or {}).get("layout") or {}
        kind = "ballasted" if layout.get("bridge_track") == "ballasted" else "ballastless"
    if kind not in DECK_VERTICAL_ACC_M_S2:
        raise ValueError(f"deck_track_type {kind!r}: expected one of {list(DECK_VERTICAL_ACC_M_S2)}")
    return kind


def _twist(run: RunData) -> tuple[list[str], np.ndarray]:
    """(pair names, (n, pairs) twist histories in m) from the deck-check monitors."""
    cols: dict[str, dict] = {}
    for c in run.column_names:
        m = TWIST_COLUMN.match(c)
        if m:
            cols.setdefault(m.group("where"), {})[(m.group("end"), m.group("side"))] = c
    names, columns = [], []
    for where, got in sorted(cols.items()):
        if len(got) != 4:
            raise ValueError(f"twist section {where}: monitors {sorted(got)} incomplete (needs a/b "
                             "x left/right)")
        names.append(where)
        columns += [got[(end, side)] for end in ("a", "b") for side in ("left", "right")]
    if not names:
        return names, np.zeros((run.table.shape[0], 0))
    z = 1e-3 * run.read_columns(columns)      # a-left, a-right, b-left, b-right of each section
    return names, (z[:, 0::4] - z[:, 1::4]) - (z[:, 2::4] - z[:, 3::4])


def evaluate(run: RunData, options) -> list[Row]:
    # imported here: the structure package loads numba and SciPy's sparse solvers, which the
    # Snakefile (it loads every profile to resolve the assessment) does not need
    from ..structure.monitors import deck_columns

    acc = run.deck_acceleration()
    disp = run.girder("disp_mm")
    if not acc:
        raise ValueError("the run has no deck midspan acceleration monitors "
                         "(deck_left_spanS_mid_z_acc_m_s2 or girder_spanS_mid_z_acc_m_s2; the "
                         "structure's default monitors)")
    spans = sorted(acc)
    info = _spans(run, options, len(spans))
    order = int(options["filter_order"])
    rows = []

    peaks, filters = [], []
    for (length, f0, f3), s in zip(info, spans):
        filt = deck_filter(f0, f3, order)
        keep = filt.interior(acc[s][0].size, run.dt_s)   # without the filter's start-up
        # the span's histories in one call (the filter runs along each column alike)
        peaks.append(float(np.max(np.abs(filt.apply(np.column_stack(acc[s]), run.dt_s)[keep]))))
        filters.append(filt)
    kind = _track_type(run, options)
    labels = [f"span{s}" for s in spans]
    i, v, lim = governing(np.array(peaks), DECK_VERTICAL_ACC_M_S2[kind], labels)
    length, f0, f3 = info[i]
    deck_monitors = {c[:-len("_z_acc_m_s2")]
                     for cols in deck_columns(run.column_names, "z").values() for c in cols}
    unfiltered = [val for k, val in (run.summary.get("monitor_peaks") or {}).items()
                  if k.endswith("_z_acc_m_s2") and k[:-len("_z_acc_m_s2")] in deck_monitors]
    rows.append(Row(
        "A2.4.4.2.1 (deck vertical acceleration)", "deck_vertical_acc_m_s2", "m/s^2", "span",
        labels[i], v, lim, f"{lim:g} m/s^2, {kind} track (EN 1990 A2 A2.4.4.2.1) [V]",
        raw_index="max_deck_vertical_acc_m_s2", raw_value=run.raw("max_deck_vertical_acc_m_s2"),
        statistic="largest |a| at midspan under the rails",
        notes=(f"band max(30 Hz, 1.5 f0, f3) with f0 = {f0:.3f} Hz, f3 = {f3:.3f} Hz of "
               f"{labels[i]} (cut-offs of the spans {', '.join(f'{f.high_hz:.1f}' for f in filters)} Hz); "
               f"raw_value is the run's deck index, low-passed at "
               f"{run.summary.get('deck_filter_hz', float('nan')):g} Hz; unfiltered peak over "
               f"every step {max(unfiltered) if unfiltered else float('nan'):.4g} m/s^2"),
    ).with_filter(filters[i]))

    if options["twist"]:
        names, twist = _twist(run)
        if not names:
            raise ValueError("the run has no deck twist monitors: list "
                             "ttbpipe.assessment.monitors.deck_check_monitors(structure) in the "
                             "case's monitors (ttbpipe assess-monitors CASE.yaml --out "
                             "CASE_DECK.yaml), or pass the option twist=false")
        t_max = np.max(np.abs(twist), axis=0)
        t_lim = twist_limit_m(run.speed_kmh)
        i, v, lim = governing(t_max, t_lim, names)
        rows.append(Row(
            "A2.4.4.2.2 (deck twist over 3 m)", "deck_twist_m", "m", "section", names[i], v, lim,
            _TWIST_SOURCE,
            raw_value=v, window_m=TWIST_BASE_M, statistic="largest |t| over the run",
            notes=(f"{lim * 1e3:g} mm at {run.speed_kmh:g} km/h; "
                   "t = (z_left - z_right)(x) - (z_left - z_right)(x + 3 m) of the rails (no "
                   "processing: raw_value = processed); under the simulated train, not LM71"),
        ))
    else:
        log.warning("EN 1990 A2: deck twist not evaluated (option twist=false)")

    if disp:
        delta = np.array([1e-3 * float(np.max(np.abs(disp[s]))) for s in spans])
        lengths = np.array([sp[0] for sp in info])
        i, v, lim = governing(delta, lengths / DEFLECTION_RATIO, labels)
        rows.append(Row(
            "A2.4.4.2.3 (vertical deflection)", "vertical_deflection_m", "m", "span", labels[i],
            v, lim, f"L/{DEFLECTION_RATIO:g} with L the span's length, under LM71 in the "
            "standard [V]",
            raw_index="max_girder_vertical_disp_m", raw_value=run.raw("max_girder_vertical_disp_m"),
            statistic="largest |midspan deflection| over the run",
            notes=(f"L = {lengths[i]:g} m; under the simulated train, not under LM71 (x dynamic "
                   "factor) as A2.4.4.2.3 asks: not the code check"),
        ))
        ratio = lengths / np.maximum(delta, 1e-12)
        j = int(np.argmin(ratio))
        rows.append(Row(
            "A2.4.4.3.2 (passenger comfort, span / deflection ratio)", "span_to_deflection_ratio",
            "1", "span", labels[j], float(ratio[j]), float("nan"),
            "compare with the L/delta chart of A2.4.4.3.2 (b_v = 1 m/s^2; not reproduced)",
            category="info", statistic="smallest L / delta over the spans",
            notes="delta of the simulated train",
        ))

    labels_c, az = run.carbody("az")
    level = str(options["comfort_level"])
    if level not in COMFORT_B_V_M_S2:
        raise ValueError(f"comfort_level {level!r}: expected one of {list(COMFORT_B_V_M_S2)}")
    b_v = np.max(np.abs(az), axis=0)
    i, v, lim = governing(b_v, COMFORT_B_V_M_S2[level], labels_c)
    rows.append(Row(
        "A2.4.4.3 (passenger comfort, vertical acceleration in the coach b_v)", "b_v_m_s2",
        "m/s^2", "car", labels_c[i], v, lim,
        f"{lim:g} m/s^2, comfort '{level}' (1.0 / 1.3 / 2.0 m/s^2 very good / good / "
        "acceptable) [V]", category="grade",
        raw_index="max_carbody_vertical_acc_m_s2",
        raw_value=run.raw("max_carbody_vertical_acc_m_s2"),
        statistic="largest |vertical floor acceleration| at the output steps",
        notes="from the vehicle-bridge interaction run (A2.4.4.3.3 [M]); unfiltered",
    ))
    return rows


PROFILE = Profile("en1990", STANDARD, "deck checks of railway bridges (A2.4.4)", DEFAULTS, evaluate)
