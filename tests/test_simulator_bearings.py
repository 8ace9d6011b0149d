"""Oil-film bearings of rotordiag.simulator.bearings against closed forms, an independent
quadrature of Reynolds' short-bearing equation (tests/reference/short_film.py) and their limits."""
from __future__ import annotations

import math

import numpy as np
import pytest
from numba import njit

from rotordiag.simulator.bearings import (
    BEARING_ELLIPTICAL,
    BEARING_LINEAR,
    BEARING_PLAIN,
    BEARING_TILTING_PAD,
    EllipticalBearing,
    LinearBearing,
    PlainBearing,
    TiltingPadBearing,
    bearing_force,
    bearing_from_dict,
)
from tests.reference import short_film as ref

D, L, C, MU = 0.45, 0.35, 0.35e-3, 0.018
W_RAD_S = 2.0 * math.pi * 3000 / 60
PLAIN = PlainBearing(diameter_m=D, length_m=L, clearance_m=C, viscosity_pa_s=MU)
S_B = MU * W_RAD_S * (D / 2) * L**3 / (4 * C**2)        # Capone's force scale (MODEL.md section 4)


def ocvirk_load(eps):
    """Ocvirk's static load of the short bearing, N (MODEL.md section 4)."""
    return S_B * eps / (1 - eps**2) ** 2 * math.sqrt(math.pi**2 * (1 - eps**2) + 16 * eps**2)


def ocvirk_coefficients(eps, load_n):
    """Short-bearing K, C in x horizontal, y vertical (load −y, Ω > 0 from +x to +y): Friswell,
    Penny, Garvey & Lees, *Dynamics of Rotating Machines* (CUP 2010), section 5.5 (the same closed
    forms as ROSS 2.3's ``calculate_analytical_stiffness_matrix``/``..._damping_matrix``)."""
    e = eps
    h0 = 1.0 / (math.pi**2 * (1 - e * e) + 16 * e * e) ** 1.5
    s = math.sqrt(1 - e * e)
    a = np.array([
        [4 * (math.pi**2 * (2 - e * e) + 16 * e * e), math.pi * (math.pi**2 * (1 - e * e) ** 2 - 16 * e**4) / (e * s)],
        [-math.pi * (math.pi**2 * (1 - e * e) * (1 + 2 * e * e) + 32 * e * e * (1 + e * e)) / (e * s),
         4 * (math.pi**2 * (1 + 2 * e * e) + 32 * e * e * (1 + e * e) / (1 - e * e))]]) * h0
    b = np.array([
        [2 * math.pi * s * (math.pi**2 * (1 + 2 * e * e) - 16 * e * e) / e, -8 * (math.pi**2 * (1 + 2 * e * e) - 16 * e * e)],
        [-8 * (math.pi**2 * (1 + 2 * e * e) - 16 * e * e), 2 * math.pi * (math.pi**2 * (1 - e * e) ** 2 + 48 * e * e) / (e * s)]]) * h0
    return a * load_n / C, b * load_n / (C * W_RAD_S)


ALL = [
    PLAIN,
    EllipticalBearing(D, L, C, MU, preload=0.5, lobe_arc_deg=150.0),
    TiltingPadBearing(D, L, C, MU, pads=4, pad_arc_deg=80.0, pivot_offset=0.5, preload=0.3, load="between_pads"),
    TiltingPadBearing(D, L, C, MU, pads=5, pad_arc_deg=60.0, pivot_offset=0.6, preload=0.2, load="on_pad"),
    LinearBearing(D, L, C, stiffness_n_m=[[1e9, 2e8], [-3e8, 1.5e9]], damping_n_s_m=[[1e6, 1e5], [1e5, 2e6]]),
]


# ----------------------------------------------------------------- plain: Ocvirk closed forms
@pytest.mark.parametrize("eps", [0.1, 0.3, 0.5, 0.7, 0.9])
def test_plain_equilibrium_is_ocvirk_eccentricity_and_attitude(eps):
    x, y = PLAIN.equilibrium(0.0, -ocvirk_load(eps), W_RAD_S)
    assert math.hypot(x, y) / C == pytest.approx(eps, rel=1e-9)
    attitude = math.atan2(x, -y)          # from the load line (−y) towards the rotation (+x)
    assert attitude == pytest.approx(math.atan(math.pi * math.sqrt(1 - eps**2) / (4 * eps)), rel=1e-9)


