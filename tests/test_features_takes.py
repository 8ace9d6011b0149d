"""Bearings recorded in separate takes, each with its own keyphasor (features._takes): every take's orders are
referenced to the same mark on the shaft, so the phase differences across the takes are measured."""
from __future__ import annotations

import numpy as np
import pytest

from rotordiag.features import ProbeChannel, Recording, extract_features, parse_keyphasor_takes

FS_HZ = 2048.0
SPEED_RPM = 3000.0
F1_HZ = SPEED_RPM / 60.0
N = 4096
#: the 1X and 2X phase of bearings 3 and 4 relative to 1 and 2: anti-phase across the coupling at 1X, 60° at 2X
ACROSS_DEG = (180.0, 60.0)
#: the keyphasor mark passes the probe at this shaft angle after t = 0 of the first take (rad)
MARK_RAD = 1.1


def _channels(delay_34_s: float = 0.0, speed_34_rpm: float = SPEED_RPM) -> list[ProbeChannel]:
    """A forward 1X + 2X orbit at every bearing, bearings 3 and 4 shifted by :data:`ACROSS_DEG`, and read
    ``delay_34_s`` later on their own clock (a second take), turning at ``speed_34_rpm``."""
    out = []
    for b in (1, 2, 3, 4):
        f1 = F1_HZ if b <= 2 else speed_34_rpm / 60.0
        t = np.arange(N) / FS_HZ + (delay_34_s if b >= 3 else 0.0)
        p1, p2 = (np.deg2rad(ACROSS_DEG[0]), np.deg2rad(ACROSS_DEG[1])) if b >= 3 else (0.0, 0.0)
        x = 20.0 * np.cos(2 * np.pi * f1 * t - p1) + 4.0 * np.cos(4 * np.pi * f1 * t + 0.3 - p2)
        y = 20.0 * np.sin(2 * np.pi * f1 * t - p1) + 4.0 * np.sin(4 * np.pi * f1 * t + 0.3 - p2)
        for a in (45.0, 135.0):
            th = np.deg2rad(a)
            out.append(ProbeChannel(b, a, "um", x * np.cos(th) + y * np.sin(th) - 150.0 + 0.01 * b))
    return out


def _pulses(delay_s: float = 0.0, speed_rpm: float = SPEED_RPM) -> np.ndarray:
    """The keyphasor pulses on a take's clock that starts ``delay_s`` after the first take's."""
    period = 60.0 / speed_rpm
    t = MARK_RAD / (2 * np.pi) * period + period * np.arange(200) - delay_s
    return t[(t >= 0) & (t <= (N - 1) / FS_HZ)]


def _across(fr) -> list[float]:
    return [fr[f"dphase_{k}x_b2_b3_{d}_deg"] for k in (1, 2) for d in ("x", "y")]


def test_a_keyphasor_per_take_measures_the_phase_across_the_coupling():
    delay = 0.0073
    together = extract_features(Recording(FS_HZ, _channels(), keyphasor_times_s=_pulses()))
    takes = extract_features(Recording(FS_HZ, _channels(delay), keyphasor_times_s=[_pulses(), _pulses(delay)],
                                       acquisitions="1,2;3,4"))
    # anti-phase at 1X and 60° at 2X across the coupling, whatever the delay between the takes
    assert np.allclose(np.abs(_across(together)), [180, 180, 60, 60], atol=1e-6)
    assert np.allclose(_across(takes), _across(together), atol=1e-6)
    both = np.isfinite(together.values)
    assert np.array_equal(both, np.isfinite(takes.values))
    # the same features (the direct pk-pk reads the sampled extremes, which the take's clock moves by 1e-6)
    assert np.allclose(takes.values[both], together.values[both], rtol=1e-5, atol=1e-9)
    assert takes.acquisitions == () and takes.phase_reference == "keyphasor" and takes.speed_source == "keyphasor"
    assert "separate_acquisitions_referenced" in {w.code for w in takes.warnings}
    assert not any(s.code == "keyphasor_faulty" for s in takes.sanity)
    # without the keyphasors the phases between the takes are missing, not the delay's
    bare = extract_features(Recording(FS_HZ, _channels(delay), speed_rpm=SPEED_RPM, acquisitions="1,2;3,4"))
    assert np.all(np.isnan(_across(bare))) and bare.acquisitions == ((1, 2), (3, 4))


