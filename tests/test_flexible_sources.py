"""`flexible`'s 2X coupling forcing against two published closed forms (docs/model.md, "flexible against
its sources"): the kinematics of a double-engagement (Oldham-type) coupling's floating member, and the
parallel-misalignment reaction force of a hexangular flexible coupling (Xia et al. 2019)."""
import math

import numpy as np
import pytest

from rotordiag.simulator import Plant, build_system
from rotordiag.simulator import _kernels as K

N = 256
THETA = np.arange(N) * 2 * math.pi / N


def _our_u_m(pl: Plant, delta: float, psi: float, phi0: float) -> np.ndarray:
    """Our relative hub displacement u(τ) (m, (N, 2)) read from the kernel: with the hubs held together the
    force on node 3 is −k_c·u."""
    sysm = build_system(pl, 1950.0, delta, 0.05, mechanism="flexible", coupling_phase_rad=psi, offset_angle_rad=phi0)
    y = np.zeros(K.N_STATE_FLEXIBLE)
    f_n = np.array([K.coupling_force(t, y, sysm.params) for t in THETA]) * pl.clearance_m * sysm.speed_rad_s**2
    return -f_n / pl.coupling_stiffness_n_m


def _line(z: np.ndarray, k: int) -> complex:
    """Complex amplitude (0-pk) of the +k (forward) or −k (backward) line of x + iy over one revolution."""
    return complex(np.fft.fft(z[:, 0] + 1j * z[:, 1])[k % N] / N)


def _oldham_centre(offset: np.ndarray, slot_angle_rad: float) -> np.ndarray:
    """Floating-member centre C(θ) − A of a double-engagement coupling: hub A's slot (direction s(θ) at
    θ + β) and hub B's (perpendicular) cross at C = A + ((B − A)·s) s. Textbook Oldham kinematics, the
    'floating member runs round a circle of diameter δ at 2Ω' of Gibbons (1976) and its successors."""
    s = np.stack([np.cos(THETA + slot_angle_rad), np.sin(THETA + slot_angle_rad)], axis=1)
    return (s @ offset)[:, None] * s


@pytest.mark.parametrize("delta, beta, phi0", [(0.3, 0.0, 0.0), (0.1, 0.4, -math.pi / 2), (0.6, -2.0, 2.5)])
def test_u_is_the_oldham_floating_member_circle_with_psi_minus_twice_the_offset_angle(delta, beta, phi0):
    pl = Plant.default().replace(coupling_damping_n_s_m=0.0)
    d_m = delta * pl.clearance_m
    centre = _oldham_centre(d_m * np.array([math.cos(phi0), math.sin(phi0)]), beta)
    # the source: mean δ/2 along the offset, and a forward 2X circle of radius δ/2 (diameter δ), nothing else
    assert abs(_line(centre, 0) - 0.5 * d_m * complex(math.cos(phi0), math.sin(phi0))) < 1e-12 * d_m
    assert abs(_line(centre, 2)) == pytest.approx(0.5 * d_m, rel=1e-12)
    assert max(abs(_line(centre, k)) for k in (-2, -1, 1, 3)) < 1e-12 * d_m
    # ours: the same zero-mean motion, sample by sample, when ψ = 2β − 2φ0
    u = _our_u_m(pl, delta, 2 * beta - 2 * phi0, phi0)
    np.testing.assert_allclose(u, centre - centre.mean(axis=0), rtol=0, atol=1e-12 * d_m)


def _xia_force_n(offset_m: np.ndarray, radius_m: float, kd_n_m: float) -> np.ndarray:
    """Xia, Pang, Yang, Zhao & Yang (2019, Applied Acoustics 155, 286–296): parallel-misalignment reaction
    of a hexangular flexible coupling on the driving hub, as implemented in the ROSS rotordynamics package
    (MisalignmentFlex, 'parallel'), rewritten in vector form: bolts at θ + 2πk/3 on radius R, each link's
    length change |R n_k + e| − R with sign (+, +, −), force kd·Σ s_k (|R n_k + e| − R) n_k; e = driven − driving."""
    out = np.zeros((N, 2))
    for k, sign in enumerate((1.0, 1.0, -1.0)):
        n = np.stack([np.cos(THETA + 2 * math.pi * k / 3), np.sin(THETA + 2 * math.pi * k / 3)], axis=1)
        stretch = np.linalg.norm(radius_m * n + offset_m, axis=1) - radius_m
        out += kd_n_m * sign * stretch[:, None] * n
    return out


@pytest.mark.parametrize("phi0", [0.0, -math.pi / 2, 2.2])
def test_2x_force_matches_xia_2019_with_kc_twice_kd(phi0):
    kd = 5.0e7
    pl = Plant.default().replace(coupling_stiffness_n_m=2 * kd, coupling_damping_n_s_m=0.0)
    delta = 0.2
    d_m = delta * pl.clearance_m                       # 70 µm on a 0.25 m bolt circle: δ/R = 2.8e-4
    e_delta = np.array([math.cos(phi0), math.sin(phi0)])
    xia = _xia_force_n(d_m * e_delta, 0.25, kd)
    # the source: a static kd·δ/2 along the offset and a forward 2X of 0-pk amplitude kd·δ (full δ), phase −φ0 − π/3
    assert abs(_line(xia, 0) - 0.5 * kd * d_m * complex(*e_delta)) < 1e-3 * kd * d_m
    x2 = _line(xia, 2)
    assert abs(x2) == pytest.approx(kd * d_m, rel=1e-3)
    assert abs(math.remainder(np.angle(x2) - (-phi0 - math.pi / 3), 2 * math.pi)) < 1e-3
    assert max(abs(_line(xia, k)) for k in (-2, -1, 1)) < 2e-3 * kd * d_m
    # ours, force on node 3 (the driving, generator hub) with the hubs held: −k_c·u = k_c·δ/2 at 2X;
    # equal to the source's 2X line with k_c = 2·kd and ψ = −2φ0 − 4π/3
    ours = -pl.coupling_stiffness_n_m * _our_u_m(pl, delta, -2 * phi0 - 4 * math.pi / 3, phi0)
    assert abs(_line(ours, 2) - x2) < 1e-3 * kd * d_m
    # what differs: the static part (ours comes from the bearing-centre offset, not from u)
    assert abs(_line(ours, 0)) < 1e-12 * kd * d_m
