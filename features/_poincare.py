"""Once-per-revolution (Poincaré) samples and the motion type."""
from __future__ import annotations

import numpy as np

from rotordiag.core.notes import Length, Note
from rotordiag.simulator.motion import PERIOD_RTOL, classify_motion

from . import _config as cfg

__all__ = ["poincare_points", "period_tolerance", "classify"]


def poincare_points(sync_at_zero: np.ndarray, residual: np.ndarray, start_sample: int, fs: float,
                    rev_times_s: np.ndarray) -> np.ndarray:
    """Signal at θ = 2πm for each analysed revolution m.

    The synchronous part is the same at every θ = 2πm (``sync_at_zero``: constant plus
    Σ Re C_k); the non-synchronous residual (shape (m, n), first sample at index
    ``start_sample`` of the record) is interpolated at the revolution start times with a
    4-point (cubic) Lagrange stencil. Returns shape (n_revs, m).
    """
    n = residual.shape[1]
    u = rev_times_s * fs - start_sample
    i = np.clip(np.floor(u).astype(np.int64), 1, n - 3)
    mu = u - i
    w = np.stack([-mu * (mu - 1) * (mu - 2) / 6, (mu + 1) * (mu - 1) * (mu - 2) / 2,
                  -(mu + 1) * mu * (mu - 2) / 2, (mu + 1) * mu * (mu - 1) / 6])      # (4, n_revs)
    idx = i[None, :] + np.arange(-1, 3)[:, None]                                       # (4, n_revs)
    vals = np.einsum("jr,cjr->rc", w, residual[:, idx])
    return vals + sync_at_zero[None, :]


def period_tolerance(point_noise_rms: np.ndarray, n_points: int) -> float:
    """Return-distance tolerance that Gaussian noise exceeds with probability ≤ ``POINCARE_FALSE_ALARM``.

    The difference of two noisy section points has variance 2σ_c² per coordinate; the
    largest of ``n_points`` squared distances stays below 2σ²·χ²_D(1 − α/n) with
    probability ≥ 1 − α (σ² the mean coordinate variance, D the dimension).
    """
    from scipy.special import chdtri  # inverse survival function of χ²

    d = point_noise_rms.size
    sigma2 = float(np.mean(point_noise_rms ** 2))
    return float(np.sqrt(2 * sigma2 * chdtri(d, cfg.POINCARE_FALSE_ALARM / max(n_points, 1))))


def classify(points: np.ndarray, orbit_size_um: float, point_noise_rms: np.ndarray):
    """Motion type from the Poincaré points of all bearings with the analysis package's classifier.

    The period tolerance is widened from the classifier's default (a fraction of the orbit
    size, meant for noise-free simulations) to :func:`period_tolerance`, so that measurement
    noise does not turn a period-1 orbit into "quasi-periodic". Returns
    ``(MotionType, note)``.
    """
    rtol = PERIOD_RTOL
    if orbit_size_um > 0:
        rtol = max(rtol, period_tolerance(point_noise_rms, points.shape[0]) / orbit_size_um)
    if not (np.isfinite(orbit_size_um) and np.isfinite(rtol)):
        # an orbit of subnormal size (e.g. samples of 1e-310): the tolerance over it overflows
        return None, Note("motion_not_classified", orbit=Length(orbit_size_um))
    return classify_motion(points, orbit_size=orbit_size_um, period_rtol=rtol), None
