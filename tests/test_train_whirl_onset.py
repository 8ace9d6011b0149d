"""Whirl onset speed of a train (issue 42 item 6, docs/train-misalignment.md): the threshold on the nonlinear film's
own coefficients, and the field's reading of misalignment as a radial preload — a more heavily loaded journal
bearing whirls later, an unloaded one earlier."""
from __future__ import annotations

import math

import pytest

from rotordiag.simulator.bearings import PlainBearing
from rotordiag.simulator.shaftline import PRESETS, preset
from rotordiag.simulator.train import (
    Disk,
    Rotor,
    Support,
    Train,
    TrainError,
    aligned_offsets,
    misaligned,
    static_state,
    uniform_elements,
    with_moves,
)
from rotordiag.simulator.train.shaftline import train_from_shaftline
from rotordiag.simulator.train.stability import stability, threshold_speed_rpm


def _rotor_on_plain_bearings(gravity_m_s2: float) -> Train:
    """A stiff 2 m shaft (Ø 0.3 m) with a 1.5 t disk on two plain short bearings (Ø 0.2 × 0.1 m, c = 150 µm)."""
    b = PlainBearing(diameter_m=0.2, length_m=0.1, clearance_m=150e-6, viscosity_pa_s=0.02)
    r = Rotor("r", uniform_elements(2.0, 0.3, 6), disks=(Disk(3, 1500.0, 20.0, 10.0),),
              supports=(Support(0, b), Support(6, b)))
    return Train((r,), gravity_m_s2=gravity_m_s2)


def test_a_more_heavily_loaded_plain_bearing_whirls_later():
    """The same rotor under 1, 2 and 4 g: the films carry 2 and 4 times the load at the same speed, run at a larger
    eccentricity and whirl later (the stability charts of plain bearings: the threshold rises as the Sommerfeld
    number falls). The radial-preload reading of misalignment rests on this."""
    onset = [threshold_speed_rpm(_rotor_on_plain_bearings(g), 20000.0, min_rpm=500.0, n_grid=10, tol_rpm=20.0,
                                 coefficients="film") for g in (9.81, 19.62, 39.24)]
    assert all(math.isfinite(v) for v in onset), onset
    assert onset[0] * 1.1 < onset[1] and onset[1] * 1.1 < onset[2], onset    # measured 5290, 6340, 7440 r/min


def test_the_threshold_is_where_the_log_decrement_changes_sign():
    t = _rotor_on_plain_bearings(9.81)
    thr = threshold_speed_rpm(t, 20000.0, min_rpm=500.0, n_grid=10, tol_rpm=20.0, coefficients="film")
    assert stability(t, thr, coefficients="film").log_decrement <= 0.0
    assert stability(t, thr - 20.0, coefficients="film").log_decrement > 0.0
    assert stability(t, 0.8 * thr, coefficients="film").stable


def test_film_coefficients_are_the_reduced_ones_on_fixed_bores_and_smaller_on_tilting_pads():
    """gen50_2pole has two-lobe bearings only (a fixed bore: the reduced coefficients are the film's); gen200_2pole's
    generator runs on tilting pads, whose film derivatives leave a smaller margin than Lund's reduced synchronous
    ones (docs/train.md: 0.162 against 0.434 on the straight bearing line)."""
    g50 = train_from_shaftline(preset("gen50_2pole"))
    a, b = stability(g50, 3000.0, coefficients="film"), stability(g50, 3000.0)
    assert a.log_decrement == pytest.approx(b.log_decrement, rel=1e-3, abs=1e-4)
    g200 = train_from_shaftline(preset("gen200_2pole"))
    film, red = stability(g200, 3000.0, coefficients="film"), stability(g200, 3000.0)
    assert 0.0 < film.log_decrement < 0.6 * red.log_decrement
    with pytest.raises(TrainError, match="coefficients must be one of"):
        stability(g200, 3000.0, coefficients="lund")


@pytest.mark.slow
def test_an_offset_that_unloads_the_generators_coupling_end_bearing_lowers_the_whirl_onset():
    """gen50_2pole on its catenary, the exciter raised by 1.5 c: bearing 3 takes load from bearing 2, which unloads,
    and the train whirls more than 10 % earlier (docs/train-misalignment.md: 4630 → 3610 r/min)."""
    rated = float(PRESETS["gen50_2pole"]["rated_speed_rpm"][0])
    tr = train_from_shaftline(preset("gen50_2pole"))
    al = with_moves(tr, aligned_offsets(tr, rated))
    c3 = float(tr.rotors[1].supports[0].bearing.clearance_m)
    up = misaligned(al, offset_m=1.5 * c3, direction_rad=math.pi / 2)
    load = [-static_state(t, rated).bearing_load_n[1, 1] for t in (al, up)]
    assert load[1] < 0.5 * load[0]
    onset = [threshold_speed_rpm(t, 3 * rated, min_rpm=0.5 * rated, n_grid=8, tol_rpm=25.0, coefficients="film")
             for t in (al, up)]
    assert onset[1] < 0.9 * onset[0], onset
