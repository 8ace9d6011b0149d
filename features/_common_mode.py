"""A 1X or 2X that is one signal common to every probe: electrical pickup, not shaft motion.

A shaft's orbit differs between a bearing's two probe directions and from bearing to bearing (the
generator's journals and the exciter's move in their own bearings). One signal of the same amplitude
and phase at every probe is electrical — mains at the running frequency or twice it (50/60 Hz and
100/120 Hz on a 2-pole generator, which runs synchronously with the grid, so the pickup sits exactly on
an order; a ground loop or a shared supply) — or the probe mountings vibrating together. Either way it
is no evidence of misalignment, and a 2X pickup a few µm strong reads as a coupling's 2X to the model
and to the 2X/1X rule of thumb alike.

:func:`common_mode` measures the share of an order's power that one common signal explains over the
probes whose order stands out of the noise; ``features._sanity`` warns on a recording it dominates, and
:func:`without_common_mode` gives the recording with the common signal removed: the verdict is given on that
(``models.checks.common_mode``).
"""
from __future__ import annotations

from dataclasses import dataclass, replace

import numpy as np

from . import _config as cfg
from ._recording import ProbeChannel, Recording

__all__ = ["CommonMode", "common_mode", "common_mode_share", "without_common_mode", "COMMON_MODE_MIN_PROBES",
           "COMMON_MODE_NOTABLE_SHARE"]

#: fewer probes are not judged: with 2 or 4 a shaft's own orbit reaches a share of 0.99 (a linear orbit along the
#: probes' bisector, in phase at both coupling-end journals)
COMMON_MODE_MIN_PROBES = 6
#: a share from which the common part is worth a look: shown in the evidence, and removed before the verdict
#: (``models.checks.common_mode``); about one recording in 1000 of a healthy shaft reaches it (docs/features.md,
#: "Measurements behind the speed estimate's thresholds")
COMMON_MODE_NOTABLE_SHARE = 0.6


@dataclass(frozen=True)
class CommonMode:
    """The signal common to every judged probe at one order.

    Attributes
    ----------
    order : int
    share : float
        ``|Σ z_i|² / (n Σ |z_i|²)`` over the judged probes' coefficients ``z_i``: 1 when every probe reads the same
        amplitude and phase, ``1/n`` on average for unrelated phasors (:func:`common_mode_share`).
    coeff_um : complex
        The common signal ``mean(z_i)``, zero-to-peak (the kX component is ``Re(C e^{jkθ})``).
    n_probes : int
    bearings : tuple of int
        The bearings whose two probes were judged (the order above ``PHASE_MIN_SNR`` × their noise-equivalent
        amplitude at both).
    """

    order: int
    share: float
    coeff_um: complex
    n_probes: int
    bearings: tuple[int, ...]

    @property
    def amp_um_pp(self) -> float:
        """Peak-to-peak amplitude of the common signal, µm."""
        return 2.0 * abs(self.coeff_um)

    @property
    def phase_lag_deg(self) -> float:
        """Its phase lag, deg in [0, 360)."""
        return float(np.degrees(-np.angle(self.coeff_um)) % 360.0)


def common_mode_share(coeffs: np.ndarray) -> float:
    """Share of the probes' power at one order that a signal common to every probe explains.

    ``|Σ z_i|² / (n Σ |z_i|²)`` for the probes' complex coefficients ``z_i`` (same phase reference): 1 when every
    probe reads the same amplitude and phase, ``1/n`` on average for unrelated phasors; NaN when there is no power.
    """
    z = np.asarray(coeffs, dtype=complex).ravel()
    power = float(np.sum(np.abs(z) ** 2))
    return float(np.abs(np.sum(z)) ** 2 / (z.size * power)) if power > 0 and z.size else float("nan")


def common_mode(fr, order: int) -> CommonMode | None:
    """The common signal at ``order`` over the probes of ``fr`` (a ``FeatureResult``) that can be judged.

    A bearing's probes are judged when the order stands out of the noise at both
    (``PHASE_MIN_SNR`` × the larger of its x/y noise-equivalent amplitudes). None when fewer than
    :data:`COMMON_MODE_MIN_PROBES` probes are judged or they do not span the coupling (a bearing on each side:
    1 or 2, and 3 or 4).
    """
    coeffs: list[complex] = []
    where: list[int] = []
    for b, det in sorted(fr.bearings.items()):
        if det.probe_coeffs_um.shape[1] < order:
            continue
        z = det.probe_coeffs_um[:, order - 1]
        noise = det.line_noise_um
        floor = 0.0
        if noise is not None and order <= noise.shape[1] and np.all(np.isfinite(noise[:, order - 1])):
            floor = float(np.max(noise[:, order - 1]))
        if np.all(np.abs(z) > cfg.PHASE_MIN_SNR * floor):
            coeffs.extend(complex(c) for c in z)
            where.append(int(b))
    if len(coeffs) < COMMON_MODE_MIN_PROBES or not (min(where) <= 2 < max(where)):
        return None
    z = np.array(coeffs)
    return CommonMode(order, common_mode_share(z), complex(z.mean()), len(coeffs), tuple(where))


def without_common_mode(recording: Recording, fr, found: list[CommonMode]) -> Recording:
    """``recording`` with each common signal of ``found`` subtracted from every channel (µm).

    The kX signal ``Re(C e^{jkθ(t)})`` is removed over the analysed segment, with the shaft angle θ the features
    ``fr`` were computed at (``features._speed.shaft_angle`` at ``fr.speed_rpm``: the keyphasor, or the locked or
    estimated speed from the first sample). The channels come back in µm; everything else is unchanged. The
    verdict of a recording with a notable common part is given on this (``models.checks.common_mode``).
    """
    from ._speed import shaft_angle

    data = recording.xy_all_um()
    estimate = (float(fr.speed_rpm), list(fr.warnings)) if fr.speed_source == "estimated" else None
    sa = shaft_angle(recording, data, estimate)
    channels: list[ProbeChannel] = []
    for ch in recording.channels:
        d = np.array(ch.data_um, dtype=float)
        for cm in found:
            d[sa.start:sa.stop] -= np.real(cm.coeff_um * np.exp(1j * cm.order * sa.theta_rad))
        channels.append(replace(ch, data=d, units="um"))
    return replace(recording, channels=channels)
