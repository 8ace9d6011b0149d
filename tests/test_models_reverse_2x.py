"""A misalignment call on a coupling 2X that whirls backward (models.checks.reverse_2x): never confident."""
from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

from rotordiag.features import ProbeChannel, Recording
from rotordiag.models.checks.reverse_2x import REVERSE_2X_MIN_RATIO, coupling_reverse_2x, reverse_2x_reason

REGISTRY = Path(__file__).resolve().parent.parent / "models" / "default_registry"
NAMES = ["b2_2x_major_um_pp", "b2_2x_rev_fwd_ratio", "b3_2x_major_um_pp", "b3_2x_rev_fwd_ratio"]


@pytest.mark.parametrize("row, found", [
    ([10.0, 0.3, 8.0, 0.5], None),                       # forward at both: a shaft's 2X
    ([10.0, 2.5, 8.0, 0.5], (2, 2.5)),                   # backward at bearing 2
    ([10.0, 0.3, 8.0, 3.0], (3, 3.0)),
    ([10.0, 2.5, 8.0, 3.0], (3, 3.0)),                   # the more backward of the two
    ([10.0, 0.3, 4.0, 9.0], None),                       # bearing 3's 2X is too small to have a direction
    ([10.0, REVERSE_2X_MIN_RATIO, 1.0, 0.1], (2, REVERSE_2X_MIN_RATIO)),
    ([np.nan, np.nan, 8.0, 2.5], (3, 2.5)),              # bearing 2 not measured
    ([np.nan, np.nan, np.nan, np.nan], None),
    ([0.0, 5.0, 0.0, 5.0], None),                        # no 2X at all
])
def test_which_coupling_bearing_whirls_backward(row, found):
    assert coupling_reverse_2x(NAMES, np.array(row)) == found
    reason = reverse_2x_reason(NAMES, np.array(row), misaligned_call=True)
    assert (reason is None) == (found is None)
    assert reverse_2x_reason(NAMES, np.array(row), misaligned_call=False) is None
    if reason is not None:
        assert reason.code == "reverse_2x" and reason.status == "uncertain"
        assert reason.values == {"bearing": found[0], "reverse_per_forward": found[1]}


def test_a_backward_2x_at_the_coupling_makes_a_misalignment_call_uncertain():
    """The default plant (Δ 0.3) is a confident misalignment call with a forward coupling 2X; with a 2X of 12 µm
    whirling backward added at bearings 2 and 3 (a phase of its own on each probe's cable reads so) it is still
    called misaligned, uncertain with ``reverse_2x``; the same 2X whirling forward adds no such reason."""
    from rotordiag.models.pipeline import diagnose_recording
    from rotordiag.models.predict import load_bundle
    from tests.service_util import simulated_channels

    if not (REGISTRY / "active").exists():
        pytest.skip("no shipped registry in this checkout")
    bundle = load_bundle(REGISTRY)
    fs, ch = simulated_channels(misalignment=0.3, record_revs=48)
    t = np.arange(len(ch[0][2])) / fs
    th = 2 * np.pi * 1800.0 / 60.0 * t

    def with_2x(direction: float) -> Recording:
        out = []
        for b, a, d in ch:
            x, y = 12.0 * np.cos(2 * th), direction * 12.0 * np.sin(2 * th)     # +1 forward, −1 backward
            add = (x * np.cos(np.deg2rad(a)) + y * np.sin(np.deg2rad(a))) if b in (2, 3) else 0.0
            out.append(ProbeChannel(b, a, "um", d + add))
        return Recording(fs, out, speed_rpm=1800.0, clearance_um=350.0)

    plain, _ = diagnose_recording(bundle, Recording(fs, [ProbeChannel(b, a, "um", d) for b, a, d in ch],
                                                    speed_rpm=1800.0, clearance_um=350.0))
    assert plain.status == "confident" and plain.severity != "aligned"
    backward, fr = diagnose_recording(bundle, with_2x(-1.0))
    assert max(fr["b2_2x_rev_fwd_ratio"], fr["b3_2x_rev_fwd_ratio"]) >= REVERSE_2X_MIN_RATIO
    codes = [r["code"] for r in backward.reasons]
    assert backward.model_severity != "aligned" and "reverse_2x" in codes and backward.status != "confident"
    forward, _ = diagnose_recording(bundle, with_2x(+1.0))
    assert "reverse_2x" not in [r["code"] for r in forward.reasons]