@pytest.mark.parametrize("eps", [0.1, 0.3, 0.5, 0.7, 0.85])
def test_plain_coefficients_are_ocvirk_closed_forms(eps):
    w = ocvirk_load(eps)
    K, Cm = PLAIN.coefficients(*PLAIN.equilibrium(0.0, -w, W_RAD_S), W_RAD_S)
    K_ref, C_ref = ocvirk_coefficients(eps, w)
    np.testing.assert_allclose(K, K_ref, rtol=1e-6, atol=1e-6 * np.abs(K_ref).max())
    np.testing.assert_allclose(Cm, C_ref, rtol=1e-6, atol=1e-6 * np.abs(C_ref).max())


def test_plain_force_against_reynolds_quadrature_with_squeeze():
    rng = np.random.default_rng(42)
    for _ in range(20):
        e, ang = rng.uniform(0.05, 0.9), rng.uniform(0, 2 * math.pi)
        x, y = C * e * math.cos(ang), C * e * math.sin(ang)
        vx, vy = rng.normal(0, 0.3, 2) * C * W_RAD_S
        fx, fy, _ = ref.film_force(D / 2, L, MU, C, (0.0, 0.0), 0.0, 2 * math.pi, x, y, vx, vy, W_RAD_S)
        np.testing.assert_allclose(PLAIN.force_n(x, y, vx, vy, W_RAD_S), (fx, fy), rtol=1e-8, atol=1e-8 * math.hypot(fx, fy))


def test_plain_pure_squeeze_at_zero_speed():
    fx, fy, _ = ref.film_force(D / 2, L, MU, C, (0.0, 0.0), 0.0, 2 * math.pi, 0.3 * C, 0.0, -0.1, 0.0, 0.0)
    np.testing.assert_allclose(PLAIN.force_n(0.3 * C, 0.0, -0.1, 0.0, 0.0), (fx, fy), rtol=1e-8, atol=1e-6)
    assert PLAIN.force_n(0.3 * C, 0.0, 0.0, 0.0, 0.0) == (0.0, 0.0)


# ----------------------------------------------------------------- two-lobe
def test_two_lobe_with_zero_preload_and_half_circle_lobes_is_the_plain_bearing():
    b = EllipticalBearing(D, L, C, MU, preload=0.0, lobe_arc_deg=180.0)
    rng = np.random.default_rng(7)
    for _ in range(50):
        e, ang = rng.uniform(0.0, 0.95), rng.uniform(0, 2 * math.pi)
        x, y = C * e * math.cos(ang), C * e * math.sin(ang)
        vx, vy = rng.normal(0, 0.5, 2) * C * W_RAD_S
        np.testing.assert_allclose(b.force_n(x, y, vx, vy, W_RAD_S), PLAIN.force_n(x, y, vx, vy, W_RAD_S),
                                   rtol=1e-10, atol=1e-10 * abs(PLAIN.force_n(x, y, vx, vy, W_RAD_S)[1]))


def test_two_lobe_force_against_reynolds_quadrature():
    b = EllipticalBearing(D, L, C, MU, preload=0.5, lobe_arc_deg=150.0)
    _, p = b.kernel()
    rng = np.random.default_rng(3)
    for _ in range(10):
        x, y = rng.uniform(-0.6, 0.6, 2) * C
        vx, vy = rng.normal(0, 0.2, 2) * C * W_RAD_S
        want = np.zeros(2)
        for k in range(2):
            o = 5 + 5 * k
            want += ref.film_force(D / 2, L, MU, p[o + 2], (p[o], p[o + 1]), p[o + 3], p[o + 4], x, y, vx, vy, W_RAD_S)[:2]
        np.testing.assert_allclose(b.force_n(x, y, vx, vy, W_RAD_S), want, rtol=1e-8, atol=1e-8 * np.abs(want).max())


