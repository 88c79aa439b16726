"""The moving window over the approach track (ttbpipe.structure.window).

* kernel: with no window the windowed kernel is the plain one bit for bit; with a window the
  DOFs that move get exactly the plain kernel's accelerations (every element touching them is
  evaluated, in the same order) and the frozen DOFs none (reference: the plain kernel with the
  frozen DOFs' rows set to zero, an obviously correct second evaluation);
* bookkeeping: DOFs leaving the window stop (velocity and accelerations 0) and move again when
  it reaches them; the bridge and monitored DOFs always move; bad margins are refused; the
  moving DOFs' ranges are exactly the DOFs that move, and Zhai's update and the clearing of the
  loads on them alone leave every array as the update and clearing of all DOFs do (frozen DOFs
  hold zero velocity and accelerations);
* coupled run: a two-car train over one span between 60 m ballasted approaches, window of 10 m
  against the whole track (the second method): wheel-force peaks and deck peaks within 1e-3 of
  the whole track's (measured 1e-5 to 1e-4 on the reference case, docs/performance.md); the
  track far behind the train is frozen at the end of the run.
"""

from __future__ import annotations

import copy

import numpy as np
import pytest

from ttbpipe.simulation.coupled import integrate, prepare, results_table
from ttbpipe.structure import build_structure
from ttbpipe.structure.kernels import structure_accelerations, windowed_accelerations_in_place
from ttbpipe.structure.window import (DOF_RANGES, clear_moving, no_window, track_window,
                                     update_window)
from ttbpipe.timestepping.zhai import zhai_predict, zhai_predict_ranges

LAYOUT = {"approach_length_m": 60.0, "spans_m": [32.0], "approach_track": "ballasted",
          "bridge_track": "slab"}


@pytest.fixture(scope="module")
def model():
    return build_structure({"layout": LAYOUT})


def _state(n, seed):
    rng = np.random.default_rng(seed)
    return rng.normal(size=n) * 1e-4, rng.normal(size=n) * 1e-2, rng.normal(size=n) * 1e3


def test_no_window_is_the_plain_kernel_bit_for_bit(model):
    u, v, f = _state(model.n_dof, 1)
    plain, windowed = np.zeros(model.n_dof), f.copy()      # in place: the loads on entry
    structure_accelerations(model.packed, u, v, f, plain)
    windowed_accelerations_in_place(model.packed, no_window(model.packed), u, v, windowed)
    assert np.array_equal(plain, windowed)


@pytest.mark.parametrize("x_low, x_high", [(2.0, 30.0), (40.0, 85.0), (95.0, 140.0)])
def test_moving_dofs_get_the_plain_accelerations_and_frozen_dofs_none(model, x_low, x_high):
    n = model.n_dof
    window = track_window(model, 10.0)
    zeros = [np.zeros(n) for _ in range(3)]
    update_window(window, x_low, x_high, *zeros)
    frozen = np.flatnonzero(window.inv_mass[:model.packed.n_diag] != model.packed.inv_mass[
        :model.packed.n_diag])
    assert frozen.size > 0                   # the case freezes part of the approaches
    u, v, f = _state(n, 2)
    plain, windowed = np.zeros(n), f.copy()
    structure_accelerations(model.packed, u, v, f, plain)
    windowed_accelerations_in_place(model.packed, window, u, v, windowed)
    expected = plain.copy()
    expected[frozen] = 0.0
    assert np.array_equal(windowed, expected)
    # the evaluated elements are fewer than all: the window saves work
    for kind, ranges, n_el in ((0, window.beam_ranges, window.beam_segment.size),
                               (2, window.pad_ranges, window.pad_segment.size)):
        rows = ranges[:window.n_ranges[kind]]
        assert 0 < np.sum(rows[:, 1] - rows[:, 0]) < n_el


def test_the_window_follows_the_train_and_stops_what_it_leaves(model):
    n = model.n_dof
    window = track_window(model, 10.0)
    x_rail = model.layout.rail_x
    rail_z = 5 * np.arange(x_rail.size)          # left rail, vertical DOF of each node
    vel, acc, acc_prev = (np.ones(n) for _ in range(3))
    update_window(window, 5.0, 20.0, vel, acc, acc_prev)
    moving = window.inv_mass[rail_z] > 0
    # around the train (wheelsets at 5-20 m, margin 10 m: the 5 m segments up to 35 m) and
    # from the bridge's margin on (50 m)
    assert moving[(x_rail > 0.0) & (x_rail < 30.0)].all()
    far = (x_rail > 35.0 + 1e-9) & (x_rail < model.layout.bridge_start_m - 10.0 - 1e-9)
    assert far.any() and not moving[far].any()
    on_bridge = (x_rail >= model.layout.bridge_start_m) & (x_rail <= model.layout.bridge_end_m)
    assert moving[on_bridge].all()
    assert (vel[rail_z][~moving] == 0).all() and (acc_prev[rail_z][~moving] == 0).all()
    # the train moves on: the track behind it stops, the track ahead moves again
    vel[:] = 1.0
    update_window(window, 20.0, 45.0, vel, acc, acc_prev)
    moving2 = window.inv_mass[rail_z] > 0
    assert not moving2[(x_rail > 0.0) & (x_rail < 5.0)].any()
    assert (vel[rail_z][(x_rail > 0.0) & (x_rail < 5.0)] == 0).all()
    assert moving2[(x_rail > 20.0) & (x_rail < 50.0)].all()
    # span blocks (girders) never stop
    assert (vel[model.packed.n_diag:] == 1.0).all()


