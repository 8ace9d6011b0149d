"""A stated speed_rpm locked to the signal's synchronous lines (features._speed_lock)."""
from __future__ import annotations

import numpy as np
import pytest

from rotordiag.features import _config as cfg
from rotordiag.features import extract_features
from rotordiag.features._speed_lock import locked_speed_hz

from .test_features_synth import DEFAULT_COMPONENTS, make_recording

RPM = 1953.7
FS = 5120.0
#: 4 s at 2560 Hz and 1953.7 r/min: 130 revolutions, a plant engineer's record length
LONG = {"fs": 2560.0, "n": 10240}


def _data(rec) -> np.ndarray:
    return np.stack([c.data for c in rec.channels])


@pytest.mark.parametrize("off", [-0.008, -0.003, 0.004, 0.009])
def test_a_stated_speed_off_by_up_to_one_percent_is_locked_to_the_signal(off):
    rec = make_recording(rpm=RPM, noise_um=0.5, seed=3, speed_rpm=RPM * (1 + off), **LONG)
    fr = extract_features(rec)
    assert fr.speed_source == "given"
    assert fr.speed_rpm == pytest.approx(RPM, rel=2e-5)
    assert "speed_off_signal" in {w.code for w in fr.warnings}
    assert "speed_off_line" not in {w.code for w in fr.warnings}     # the check after the lock is quiet
    # the orders are read as at the true speed (at the stated one, 0.4 % over 130 revolutions turns the 2X by
    # a whole revolution and its amplitude collapses)
    ref = extract_features(make_recording(rpm=RPM, noise_um=0.5, seed=3, speed_rpm=RPM, **LONG))
    for name in ("b2_x_1x_amp_um_pp", "b3_y_2x_amp_um_pp", "b1_x_3x_amp_um_pp", "dphase_1x_b2_b3_x_deg"):
        assert fr[name] == pytest.approx(ref[name], rel=1e-3, abs=0.05)


def test_the_stated_speed_is_used_exactly_when_it_is_right():
    fr = extract_features(make_recording(rpm=RPM, fs=FS, speed_rpm=RPM))
    assert fr.speed_rpm == pytest.approx(RPM, rel=1e-7)
    assert not {"speed_off_signal", "speed_off_line"} & {w.code for w in fr.warnings}


def test_a_stated_speed_further_off_is_kept():
    rec = make_recording(rpm=RPM, noise_um=0.5, seed=3, speed_rpm=RPM * 1.03, **LONG)
    fr = extract_features(rec)
    assert fr.speed_rpm == pytest.approx(RPM * 1.03, rel=1e-12)
    assert "speed_off_signal" not in {w.code for w in fr.warnings}


def test_one_line_alone_is_not_locked_to():
    """A 1X without a 2X or 3X above the noise: the line next to the stated speed might be an oil whirl's 2nd
    harmonic as well as the 1X, so the stated speed is kept (and its mismatch flagged as before)."""
    comps = {b: [(1, 30.0, 20.0 * b, 25.0, 110.0)] for b in (1, 2, 3, 4)}
    rec = make_recording(components=comps, rpm=RPM, noise_um=0.2, seed=4, speed_rpm=RPM * 1.004, **LONG)
    assert locked_speed_hz(_data(rec), rec.sample_rate_hz, RPM * 1.004 / 60) is None
    fr = extract_features(rec)
    assert fr.speed_rpm == pytest.approx(RPM * 1.004, rel=1e-12)


def test_lines_that_disagree_are_not_locked_to():
    """A strong non-synchronous line 0.5 % below 1X (an oil whirl at 0.4975X: its 2nd harmonic) beside a clean
    2X: the two read speeds 0.5 % apart, one of them is not the running speed, and the stated one is kept."""
    comps = {b: [(1, 4.0, 20.0 * b, 3.0, 110.0), (2, 20.0, 40.0, 15.0, 130.0)] for b in (1, 2, 3, 4)}
    f_w2 = 2 * 0.4975 * RPM / 60

    def whirl_2nd(t, b):
        return 40 * np.cos(2 * np.pi * f_w2 * t), 40 * np.sin(2 * np.pi * f_w2 * t)

    rec = make_recording(components=comps, rpm=RPM, extra=whirl_2nd, noise_um=0.1, seed=5, speed_rpm=RPM, **LONG)
    assert locked_speed_hz(_data(rec), rec.sample_rate_hz, RPM / 60) is None
    # without the foreign line the same orders lock
    clean = make_recording(components=comps, rpm=RPM, noise_um=0.1, seed=5, speed_rpm=RPM * 1.004, **LONG)
    assert locked_speed_hz(_data(clean), clean.sample_rate_hz, RPM * 1.004 / 60) == pytest.approx(RPM / 60, rel=2e-5)


def test_lock_bounds():
    rec = make_recording(rpm=RPM, components=DEFAULT_COMPONENTS, **LONG)
    data = _data(rec)
    assert locked_speed_hz(data[:, :8], rec.sample_rate_hz, RPM / 60) is None           # too short to say
    assert locked_speed_hz(data, rec.sample_rate_hz, 0.0) is None
    # the window is the configured one: 1.5 % off is outside ±1 %
    assert cfg.SPEED_LOCK_MAX_REL == 0.01
    assert locked_speed_hz(data, rec.sample_rate_hz, RPM * 1.015 / 60) is None