# ----------------------------------------------------------------- tilting pad
def _check_tilting_pad_against_reference(b, points, n_scan):
    R = D / 2
    cp = C / (1 - b.preload)
    arc = math.radians(b.pad_arc_deg)
    piv = b.pivot_angles_rad()
    arcs = [(t - b.pivot_offset * arc, t + (1 - b.pivot_offset) * arc) for t in piv]
    for x, y in points:
        want = ref.tilting_pad_static_force(R, L, MU, C, cp, piv, arcs, x, y, W_RAD_S, n_scan=n_scan)
        np.testing.assert_allclose(b.force_n(x, y, 0.0, 0.0, W_RAD_S), want, rtol=1e-7, atol=1e-7 * np.abs(want).max())


def test_tilting_pad_static_force_against_moment_balance_about_the_pivot():
    _check_tilting_pad_against_reference(ALL[2], [(0.1 * C, -0.5 * C)], n_scan=40)


@pytest.mark.slow
@pytest.mark.parametrize("b", ALL[2:4], ids=["4pad_lbp", "5pad_lop_offset"])
def test_tilting_pad_static_force_against_moment_balance_many_positions(b):
    _check_tilting_pad_against_reference(b, [(0.0, -0.3 * C), (0.1 * C, -0.5 * C), (-0.2 * C, 0.1 * C),
                                             (0.3 * C, 0.2 * C)], n_scan=400)


def test_tilting_pad_reduced_coefficients():
    """Lund's pad assembly: each pad's reduced impedance is radial (no stiffness or damping along its
    tangent), so the sum is symmetric, and with the load between symmetric pads it has no
    cross-coupling; at ω → 0 it is the stiffness of the compiled (quasi-static) force."""
    b = ALL[2]
    r = b.equilibrium(0.0, -ocvirk_load(0.5), W_RAD_S)
    for Kp, Cp, t in b.pad_coefficients(*r, W_RAD_S):
        Zp = Kp + 1j * W_RAD_S * Cp
        Zr = Zp - np.outer(Zp @ t, t @ Zp) / (t @ Zp @ t)
        assert np.abs(Zr @ t).max() < 1e-9 * np.abs(Zp).max() and np.abs(t @ Zr).max() < 1e-9 * np.abs(Zp).max()
    K, Cm = b.reduced_coefficients(*r, W_RAD_S)
    assert abs(K[0, 1]) < 1e-8 * K[1, 1] and abs(K[1, 0]) < 1e-8 * K[1, 1]
    assert abs(Cm[0, 1]) < 1e-8 * Cm[1, 1] and abs(Cm[1, 0]) < 1e-8 * Cm[1, 1]
    assert K[0, 0] > 0 and K[1, 1] > 0 and Cm[0, 0] > 0 and Cm[1, 1] > 0
    K0, _ = b.reduced_coefficients(*r, W_RAD_S, whirl_rad_s=1e-7 * W_RAD_S)
    Kq, _ = b.coefficients(*r, W_RAD_S)
    np.testing.assert_allclose(K0, Kq, rtol=1e-6, atol=1e-6 * Kq[1, 1])


@pytest.mark.parametrize("b", ALL[2:4], ids=["4pad_lbp", "5pad_lop"])
def test_tilting_pad_has_negligible_cross_coupled_stiffness(b):
    r = b.equilibrium(0.0, -ocvirk_load(0.5), W_RAD_S)
    K, _ = b.coefficients(*r, W_RAD_S)
    assert abs(K[0, 1]) < 1e-6 * abs(K[1, 1]) and abs(K[1, 0]) < 1e-6 * abs(K[1, 1])
    # a plain bearing at the same load: the cross-coupling the pads remove
    Kp, _ = PLAIN.coefficients(*PLAIN.equilibrium(0.0, -ocvirk_load(0.5), W_RAD_S), W_RAD_S)
    assert max(abs(Kp[0, 1]), abs(Kp[1, 0])) > 0.5 * abs(Kp[1, 1])


# ----------------------------------------------------------------- every type
@pytest.mark.parametrize("b", ALL, ids=lambda b: b.TYPE)
def test_compiled_dispatch_equals_force_n(b):
    code, p = b.kernel()
    assert code in (BEARING_PLAIN, BEARING_ELLIPTICAL, BEARING_TILTING_PAD, BEARING_LINEAR)
    assert p.dtype == np.float64
    rng = np.random.default_rng(11)
    for _ in range(20):
        x, y = rng.uniform(-0.5, 0.5, 2) * C
        vx, vy = rng.normal(0, 0.2, 2) * C * W_RAD_S
        got = bearing_force(code, p, x, y, vx, vy, W_RAD_S)
        want = b.force_n(x, y, vx, vy, W_RAD_S)
        np.testing.assert_allclose(got, want, rtol=1e-12, atol=1e-12 * max(np.abs(want).max(), 1.0))


