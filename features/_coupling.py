"""The two shaft ends across the coupling, relative to each other (bearings 2 and 3).

The probes at the coupling-end bearings 2 (generator) and 3 (exciter) each read their journal
relative to their own bearing. Their *difference*, ``r_2 − r_3``, is the relative position of the two
shaft ends — what a hot-alignment check with proximity probes across a coupling measures (the shaft
centrelines' relative position, static, and their relative once-per-revolution motion):

* a **stationary offset** of the two shaft lines (``offset``) keeps the journals at different
  positions in their bearings: a static ``|mean(r_2 − r_3)| ≈ δ``;
* a **rotating coupling eccentricity** (``rigid``) carries the offset round with the shaft: a forward
  1X circle of radius ``≈ δ`` in ``r_2 − r_3``, no static part;
* the paper's constraint (``pin``) keeps ``|r_2 − r_3| = δ`` at every instant: static while the link
  settles, rotating (1X or non-synchronous) once it races;
* a flexible coupling's 2X reaction moves both ends together: next to nothing here (its signature is
  the 2X at the coupling bearings).

On the simulated rotor, whose coupling-end journals are the coupling halves, each of these is δ
exactly; on a real train the bearings sit a span away from the coupling, so the figures scale with
the offset but are not equal to it. They are trees' inputs (the difference of two vectors is hard for
trees to form from amplitudes and phase differences) and the evidence section's "shaft ends across the
coupling".
"""
from __future__ import annotations

import numpy as np

__all__ = ["COUPLING_BEARINGS", "COUPLING_FEATURES", "coupling_features"]

#: the coupling-end bearings (generator side, exciter side)
COUPLING_BEARINGS: tuple[int, int] = (2, 3)

#: name → (unit, definition), in schema order
COUPLING_FEATURES: dict[str, tuple[str, str]] = {
    "cpl_1x_rel_fwd_um_pp": ("µm pk-pk", "forward 1X of the relative motion r_b2 − r_b3 of the shaft ends across "
                             "the coupling, 2|F_1(b2) − F_1(b3)| (a rotating coupling eccentricity δ: ≈ 2δ)"),
    "cpl_1x_rel_fwd_pp_per_c": ("1", "cpl_1x_rel_fwd_um_pp / radial clearance (mean of bearings 2 and 3)"),
    "cpl_ac_rel_rms_um": ("µm rms", "RMS of the relative AC motion r_b2 − r_b3 (x and y together): the fitted orders "
                          "(slow-roll compensated when asked) plus the non-synchronous residual, less the probes' "
                          "broadband noise power"),
    "cpl_ac_rel_rms_per_c": ("1", "cpl_ac_rel_rms_um / radial clearance"),
    "cpl_dc_offset_per_c": ("1", "static offset of the shaft ends across the coupling, |mean(r_b2) − mean(r_b3)| / "
                            "clearance (a stationary shaft-line offset δ: ≈ δ/c); NaN as b?_centre_x_per_c at either "
                            "bearing (the DC gaps must be referenced to the bearing centres)"),
    "cpl_rel_rms_per_c": ("1", "RMS separation of the shaft ends across the coupling, "
                          "√(cpl_dc_offset_per_c² + cpl_ac_rel_rms_per_c²) (an offset of δ of any of the three "
                          "kinds: ≈ δ/c); NaN as cpl_dc_offset_per_c"),
}


def coupling_features(coeffs_x_um: np.ndarray, coeffs_y_um: np.ndarray, mean_um: np.ndarray,
                      resid_um: np.ndarray, noise_rms_um: np.ndarray, clearance_um: np.ndarray,
                      centre_valid: np.ndarray) -> dict[str, float]:
    """The :data:`COUPLING_FEATURES` of the two coupling-end bearings.

    Parameters
    ----------
    coeffs_x_um, coeffs_y_um : ndarray, complex, shape (2, K)
        Order coefficients ``C_k`` (zero-to-peak, µm) of x and y at bearing 2 (row 0) and bearing 3
        (row 1), on one shaft-angle axis.
    mean_um : ndarray, shape (2, 2)
        Fitted constant (x, y) per bearing (µm).
    resid_um : ndarray, shape (4, n)
        Residual after the order fit: x, y of bearing 2, then x, y of bearing 3.
    noise_rms_um : ndarray, shape (4,)
        Broadband noise RMS of the same four rows.
    clearance_um : ndarray, shape (2,)
        Radial clearances (NaN unknown).
    centre_valid : ndarray of bool, shape (2,)
        Whether each bearing's mean is a journal position (``b?_centre_x_per_c`` finite).

    Returns
    -------
    dict
        ``{name: value}`` for every key of :data:`COUPLING_FEATURES`.
    """
    dx = coeffs_x_um[0] - coeffs_x_um[1]
    dy = coeffs_y_um[0] - coeffs_y_um[1]
    fwd1 = 0.5 * abs(dx[0] + 1j * dy[0])
    sync_ms = 0.5 * float(np.sum(np.abs(dx) ** 2 + np.abs(dy) ** 2))       # Re(C e^{jkθ}): mean square |C|²/2
    rel_resid = resid_um[0:2] - resid_um[2:4]
    resid_ms = float(np.einsum("ij,ij->", rel_resid, rel_resid)) / rel_resid.shape[1]
    nonsync_ms = max(resid_ms - float(np.sum(np.square(noise_rms_um))), 0.0)
    ac_rms = float(np.sqrt(sync_ms + nonsync_ms))
    c = float(np.mean(clearance_um)) if np.all(np.isfinite(clearance_um)) else float("nan")
    if bool(np.all(centre_valid)) and np.isfinite(c):
        dc = float(np.hypot(*(mean_um[0] - mean_um[1]))) / c
        sep = float(np.hypot(dc, ac_rms / c))
    else:
        dc = sep = float("nan")
    return {
        "cpl_1x_rel_fwd_um_pp": 2.0 * fwd1,
        "cpl_1x_rel_fwd_pp_per_c": 2.0 * fwd1 / c,
        "cpl_ac_rel_rms_um": ac_rms,
        "cpl_ac_rel_rms_per_c": ac_rms / c,
        "cpl_dc_offset_per_c": dc,
        "cpl_rel_rms_per_c": sep,
    }
