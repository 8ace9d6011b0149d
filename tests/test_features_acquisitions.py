"""Bearings recorded in separate acquisitions (features._acquisitions, Recording.acquisitions): the phase
differences between takes are missing, not the delay between them."""
from __future__ import annotations

import numpy as np
import pytest

from rotordiag.features import (
    ProbeChannel,
    Recording,
    evidence,
    extract_features,
    format_acquisitions,
    parse_acquisitions,
    split_pairs,
)

FS_HZ = 2048.0
SPEED_RPM = 3000.0
PAIRS = ((2, 3), (1, 2), (3, 4))


def _channels(delay_34_s: float = 0.0, n: int = 4096) -> list[ProbeChannel]:
    """A 1X + 2X orbit at every bearing, in phase along the train (shaft ends moving together), with bearings 3 and 4
    read ``delay_34_s`` later (a second take started that much earlier in the shaft's motion)."""
    f1 = SPEED_RPM / 60.0
    out = []
    for b in (1, 2, 3, 4):
        t = np.arange(n) / FS_HZ + (delay_34_s if b >= 3 else 0.0)
        x = 20.0 * np.cos(2 * np.pi * f1 * t) + 4.0 * np.cos(2 * np.pi * 2 * f1 * t + 0.3)
        y = 20.0 * np.sin(2 * np.pi * f1 * t) + 4.0 * np.sin(2 * np.pi * 2 * f1 * t + 0.3)
        for a in (45.0, 135.0):
            th = np.deg2rad(a)
            out.append(ProbeChannel(b, a, "um", x * np.cos(th) + y * np.sin(th) - 150.0))
    return out


@pytest.mark.parametrize("text, groups", [("1,2;3,4", ((1, 2), (3, 4))), (" 3 , 4 ; 2,1 ", ((1, 2), (3, 4))),
                                          ("1;2;3;4", ((1,), (2,), (3,), (4,))), ("1,2,3,4", ((1, 2, 3, 4),)),
                                          ([[4, 3], [1, 2]], ((1, 2), (3, 4))), ("2,3;1,4;", ((1, 4), (2, 3)))])
def test_parse_and_format(text, groups):
    assert parse_acquisitions(text) == groups
    assert parse_acquisitions(format_acquisitions(groups)) == groups


@pytest.mark.parametrize("bad, words", [("1,2;2,3", "bearing 2 is in more than one"), ("1,1;3", "bearing 1 is in more"),
                                        ("1,9;3", "'9' is not a bearing"), ("a;b", "'a' is not a bearing"),
                                        ([[1.5, 2], [3]], "1.5 is not a bearing"), ([[True], [2]], "True is not"),
                                        ([[1, 2], []], "[1] is empty"), ("", "is empty"), ([], "is empty"),
                                        (12, "must be groups"), ([12], "[0] must be a group"), ({"1": 2}, "must be groups")])
def test_bad_groups_say_what_to_give(bad, words):
    with pytest.raises(ValueError, match="e.g. \"1,2;3,4\"") as exc:
        parse_acquisitions(bad)
    assert words in str(exc.value)


def test_split_pairs():
    assert split_pairs(((1, 2), (3, 4)), PAIRS) == ((2, 3),)
    assert split_pairs(((1,), (2, 3, 4)), PAIRS) == ((1, 2),)
    assert split_pairs(((1,), (2,), (3,), (4,)), PAIRS) == PAIRS
    assert split_pairs((), PAIRS) == () and split_pairs(None, PAIRS) == ()
    assert split_pairs(((2,), (3,)), PAIRS) == ((2, 3),)        # pairs with an unrecorded bearing are not split


def test_recording_normalises_and_refuses():
    ch = _channels()
    assert Recording(FS_HZ, ch, speed_rpm=SPEED_RPM, acquisitions="1,2;3,4").acquisition_groups == ((1, 2), (3, 4))
    # one group, or none: every channel sampled together
    assert Recording(FS_HZ, ch, speed_rpm=SPEED_RPM, acquisitions="1,2,3,4").acquisitions is None
    assert Recording(FS_HZ, ch, speed_rpm=SPEED_RPM).acquisition_groups == ()
    # a bearing listed but not recorded is left out; a recorded one in no group is refused
    only23 = [c for c in ch if c.bearing in (2, 3)]
    assert Recording(FS_HZ, only23, speed_rpm=SPEED_RPM, acquisitions="1,2;3,4").acquisition_groups == ((2,), (3,))
    assert Recording(FS_HZ, only23, speed_rpm=SPEED_RPM, acquisitions="1,2,3;4").acquisitions is None
    with pytest.raises(ValueError, match="bearing 4 is recorded but in no acquisition"):
        Recording(FS_HZ, ch, speed_rpm=SPEED_RPM, acquisitions="1,2;3")
    with pytest.raises(ValueError, match="one pulse train cannot reference takes"):
        Recording(FS_HZ, ch, keyphasor_times_s=np.arange(0.0, 2.0, 0.02), acquisitions="1,2;3,4")


def test_phases_between_takes_are_missing_not_the_delay():
    """Bearings 3 and 4 read 2 ms later: sent as one recording, the phase across the coupling is the delay's
    (360°·f·τ = 36° at 1X, 72° at 2X, at 50 Hz); stated as two takes, it is missing and said, while the phases within
    each take stay (and are the shaft's: 0°)."""
    tau = 0.002
    f1 = SPEED_RPM / 60.0
    as_one = extract_features(Recording(FS_HZ, _channels(tau), speed_rpm=SPEED_RPM, clearance_um=350.0))
    for k in (1, 2):
        for d in ("x", "y"):
            assert as_one[f"dphase_{k}x_b2_b3_{d}_deg"] == pytest.approx(360.0 * k * f1 * tau, abs=0.5)
            assert as_one[f"dphase_{k}x_b1_b2_{d}_deg"] == pytest.approx(0.0, abs=0.5)
    assert as_one.acquisitions == ()
    takes = extract_features(Recording(FS_HZ, _channels(tau), speed_rpm=SPEED_RPM, clearance_um=350.0,
                                       acquisitions="1,2;3,4"))
    assert takes.acquisitions == ((1, 2), (3, 4))
    for k in (1, 2):
        for d in ("x", "y"):
            assert np.isnan(takes[f"dphase_{k}x_b2_b3_{d}_deg"])
            for pair in ("b1_b2", "b3_b4"):
                assert takes[f"dphase_{k}x_{pair}_{d}_deg"] == pytest.approx(0.0, abs=0.5)
    # every other feature is the recording's own
    other = [i for i, n in enumerate(takes.names) if "_b2_b3_" not in n]
    np.testing.assert_array_equal(takes.values[other], as_one.values[other])
    said = [w for w in takes.warnings if w.code == "separate_acquisitions_unreferenced"]
    assert said and said[0].values["groups"] == "1,2;3,4" and said[0].values["pairs"] == "bearings 2 and 3"
    coupling = [e for e in evidence(takes) if e.scope == "coupling 2–3"]
    assert len(coupling) == 1 and coupling[0].value.startswith("not measured (bearings 2 and 3 recorded in separate")
    assert "record bearings 2 and 3 together" in coupling[0].meaning
    assert [e.name for e in evidence(as_one) if e.scope == "coupling 2–3"] == [
        "1X phase difference x", "1X phase difference y", "2X phase difference x", "2X phase difference y"]