@njit(cache=False)
def _sum_forces(code, p, n, w):
    s = 0.0
    for i in range(n):
        fx, fy = bearing_force(code, p, 1e-5 * i, -1e-4, 0.0, 0.0, w)
        s += fx + fy
    return s


@pytest.mark.parametrize("b", ALL, ids=lambda b: b.TYPE)
def test_kernel_is_callable_inside_compiled_code(b):
    code, p = b.kernel()
    want = sum(sum(b.force_n(1e-5 * i, -1e-4, 0.0, 0.0, W_RAD_S)) for i in range(3))
    assert _sum_forces(code, p, 3, W_RAD_S) == pytest.approx(want, rel=1e-12)


@pytest.mark.parametrize("b", ALL[:4], ids=lambda b: b.TYPE)
def test_reverse_rotation_is_the_mirror_image(b):
    if isinstance(b, TiltingPadBearing) and b.pivot_offset != 0.5:
        b = TiltingPadBearing(D, L, C, MU, pads=5, pad_arc_deg=60.0, pivot_offset=0.5, preload=0.2, load="on_pad")
    x, y = b.equilibrium(0.0, -ocvirk_load(0.4), W_RAD_S)
    xr, yr = b.equilibrium(0.0, -ocvirk_load(0.4), -W_RAD_S)
    assert (xr, yr) == pytest.approx((-x, y), rel=1e-9, abs=1e-12 * C)
    rng = np.random.default_rng(5)
    for _ in range(10):
        px, py = rng.uniform(-0.5, 0.5, 2) * C
        vx, vy = rng.normal(0, 0.2, 2) * C * W_RAD_S
        fx, fy = b.force_n(px, py, vx, vy, W_RAD_S)
        gx, gy = b.force_n(-px, py, -vx, vy, -W_RAD_S)
        np.testing.assert_allclose((-gx, gy), (fx, fy), rtol=1e-10, atol=1e-10 * math.hypot(fx, fy))


@pytest.mark.parametrize("b", ALL, ids=lambda b: b.TYPE)
def test_coefficients_predict_the_force_change(b):
    """K, C against finite differences of force_n with a 100× larger step (second-order agreement)."""
    r = b.equilibrium(0.0, -ocvirk_load(0.4), W_RAD_S)
    K, Cm = b.coefficients(*r, W_RAD_S)
    f0 = np.array(b.force_n(*r, 0.0, 0.0, W_RAD_S))
    h = 1e-4 * C
    for j in range(2):
        d = np.eye(2)[j] * h
        df = (np.array(b.force_n(r[0] + d[0], r[1] + d[1], 0.0, 0.0, W_RAD_S))
              - np.array(b.force_n(r[0] - d[0], r[1] - d[1], 0.0, 0.0, W_RAD_S))) / (2 * h)
        np.testing.assert_allclose(-df, K[:, j], rtol=1e-5, atol=1e-5 * np.abs(K).max())
        dv = np.eye(2)[j] * h * W_RAD_S
        df = (np.array(b.force_n(*r, *dv, W_RAD_S)) - np.array(b.force_n(*r, *(-dv), W_RAD_S))) / (2 * h * W_RAD_S)
        np.testing.assert_allclose(-df, Cm[:, j], rtol=1e-5, atol=1e-5 * np.abs(Cm).max())
    np.testing.assert_allclose(f0, (0.0, ocvirk_load(0.4)), atol=1e-9 * ocvirk_load(0.4))


@pytest.mark.parametrize("b", ALL, ids=lambda b: b.TYPE)
def test_dict_round_trip(b):
    assert bearing_from_dict(b.to_dict()) == b
    assert type(b).from_dict(b.to_dict()) == b


