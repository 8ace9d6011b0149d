"""The extractor's speed-ups change no feature: every value of the pinned recordings as it was before them.

``tests/reference/features_pinned.npz`` was written by ``tests/reference/features_pinned.py`` before the
feature extraction was made faster (issue 43 item 7): vectorised or compiled code must reproduce the same floats
(1e-9 relative; NaN where NaN), the same speed, revolutions, warning and sanity codes, and order coefficients.
"""
from __future__ import annotations

import numpy as np
import pytest

from tests.reference.features_pinned import PINNED, recordings, summary

_pinned = np.load(PINNED)
_CASES = sorted({k.split("/")[0] for k in _pinned.files if "/" in k})


@pytest.fixture(scope="module")
def cases() -> dict[str, object]:
    return recordings(_pinned["input_bench_um"])


@pytest.mark.parametrize("name", _CASES)
def test_features_as_pinned(cases: dict[str, object], name: str) -> None:
    from rotordiag.features import extract_features

    got = summary(extract_features(cases[name]))
    want = {k.split("/", 1)[1]: _pinned[k] for k in _pinned.files if k.startswith(name + "/")}
    assert sorted(got) == sorted(want)
    for key, w in want.items():
        g = got[key]
        if w.dtype.kind in "US":
            assert g.tolist() == w.tolist(), key
        else:
            # 1e-9 relative; a value within 1e-12 of zero (a phase difference of a few µrad, a ratio of noise) is
            # compared absolutely: its last bits differ between NumPy releases (seen at the dependency floors)
            np.testing.assert_allclose(g, w, rtol=1e-9, atol=1e-12, equal_nan=True, err_msg=f"{name}: {key}")


def test_pinned_cases_cover_the_ways_through_the_extractor() -> None:
    """The pinned set takes a given, an estimated and a keyphasor speed, and a record with a whirl line."""
    assert {"bench_given", "bench_estimated", "analytic_keyphasor", "analytic_whirl"} <= set(_CASES)
    assert any(len(_pinned[f"{c}/warnings"]) and _pinned[f"{c}/warnings"][0] == "speed_off_signal" for c in _CASES)