def _moving_from_ranges(window, n):
    moving = np.zeros(n, dtype=bool)
    for start, end in window.dof_ranges[:window.n_ranges[DOF_RANGES]]:
        moving[start:n if end < 0 else end] = True
    return moving


@pytest.mark.parametrize("x_low, x_high", [(2.0, 30.0), (40.0, 85.0), (95.0, 140.0)])
def test_zhai_update_and_clearing_of_the_moving_dofs_alone_equal_those_of_all(model, x_low,
                                                                              x_high):
    n, n_diag = model.n_dof, model.packed.n_diag
    window = track_window(model, 10.0)
    assert _moving_from_ranges(window, n).all()           # before the first update: all move
    rng = np.random.default_rng(5)
    u, v, a, a_prev = (rng.normal(size=n) for _ in range(4))
    update_window(window, x_low, x_high, v, a, a_prev)
    moving = _moving_from_ranges(window, n)
    # the ranges hold exactly the DOFs that move: an active or always-moving segment's, and
    # the span blocks' (the frozen ones: a zero inverse mass where the structure has none)
    segment = window.dof_segment
    expected = np.ones(n, dtype=bool)
    expected[:n_diag] = (segment < 0) | (window.segment_on[np.maximum(segment, 0)] != 0)
    assert np.array_equal(moving, expected)
    assert 0 < (~moving).sum() and (window.inv_mass[:n_diag][~moving[:n_diag]] == 0).all()
    assert (v[~moving] == 0).all() and (a[~moving] == 0).all() and (a_prev[~moving] == 0).all()
    for psi in (0.0, 0.5):
        full = [x.copy() for x in (u, v, a, a_prev)]
        part = [x.copy() for x in (u, v, a, a_prev)]
        zhai_predict(*full, 1.25e-4, psi, psi)
        zhai_predict_ranges(*part, 1.25e-4, psi, psi, window.dof_ranges,
                            window.n_ranges[DOF_RANGES])
        for x, y in zip(full, part):
            assert np.array_equal(x, y)
    loads = rng.normal(size=n)
    loads[~moving] = 0.0
    clear_moving(window, loads)
    assert (loads == 0).all()
    everything = rng.normal(size=n)
    clear_moving(no_window(model.packed), everything)
    assert (everything == 0).all()


def test_monitored_dofs_always_move_and_bad_margins_are_refused(model):
    keep = [5 * 10]                               # a rail node about 6 m from the start
    window = track_window(model, 10.0, keep_dofs=keep)
    zeros = [np.zeros(model.n_dof) for _ in range(3)]
    update_window(window, 100.0, 140.0, *zeros)
    assert window.inv_mass[keep[0]] > 0
    with pytest.raises(ValueError, match="track_window_m"):
        track_window(model, 0.0)


CASE = {
    "structure": {"layout": LAYOUT},
    "train": {"composition": ["motor", "trailer"]},
    "simulation": {"track": "structure", "speed_kmh": 300.0, "time_step_s": 1.25e-4,
                   "output_interval_s": 1.0e-3},
    "irregularity": {"source": "synthetic", "spectrum": "tbt3352", "seed": 11},
}


def _run(margin):
    case = copy.deepcopy(CASE)
    case["simulation"]["track_window_m"] = margin
    setup = prepare(case)
    raw = integrate(setup)
    return setup, raw, results_table(setup, raw)


def test_a_coupled_run_in_the_window_matches_the_whole_track():
    setup_w, raw_w, table_w = _run(10.0)
    setup_a, raw_a, table_a = _run(None)
    # wheel forces: max P, min P, max |Q|, max Q/P of every wheel, relative to the largest
    scale = np.abs(raw_a.wheel_peak).max(axis=(0, 1))
    rel = np.abs(raw_w.wheel_peak - raw_a.wheel_peak).max(axis=(0, 1)) / scale
    assert (rel < 1e-3).all(), rel
    # the structure's monitored peaks (deck, girder, slab, rail) and the wheel-load histories
    peak_rel = np.abs(raw_w.monitors.peak - raw_a.monitors.peak) / np.abs(raw_a.monitors.peak)
    names = setup_a.monitors.names
    deck = [i for i, name in enumerate(names) if not name.startswith("rail_")]
    assert deck and peak_rel[deck].max() < 1e-3, dict(zip(names, peak_rel))
    loads = [c for c in table_a.columns if c.endswith("_P_N")]
    assert loads
    for c in loads:
        a, w = table_a[c].to_numpy(), table_w[c].to_numpy()
        assert np.max(np.abs(w - a)) < 1e-3 * np.max(np.abs(a)), c
    # at the end (leading wheelset 5 m before the rails end) the first approach is frozen
    x_rail = setup_w.structure.layout.rail_x
    rail_z = 5 * np.arange(x_rail.size)
    behind = x_rail < 20.0
    assert (raw_w.final.vel[rail_z][behind] == 0).all()
    assert (np.abs(raw_a.final.vel[rail_z][behind]) > 0).any()


def test_a_study_passes_its_window_to_the_runs_and_refuses_a_bad_one():
    from ttbpipe.study.samples import build_case, resolve_simulation

    sim = resolve_simulation({"track_window_m": 20.0})
    case = build_case(sim, {"layout": LAYOUT}, irregularity={"source": "synthetic"})
    assert case["simulation"]["track_window_m"] == 20.0
    assert "track_window_m" not in build_case(resolve_simulation({}), {"layout": LAYOUT},
                                              irregularity={})["simulation"]
    with pytest.raises(Exception, match="track_window_m"):
        resolve_simulation({"track_window_m": 0.0})