def test_trains_follow_the_order_the_acquisitions_are_listed():
    delay = 0.0041
    listed = extract_features(Recording(FS_HZ, _channels(delay), keyphasor_times_s=[_pulses(delay), _pulses()],
                                        acquisitions="3,4;1,2"))
    assert np.allclose(np.abs(_across(listed)), [180, 180, 60, 60], atol=1e-6)
    # the same trains the other way round pair each take with the other's mark: the phases are the delay's
    swapped = extract_features(Recording(FS_HZ, _channels(delay), keyphasor_times_s=[_pulses(), _pulses(delay)],
                                         acquisitions="3,4;1,2"))
    assert not np.allclose(np.abs(_across(swapped)), [180, 180, 60, 60], atol=1.0)


def test_trains_as_text_and_refusals():
    assert np.array_equal(parse_keyphasor_takes("0.1, 0.2,0.3"), [0.1, 0.2, 0.3])
    two = parse_keyphasor_takes("0.1,0.2;0.15,0.25;")
    assert isinstance(two, tuple) and [list(t) for t in two] == [[0.1, 0.2], [0.15, 0.25]]
    with pytest.raises(ValueError, match=r"keyphasor_times_s\[1\] must be strictly increasing"):
        parse_keyphasor_takes([[0.1, 0.2], [0.3, 0.2]])
    with pytest.raises(ValueError, match="separated by commas"):
        parse_keyphasor_takes("0.1,x;0.2,0.3")
    ch = _channels()
    with pytest.raises(ValueError, match="2 pulse train.*but no acquisitions"):
        Recording(FS_HZ, ch, keyphasor_times_s=[_pulses(), _pulses()])
    with pytest.raises(ValueError, match="3 pulse trains for 2 acquisitions"):
        Recording(FS_HZ, ch, keyphasor_times_s=[_pulses()] * 3, acquisitions="1,2;3,4")
    with pytest.raises(ValueError, match="one pulse train cannot reference takes.*one pulse train per acquisition"):
        Recording(FS_HZ, ch, keyphasor_times_s=_pulses(), acquisitions="1,2;3,4")
    # a take whose bearings are not recorded drops its train: one take left, one train
    only12 = [c for c in ch if c.bearing <= 2]
    rec = Recording(FS_HZ, only12, keyphasor_times_s=[_pulses(), _pulses(0.003)], acquisitions="1,2;3,4")
    assert rec.keyphasor_takes is None and np.array_equal(rec.keyphasor_times_s, _pulses())
    slow = [ProbeChannel(c.bearing, c.angle_deg, c.units, c.data, slow_roll_um_pp={1: (1.0, 10.0)}) for c in ch]
    with pytest.raises(ValueError, match="slow_roll_um_pp with one keyphasor per acquisition is not supported"):
        Recording(FS_HZ, slow, keyphasor_times_s=[_pulses(), _pulses()], acquisitions="1,2;3,4")
    # a take's own refusal names the take
    with pytest.raises(ValueError, match="the take of bearings 3, 4: keyphasor_times_s: 0 pulse"):
        extract_features(Recording(FS_HZ, ch, keyphasor_times_s=[_pulses(), [50.0, 50.02]], acquisitions="1,2;3,4"))


def test_a_faulty_train_leaves_that_take_unreferenced():
    delay = 0.0052
    faulty = np.delete(_pulses(delay), np.arange(4, _pulses(delay).size, 5))      # every 5th pulse missing
    fr = extract_features(Recording(FS_HZ, _channels(delay), keyphasor_times_s=[_pulses(), faulty],
                                    acquisitions="1,2;3,4", speed_rpm=SPEED_RPM))
    assert np.all(np.isnan(_across(fr))) and fr.acquisitions == ((1, 2), (3, 4))
    assert np.isfinite(fr["dphase_1x_b1_b2_x_deg"]) and np.isfinite(fr["dphase_1x_b3_b4_x_deg"])
    found = [s for s in fr.sanity if s.code == "keyphasor_faulty"]
    assert len(found) == 1 and found[0].variant == "take" and found[0].values["bearings"] == "3, 4"
    assert any(w.code == "separate_acquisitions_unreferenced"
               and w.values["why"].startswith("the keyphasor of the take of bearings 3, 4 could not be used")
               for w in fr.warnings)