def test_linear_table_is_interpolated_in_speed():
    b = LinearBearing(D, L, C, stiffness_n_m=[[[1e9, 0], [0, 2e9]], [[3e9, 1e8], [0, 4e9]]],
                      damping_n_s_m=[np.eye(2) * 1e6, np.eye(2) * 3e6], speeds_rad_s=[100.0, 300.0])
    K, Cm = b.coefficients(0.0, 0.0, 150.0)
    np.testing.assert_allclose(K, [[1.5e9, 2.5e7], [0, 2.5e9]])
    np.testing.assert_allclose(Cm, np.eye(2) * 1.5e6)
    np.testing.assert_allclose(b.coefficients(0.0, 0.0, 50.0)[0], [[1e9, 0], [0, 2e9]])   # held outside
    assert b.equilibrium(0.0, -2e5, 100.0) == pytest.approx((0.0, -1e-4))


@pytest.mark.parametrize("data, match", [
    ({"type": "tilting_pad", "diameter_m": D, "length_m": L, "clearance_m": C, "viscosity_pa_s": MU, "pads": 1}, "pads"),
    ({"type": "tilting_pad", "diameter_m": D, "length_m": L, "clearance_m": C, "viscosity_pa_s": MU, "pads": 5,
      "pad_arc_deg": 80}, "pad_arc_deg"),
    ({"type": "tilting_pad", "diameter_m": D, "length_m": L, "clearance_m": C, "viscosity_pa_s": MU, "load": "top"}, "load"),
    ({"type": "elliptical", "diameter_m": D, "length_m": L, "clearance_m": C, "viscosity_pa_s": MU, "preload": 1.2}, "preload"),
    ({"type": "plain", "diameter_m": D, "length_m": L, "clearance_m": 350, "viscosity_pa_s": MU}, "clearance_m"),
    ({"type": "plain", "diameter_m": -1, "length_m": L, "clearance_m": C, "viscosity_pa_s": MU}, "diameter_m"),
    ({"type": "plain", "diameter_m": D, "length_m": L, "clearance_m": C, "viscosity_pa_s": MU, "colour": 1}, "colour"),
    ({"type": "roller"}, "type"),
    ({"type": "linear", "diameter_m": D, "length_m": L, "clearance_m": C, "stiffness_n_m": [1, 2],
      "damping_n_s_m": [[0, 0], [0, 0]]}, "stiffness_n_m"),
])
def test_bad_input_says_what_to_fix(data, match):
    with pytest.raises(ValueError, match=match):
        bearing_from_dict(data)


def test_equilibrium_refuses_loads_no_film_carries():
    with pytest.raises(ValueError, match="speed"):
        PLAIN.equilibrium(0.0, -1e4, 0.0)
    with pytest.raises(ValueError, match="cannot carry"):
        PLAIN.equilibrium(0.0, -1e3 * ocvirk_load(0.9), W_RAD_S)


def test_pad_states_reproduce_the_synchronous_pad_assembly_coefficients():
    """Massless pads as states, integrated (RK4, 400 steps a period) under a small prescribed
    elliptical synchronous orbit: the force's first harmonic is −(K + iΩC)·r with Lund's reduced K, C
    (an independent check of the reduction), not the quasi-static coefficients."""
    b = ALL[2]
    x0, y0 = b.equilibrium(0.0, -1e5, W_RAD_S)
    u = b.pad_tilts(x0, y0, W_RAD_S)
    fx0, fy0, du = b.force_with_pad_states(x0, y0, 0.0, 0.0, W_RAD_S, u)
    assert (fx0, fy0) == pytest.approx(b.force_n(x0, y0, 0.0, 0.0, W_RAD_S), rel=1e-12, abs=1e-6)
    assert np.abs(du).max() < 1e-9 * W_RAD_S                       # at rest: the pads stay
    amp, om = 1e-3 * C, W_RAD_S

    def rates(t, u):
        c, s = math.cos(om * t), math.sin(om * t)
        fx, fy, du = b.force_with_pad_states(x0 + amp * c, y0 + 0.5 * amp * s, -amp * om * s, 0.5 * amp * om * c,
                                             W_RAD_S, u)
        return du, fx, fy

    n = 400
    h = 2 * math.pi / om / n
    t = 0.0
    rec = []
    for cycle in range(8):
        for _ in range(n):
            k1, fx, fy = rates(t, u)
            if cycle == 7:
                rec.append((t, fx - fx0, fy - fy0))
            k2 = rates(t + h / 2, u + h / 2 * k1)[0]
            k3 = rates(t + h / 2, u + h / 2 * k2)[0]
            k4 = rates(t + h, u + h * k3)[0]
            u = u + h / 6 * (k1 + 2 * k2 + 2 * k3 + k4)
            t += h
    rec = np.array(rec)
    e = np.exp(-1j * om * rec[:, 0])
    first = 2 / n * np.array([np.sum(rec[:, 1] * e), np.sum(rec[:, 2] * e)])
    r = np.array([amp, -0.5j * amp])
    K, Cm = b.reduced_coefficients(x0, y0, W_RAD_S)
    want = -(K + 1j * om * Cm) @ r
    np.testing.assert_allclose(first, want, rtol=1e-4, atol=1e-4 * np.abs(want).max())
    Kq, Cq = b.coefficients(x0, y0, W_RAD_S)
    assert np.abs(first - (-(Kq + 1j * om * Cq) @ r)).max() > 0.1 * np.abs(want).max()


