"""Orbit shape: whirl direction, ellipticity, loops and figure-8s, area, peak-to-peak."""
from __future__ import annotations

import numpy as np
import pytest

from rotordiag.features import extract_features
from rotordiag.features._orbit import orbit_shape

from .test_features_synth import make_recording

RPM = 1953.7


def _z_record(zfun, **kw):
    """A recording (bearing 2 only) whose orbit is x + jy = zfun(θ)."""
    def extra(t, b):
        z = zfun(2 * np.pi * RPM / 60 * t)
        return z.real, z.imag
    return make_recording(components={2: []}, extra=extra, speed_rpm=RPM, **kw)


@pytest.mark.parametrize("sign", [1, -1])
def test_circular_whirl_direction(sign):
    fr = extract_features(_z_record(lambda th: 20 * np.exp(1j * sign * th)))
    assert fr["b2_1x_whirl_dir"] == sign
    assert fr["b2_1x_whirl_index"] == pytest.approx(sign, abs=1e-12)
    assert fr["b2_1x_ellipticity"] == pytest.approx(1.0, abs=1e-12)
    assert fr["b2_orbit12_ellipticity"] == pytest.approx(1.0, abs=1e-9)
    assert fr["b2_orbit12_turning_number"] == sign
    assert fr["b2_orbit12_loop"] == 0.0
    assert fr["b2_orbit12_area_um2"] == pytest.approx(sign * np.pi * 400, rel=1e-9)
    assert fr["b2_orbit12_um_pp"] == pytest.approx(40.0, rel=1e-9)
    assert fr["b2_1x_fwd_um_pp" if sign > 0 else "b2_1x_rev_um_pp"] == pytest.approx(40.0, rel=1e-12)


def test_backward_elliptical_orbit():
    """x = 30 cos θ, y = −10 sin θ: a backward ellipse, axes 60 and 20 pk-pk."""
    fr = extract_features(_z_record(lambda th: 30 * np.cos(th) - 10j * np.sin(th)))
    assert fr["b2_1x_whirl_dir"] == -1
    assert fr["b2_1x_ellipticity"] == pytest.approx(1 / 3, rel=1e-9)
    assert fr["b2_1x_whirl_index"] == pytest.approx(-1 / 3, rel=1e-9)
    assert fr["b2_1x_major_um_pp"] == pytest.approx(60.0, rel=1e-9)
    assert fr["b2_orbit12_um_pp"] == pytest.approx(60.0, rel=1e-7)
    assert fr["b2_orbit12_area_um2"] == pytest.approx(-np.pi * 300, rel=1e-9)
    assert fr["b2_orbit12_ellipticity"] == pytest.approx(1 / 3, rel=1e-9)


def test_figure_eight_detected():
    """x = 20 cos θ, y = 15 sin 2θ: a figure-8 (turning number 0, zero net area)."""
    fr = extract_features(_z_record(lambda th: 20 * np.cos(th) + 15j * np.sin(2 * th)))
    assert fr["b2_orbit12_turning_number"] == 0
    assert fr["b2_orbit12_loop"] == 1.0
    assert abs(fr["b2_orbit12_area_um2"]) < 1e-9 * 400
    assert fr["b2_orbit12_concavity"] == pytest.approx(0.5, abs=1e-6)


@pytest.mark.parametrize("r2,loop", [(0.3, False), (0.45, False), (0.6, True), (1.5, True)])
def test_inner_loop_appears_when_2x_forward_exceeds_half_1x(r2, loop):
    """z = e^{jθ} + r e^{2jθ}: the velocity vanishes at r = 1/2, an inner loop forms above it."""
    fr = extract_features(_z_record(lambda th: 20 * (np.exp(1j * th) + r2 * np.exp(2j * th))))
    assert fr["b2_orbit12_loop"] == float(loop)
    assert fr["b2_orbit12_turning_number"] == (2 if loop else 1)
    # signed area π Σ k(|F_k|² − |R_k|²)
    assert fr["b2_orbit12_area_um2"] == pytest.approx(np.pi * 400 * (1 + 2 * r2 ** 2), rel=1e-9)
    if not loop:
        # the kidney shape grows concave before the loop forms
        conc = fr["b2_orbit12_concavity"]
        assert (conc > 0) == (r2 > 0.25)   # curvature changes sign for r > 1/4


def test_concavity_zero_for_ellipse_and_positive_for_kidney():
    e = orbit_shape(np.array([10.0 + 0j, 0j]), np.array([-5j, 0j]))
    assert e.concavity == 0.0 and e.turning_number == 1
    k = orbit_shape(np.array([10.0 + 0j, 4.0 + 0j]), np.array([-10j, -4j]))
    assert 0 < k.concavity < 0.5 and k.turning_number == 1


def test_orbit_peak_to_peak_against_dense_brute_force():
    rng = np.random.default_rng(4)
    for _ in range(5):
        cx = rng.normal(size=2) + 1j * rng.normal(size=2)
        cy = rng.normal(size=2) + 1j * rng.normal(size=2)
        th = np.linspace(0, 2 * np.pi, 2001)[:-1]
        z = (np.exp(1j * np.outer(th, [1, 2])) @ cx).real + 1j * (np.exp(1j * np.outer(th, [1, 2])) @ cy).real
        brute = np.max(np.abs(z[:, None] - z[None, :]))
        assert orbit_shape(cx, cy).pp_um == pytest.approx(brute, rel=1e-5)  # brute grid error ~1e-6


def test_orbit_without_1x_or_2x_has_no_shape():
    """Only 3X present: the 1X + 2X orbit is a point; its shape features are NaN, not 'a loop'."""
    fr = extract_features(make_recording(components={2: [(3, 5.0, 0.0, 5.0, 90.0)]}, speed_rpm=RPM))
    assert fr["b2_orbit12_um_pp"] == pytest.approx(0.0, abs=1e-9)
    for name in ("turning_number", "loop", "concavity", "ellipticity"):
        assert np.isnan(fr[f"b2_orbit12_{name}"]), name
    assert fr["b2_3x_major_um_pp"] == pytest.approx(10.0, rel=1e-9)