def test_takes_at_different_speeds_are_said():
    fast = SPEED_RPM * 1.03
    fr = extract_features(Recording(FS_HZ, _channels(0.002, speed_34_rpm=fast),
                                    keyphasor_times_s=[_pulses(), _pulses(0.002, fast)], acquisitions="1,2;3,4"))
    assert any(w.code == "takes_speeds_differ" and f"{fast:.1f} r/min" in w.values["speeds"] for w in fr.warnings)
    assert SPEED_RPM < fr.speed_rpm < fast


def test_the_least_regular_motion_of_the_takes_is_reported():
    """Oil whirl (0.43X) seen only at bearings 3 and 4: sampled together the motion is not periodic, and with one
    keyphasor per take the same is reported, with a warning naming each take's type."""
    def with_whirl(channels, delay_s=0.0):
        out = []
        for c in channels:
            t = np.arange(N) / FS_HZ + (delay_s if c.bearing >= 3 else 0.0)
            whirl = 6.0 * np.cos(2 * np.pi * 0.43 * F1_HZ * t - np.deg2rad(c.angle_deg)) if c.bearing >= 3 else 0.0
            out.append(ProbeChannel(c.bearing, c.angle_deg, c.units, c.data + whirl))
        return out

    delay = 0.006
    together = extract_features(Recording(FS_HZ, with_whirl(_channels()), keyphasor_times_s=_pulses()))
    takes = extract_features(Recording(FS_HZ, with_whirl(_channels(delay), delay), acquisitions="1,2;3,4",
                                       keyphasor_times_s=[_pulses(), _pulses(delay)]))
    assert together.motion_type.kind != "period-n"
    assert takes.motion_type.kind == together.motion_type.kind
    for name in ("motion_period", "motion_quasi_periodic", "motion_chaotic"):
        assert takes[name] == together[name]
    assert any(w.code == "takes_motion_differ"
               and w.values["motions"].startswith("bearings 1, 2: period-1, bearings 3, 4: ") for w in takes.warnings)


def _pulse_channel(pulses: np.ndarray) -> np.ndarray:
    """A keyphasor probe's output: −8 V, dropping to −12 V for 1 ms at each pulse (a notch)."""
    t = np.arange(N) / FS_HZ
    v = np.full(N, -8.0)
    for p in pulses:
        v[(t >= p) & (t < p + 0.001)] = -12.0
    return v


def test_a_raw_keyphasor_channel_per_take_from_csv_and_npy():
    from rotordiag.features.reader import ReadOptions, read_recording

    delay = 0.0073
    chans = _channels(delay)
    kp1, kp2 = _pulse_channel(_pulses()), _pulse_channel(_pulses(delay))
    layout = ",".join(f"{c.bearing}@{c.angle_deg:g}" for c in chans)
    header = "time_s," + ",".join(f"b{c.bearing}_{c.angle_deg:g}" for c in chans) + ",kp_a,kp_b"
    rows = np.column_stack([np.arange(N) / FS_HZ, *[c.data for c in chans], kp1, kp2])
    csv = (header + "\n" + "\n".join(",".join(f"{v:.9g}" for v in r) for r in rows)).encode()
    mapping = {f"b{c.bearing}_{c.angle_deg:g}": f"b{c.bearing}@{c.angle_deg:g}" for c in chans}
    want = extract_features(Recording(FS_HZ, chans, keyphasor_times_s=[_pulses(), _pulses(delay)],
                                      acquisitions="1,2;3,4"))
    res = read_recording(csv, filename="takes.csv", options=ReadOptions(
        channels=mapping, keyphasor_channel="KP_A; kp_b", acquisitions="1,2;3,4"))
    assert res.recording.keyphasor_takes is not None and any("one per acquisition" in n for n in res.notes)
    got = extract_features(res.recording)
    # pulse times from the falling edge, interpolated between samples: within a sample of the exact ones
    gap = (np.array(_across(got)) - np.array(_across(want)) + 180.0) % 360.0 - 180.0
    assert np.all(np.abs(gap) < 0.5)
    arr = np.vstack([*[c.data for c in chans], kp1, kp2])
    buf = __import__("io").BytesIO()
    np.save(buf, arr)
    res = read_recording(buf.getvalue(), filename="takes.npy", options=ReadOptions(
        sample_rate_hz=FS_HZ, channels=layout, keyphasor_channel="8;9", acquisitions="1,2;3,4"))
    assert np.allclose(_across(extract_features(res.recording)), _across(got), atol=1e-9)
    with pytest.raises(ValueError, match="have no names; give the keyphasor channel's index"):
        read_recording(buf.getvalue(), filename="takes.npy", options=ReadOptions(
            sample_rate_hz=FS_HZ, channels=layout, keyphasor_channel="kp_a;kp_b", acquisitions="1,2;3,4"))
    with pytest.raises(ValueError, match="2 keyphasor channels .kp_a;kp_b. for 1 acquisition"):
        read_recording(csv, filename="takes.csv", options=ReadOptions(channels=mapping, keyphasor_channel="kp_a;kp_b"))
    with pytest.raises(ValueError, match="keyphasor channel 'kp_c' is not a column"):
        read_recording(csv, filename="takes.csv", options=ReadOptions(
            channels=mapping, keyphasor_channel="kp_a;kp_c", acquisitions="1,2;3,4"))