def test_equilibrium_is_bounded_by_each_film_not_by_the_assembled_clearance():
    """A two-lobe bore's horizontal clearance (m 0.5: √3 c to the lobe circles) and a load-between-pads
    bearing's vertical one exceed c: heavy loads put the journal there, carried by the film; the
    journal at rest with no load sits at the centre."""
    ell = ALL[1]
    x, y = ell.equilibrium(-1e6, 0.0, W_RAD_S)
    assert x < -1.0 * C and ell.film_eccentricity(x, y) < 0.99
    np.testing.assert_allclose(ell.force_n(x, y, 0.0, 0.0, W_RAD_S), (1e6, 0.0), atol=1e-6 * 1e6)
    tp = ALL[2]
    x, y = tp.equilibrium(0.0, -1e7, W_RAD_S)
    assert y < -1.0 * C and tp.film_eccentricity(x, y) < 0.99
    np.testing.assert_allclose(tp.force_n(x, y, 0.0, 0.0, W_RAD_S), (0.0, 1e7), atol=1e-6 * 1e7)
    for b in ALL[:4]:
        assert np.hypot(*b.equilibrium(0.0, 0.0, W_RAD_S)) < 1e-9 * C
    with pytest.raises(ValueError, match="cannot carry"):
        ell.equilibrium(-1e9, 0.0, W_RAD_S)


def test_a_toml_shaft_line_table_names_a_bearing():
    import tomllib
    doc = tomllib.loads("""
[[bearing]]
type = "tilting_pad"
diameter_m = 0.45
length_m = 0.35
clearance_m = 0.35e-3
viscosity_pa_s = 0.018
pads = 5
load = "on_pad"
[[bearing]]
type = "two_lobe"
diameter_m = 0.25
length_m = 0.15
clearance_m = 0.2e-3
viscosity_pa_s = 0.018
preload = 0.4
""")
    a, b = (bearing_from_dict(t) for t in doc["bearing"])
    assert isinstance(a, TiltingPadBearing) and a.pads == 5 and a.load == "on_pad" and a.pad_arc_deg == 57.6
    assert isinstance(b, EllipticalBearing) and b.preload == 0.4 and b.to_dict()["type"] == "elliptical"


@pytest.mark.parametrize("b", ALL[:4] + [TiltingPadBearing(D, L, C, MU, pads=4, preload=0.0, load="on_pad")],
                         ids=lambda b: b.TYPE)
def test_equilibrium_converges_for_loads_in_any_direction_and_both_rotations(b):
    rng = np.random.default_rng(2024)
    for _ in range(25):
        mag, ang = 10 ** rng.uniform(3, 6.5), rng.uniform(0, 2 * math.pi)
        speed = W_RAD_S * rng.choice([1.0, -1.0]) * rng.uniform(0.2, 1.2)
        load = (mag * math.cos(ang), mag * math.sin(ang))
        r = b.equilibrium(*load, speed)
        f = b.force_n(*r, 0.0, 0.0, speed)
        assert math.hypot(f[0] + load[0], f[1] + load[1]) < 1e-8 * mag


