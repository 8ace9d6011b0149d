"""A keyphasor pulse train with missing or extra pulses (features._keyphasor): not tracked, said."""
from __future__ import annotations

import numpy as np
import pytest

from rotordiag.features import extract_features
from rotordiag.features._keyphasor import KEYPHASOR_JUMP_MAX, keyphasor_fault

from .test_features_synth import DEFAULT_COMPONENTS, keyphasor_times, make_recording

RPM = 1953.7
DURATION_S = 16384 / 5120.0


def _missing_every(pulses: np.ndarray, k: int) -> np.ndarray:
    return np.delete(pulses, np.arange(k - 1, pulses.size, k))


def test_a_sound_train_and_a_run_down_are_no_fault():
    assert keyphasor_fault(keyphasor_times(RPM, DURATION_S, 0.01)) is None
    # a speed falling 3 % over the record (far faster than any turbine-generator's coast-down)
    f0, ramp = RPM / 60.0, -0.03
    acc = f0 * ramp / DURATION_S
    m = np.arange(0, int(f0 * DURATION_S * (1 + ramp / 2)))
    assert keyphasor_fault((-f0 + np.sqrt(f0 ** 2 + 2 * acc * m)) / acc) is None
    assert keyphasor_fault(np.array([0.0, 0.03, 0.09])) is None            # two intervals: not judged


def test_missing_pulses_are_found_and_the_period_read_from_the_sound_ones():
    period = 60.0 / RPM
    fault = keyphasor_fault(_missing_every(keyphasor_times(RPM, DURATION_S, 0.01), 5))
    assert fault is not None and fault.n_off >= 15
    assert fault.ratios[1] == pytest.approx(2.0, rel=0.01)
    assert fault.period_s == pytest.approx(period, rel=1e-9)
    assert "missing pulses" in fault.describe()


def test_a_second_edge_every_revolution_leaves_no_period():
    pulses = keyphasor_times(RPM, DURATION_S, 0.01)
    both = np.sort(np.concatenate([pulses, pulses + 0.37 * 60.0 / RPM]))
    fault = keyphasor_fault(both)
    assert fault is not None and fault.period_s is None
    assert fault.ratios[0] < 1.0 - KEYPHASOR_JUMP_MAX and "extra pulses" in fault.describe()


@pytest.mark.parametrize("speed_given", [False, True])
def test_orders_are_not_tracked_by_a_faulty_train(speed_given):
    """Every 5th pulse missing: the orders come out as with the speed given (phases from the first sample, so
    amplitudes only), the warning says the keyphasor was not used, and the sanity warning says what to check."""
    kp = _missing_every(keyphasor_times(RPM, DURATION_S, 0.01), 5)
    extra = {"speed_rpm": RPM} if speed_given else {}
    fr = extract_features(make_recording(rpm=RPM, keyphasor_times_s=kp, **extra))
    # the speed from the sound pulse intervals is not one the user gave, and says so
    assert fr.speed_source == ("given" if speed_given else "keyphasor intervals")
    assert fr.phase_reference == "first sample"
    assert fr.speed_rpm == pytest.approx(RPM, rel=1e-6)
    assert fr.warnings[0].code == "keyphasor_not_used" and fr.warnings[0].values["speed_rpm"] == fr.speed_rpm
    finding = [f for f in fr.sanity if f.code == "keyphasor_faulty"]
    assert len(finding) == 1 and finding[0].level == "warn" and finding[0].variant == "default"
    assert finding[0].values["fault"]                                       # what is wrong with the pulse train
    for b, comps in DEFAULT_COMPONENTS.items():
        for k, ax, _, ay, _ in comps:
            assert fr[f"b{b}_x_{k}x_amp_um_pp"] == pytest.approx(2 * ax, rel=2e-3)
            assert fr[f"b{b}_y_{k}x_amp_um_pp"] == pytest.approx(2 * ay, rel=2e-3)


def test_a_faulty_train_without_a_period_falls_back_to_the_signals_speed():
    pulses = keyphasor_times(RPM, DURATION_S, 0.01)
    both = np.sort(np.concatenate([pulses, pulses + 0.37 * 60.0 / RPM]))
    fr = extract_features(make_recording(rpm=RPM, keyphasor_times_s=both))
    assert fr.speed_source == "estimated" and fr.speed_rpm == pytest.approx(RPM, rel=1e-3)
    assert fr.warnings[0].code == "keyphasor_not_used" and fr.warnings[0].values["source"] == "estimated from the signal"
    assert "keyphasor_faulty" in {f.code for f in fr.sanity}


def test_slow_roll_vectors_need_a_sound_keyphasor():
    """Slow-roll vectors are keyphasor-referenced: with a faulty pulse train there is no such reference, so the
    recording is refused with what to fix instead of subtracting vectors at a wrong phase."""
    import dataclasses

    kp = _missing_every(keyphasor_times(RPM, DURATION_S, 0.01), 5)
    rec = make_recording(rpm=RPM, keyphasor_times_s=kp)
    rec = dataclasses.replace(rec, channels=[dataclasses.replace(c, slow_roll_um_pp={1: (3.0, 40.0)})
                                             for c in rec.channels])
    with pytest.raises(ValueError, match="slow-roll compensation needs the keyphasor's phase reference"):
        extract_features(rec)


def test_a_slow_roll_recording_needs_a_sound_keyphasor():
    from rotordiag.features import slow_roll_vectors

    kp = _missing_every(keyphasor_times(RPM, DURATION_S, 0.01), 5)
    with pytest.raises(ValueError, match="slow-roll recording: keyphasor_times_s not used"):
        slow_roll_vectors(make_recording(rpm=RPM, keyphasor_times_s=kp))