def test_pulse_limit_counts_every_take():
    from rotordiag.features.reader import ReadLimits, recording_from_dict

    body = {"sample_rate_hz": FS_HZ, "acquisitions": "1,2;3,4",
            "keyphasor_times_s": [_pulses()[:8].tolist(), _pulses(0.002)[:8].tolist()],
            "channels": [{"bearing": c.bearing, "angle_deg": c.angle_deg, "units": "um", "data": c.data.tolist()}
                         for c in _channels(0.002)]}
    assert recording_from_dict(body, limits=ReadLimits(max_keyphasor_pulses=16)).recording.keyphasor_takes
    with pytest.raises(ValueError, match="16 keyphasor pulses; at most 15 are accepted"):
        recording_from_dict(body, limits=ReadLimits(max_keyphasor_pulses=15))


def test_merge_takes_cuts_to_the_shortest_and_refuses_mismatches():
    from rotordiag.features.reader import ReadResult
    from rotordiag.features.take_files import merge_takes

    delay = 0.0061
    chans = _channels(delay)
    first = Recording(FS_HZ, chans[:4], keyphasor_times_s=_pulses(), clearance_um=300.0)
    longer = [ProbeChannel(c.bearing, c.angle_deg, c.units, np.concatenate([c.data, c.data[:100]])) for c in chans[4:]]
    second = Recording(FS_HZ, longer, keyphasor_times_s=_pulses(delay), clearance_um={3: 300.0, 4: 320.0})
    res = merge_takes([ReadResult(first, "csv", ["a note"]), ReadResult(second, "npy")], ["a.csv", "b.npy"])
    rec = res.recording
    assert rec.acquisition_groups == ((1, 2), (3, 4)) and rec.n_points == N and rec.keyphasor_takes is not None
    assert rec.clearance_for(1) == 300.0 and rec.clearance_for(4) == 320.0 and res.format == "csv+npy"
    assert "a.csv: a note" in res.notes and "cut to the shortest take's 4096 samples" in res.notes[0]
    want = extract_features(Recording(FS_HZ, chans, keyphasor_times_s=[_pulses(), _pulses(delay)],
                                      acquisitions="1,2;3,4"))
    assert np.allclose(_across(extract_features(rec)), _across(want), atol=1e-9)
    other_rate = Recording(FS_HZ * 1.01, chans[4:], keyphasor_times_s=_pulses(delay))
    with pytest.raises(ValueError, match=r"different sample rates \(Hz\): a.csv: 2048, b.npy: 2068.48"):
        merge_takes([ReadResult(first, "csv"), ReadResult(other_rate, "npy")], ["a.csv", "b.npy"])
    fast = Recording(FS_HZ, chans[4:], speed_rpm=3100.0)
    slow = Recording(FS_HZ, chans[:4], speed_rpm=3000.0)
    with pytest.raises(ValueError, match="different running speeds"):
        merge_takes([ReadResult(slow, "csv"), ReadResult(fast, "csv")], ["a", "b"])
    split = Recording(FS_HZ, chans, speed_rpm=3000.0, acquisitions="1,2;3,4")
    with pytest.raises(ValueError, match="a: is itself recorded in separate acquisitions"):
        merge_takes([ReadResult(split, "csv"), ReadResult(fast, "csv")], ["a", "b"])