def test_pad_states_are_continuous_where_a_quasi_static_pad_loses_its_loaded_tilt():
    """5-pad LOP (m 0.2, offset 0.6) near 680 kN: the two upper pads' loaded quasi-static tilts vanish
    at a fold between y = −0.4682 c and −0.4687 c and the compiled force jumps; with the tilts as
    states the force is continuous there (docs/bearings.md)."""
    b = TiltingPadBearing(D, L, C, MU, pads=5, pad_arc_deg=60.0, pivot_offset=0.6, preload=0.2, load="on_pad")
    s = MU * (W_RAD_S / (2 * math.pi)) * L * D * (D / 2 / C) ** 2 / np.geomspace(0.03, 3.0, 36)[8]
    x, y = b.equilibrium(0.0, -s, W_RAD_S)
    u = b.pad_tilts(x, y + 5e-4 * C, W_RAD_S)
    lo, hi = y - 1e-3 * C, y + 1e-3 * C
    jump_quasi = b.force_n(x, lo, 0.0, 0.0, W_RAD_S)[1] - b.force_n(x, hi, 0.0, 0.0, W_RAD_S)[1]
    jump_states = (b.force_with_pad_states(x, lo, 0.0, 0.0, W_RAD_S, u)[1]
                   - b.force_with_pad_states(x, hi, 0.0, 0.0, W_RAD_S, u)[1])
    assert jump_quasi > 0.04 * s              # ≈ 39 kN across 0.002 c
    assert 0.0 < jump_states < 0.01 * s       # the film's own stiffness: ≈ 6 kN


@pytest.mark.parametrize("b", ALL, ids=lambda b: b.TYPE)
def test_non_finite_states_give_nan_not_a_force(b):
    """A trial integrator stage with a non-finite state must be rejected, not given a force."""
    code, p = b.kernel()
    for args in [(math.nan, 0.0, 0.0, 0.0), (0.0, 0.0, math.nan, 0.0), (0.0, -1e-4, 0.0, math.inf)]:
        assert not np.all(np.isfinite(bearing_force(code, p, *args, W_RAD_S)))
    if not isinstance(b, LinearBearing):
        assert all(math.isnan(v) for v in b.force_n(0.0, -1.01 * C / (1 - getattr(b, "preload", 0.0)) - C, 0.0, 0.0,
                                                    W_RAD_S))
    if isinstance(b, TiltingPadBearing):
        u = b.pad_tilts(0.0, -0.1 * C, W_RAD_S)
        assert not np.all(np.isfinite(b.force_with_pad_states(math.nan, 0.0, 0.0, 0.0, W_RAD_S, u)[:2]))


def test_pad_states_mirror_under_reverse_rotation():
    b = TiltingPadBearing(D, L, C, MU, pads=5, pivot_offset=0.5, preload=0.2, load="on_pad")
    x, y = b.equilibrium(0.0, -ocvirk_load(0.4), W_RAD_S)
    u = b.pad_tilts(x, y, W_RAD_S)
    ur = b.pad_tilts(-x, y, -W_RAD_S)
    mirror = [0, 4, 3, 2, 1]                          # pad k at −90° + 72°k mirrors to pad −k
    np.testing.assert_allclose(ur[mirror], -u, rtol=1e-9, atol=1e-12)
    f = b.force_with_pad_states(x + 0.01 * C, y, 0.02 * C * W_RAD_S, -0.01 * C * W_RAD_S, W_RAD_S, u)
    g = b.force_with_pad_states(-x - 0.01 * C, y, -0.02 * C * W_RAD_S, -0.01 * C * W_RAD_S, -W_RAD_S, ur)
    np.testing.assert_allclose((-g[0], g[1]), f[:2], rtol=1e-9)
    np.testing.assert_allclose(g[2][mirror], -f[2], rtol=1e-8, atol=1e-9 * np.abs(f[2]).max())


def test_fixed_geometry_films_reduce_to_their_coefficients():
    for b in ALL[:2] + ALL[4:]:
        r = b.equilibrium(0.0, -ocvirk_load(0.4), W_RAD_S)
        for K1, K2 in zip(b.reduced_coefficients(*r, W_RAD_S, whirl_rad_s=0.45 * W_RAD_S), b.coefficients(*r, W_RAD_S),
                          strict=True):
            np.testing.assert_array_equal(K1, K2)
