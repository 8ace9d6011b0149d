"""Two-lobe and tilting-pad films against published closed forms and the limits that hold whatever
the source (issue 42 item 1). What is compared, and why no finite-length table is, is in
docs/bearings.md ("Two-lobe and tilting-pad coefficients: published forms and limits").

Published closed forms: the short (Ocvirk) bearing's 8 coefficients, Friswell, Penny, Garvey &
Lees, *Dynamics of Rotating Machines* (CUP 2010), section 5.5 (``ocvirk_coefficients``), and Lund's
pad-assembly reduction of a tilting-pad bearing, J. W. Lund, "Spring and damping coefficients for the
tilting-pad journal bearing", ASLE Transactions 7 (1964) 342-352 (written out here with the pad tilt
as a third degree of freedom, on the independent quadrature of tests/reference/short_film.py).
"""
from __future__ import annotations

import math

import numpy as np
import pytest
from scipy.optimize import brentq

from rotordiag.simulator.bearings import EllipticalBearing, TiltingPadBearing
from tests.reference import finite_film as ref_fin
from tests.reference import short_film as ref
from tests.test_simulator_bearings import MU, PLAIN, W_RAD_S, C, D, L, ocvirk_coefficients, ocvirk_load

EPS = [0.2, 0.5, 0.8]          # plain-bearing eccentricities whose Ocvirk loads set the load scale

TWO_LOBE_ZERO = EllipticalBearing(D, L, C, MU, preload=0.0, lobe_arc_deg=180.0)
TWO_LOBE = [
    EllipticalBearing(D, L, C, MU, preload=0.5, lobe_arc_deg=150.0),
    EllipticalBearing(D, L, C, MU, preload=0.3, lobe_arc_deg=160.0),
]
PADS = {
    "4lbp": TiltingPadBearing(D, L, C, MU, pads=4, pad_arc_deg=80.0, pivot_offset=0.5, preload=0.3, load="between_pads"),
    "4lbp_m0": TiltingPadBearing(D, L, C, MU, pads=4, pad_arc_deg=80.0, pivot_offset=0.5, preload=0.0,
                                 load="between_pads"),
    "4lop": TiltingPadBearing(D, L, C, MU, pads=4, pad_arc_deg=80.0, pivot_offset=0.5, preload=0.3, load="on_pad"),
    "5lop_offset": TiltingPadBearing(D, L, C, MU, pads=5, pad_arc_deg=60.0, pivot_offset=0.6, preload=0.2,
                                     load="on_pad"),
    "5lbp_offset": TiltingPadBearing(D, L, C, MU, pads=5, pad_arc_deg=60.0, pivot_offset=0.6, preload=0.2,
                                     load="between_pads"),
}


def _static(b, eps):
    w = ocvirk_load(eps)
    return w, b.equilibrium(0.0, -w, W_RAD_S)


# ----------------------------------------------------------------- (a) two-lobe, preload 0
@pytest.mark.parametrize("eps", [0.1, 0.3, 0.5, 0.7, 0.85])
def test_two_lobe_without_preload_has_the_published_short_bearing_coefficients(eps):
    """A two-lobe bore with m = 0 and two 180° lobes is the plain circle: its static position and
    all 8 coefficients are Ocvirk's closed forms (Friswell et al. 2010, §5.5) and the plain
    bearing's. Measured agreement ~1e-10 (central differences of the films); tolerance 1e-8."""
    w, r = _static(TWO_LOBE_ZERO, eps)
    assert math.hypot(*r) / C == pytest.approx(eps, rel=1e-9)
    np.testing.assert_allclose(r, PLAIN.equilibrium(0.0, -w, W_RAD_S), rtol=0, atol=1e-12 * C)
    K, Cm = TWO_LOBE_ZERO.coefficients(*r, W_RAD_S)
    K_ref, C_ref = ocvirk_coefficients(eps, w)
    np.testing.assert_allclose(K, K_ref, rtol=0, atol=1e-8 * np.abs(K_ref).max())
    np.testing.assert_allclose(Cm, C_ref, rtol=0, atol=1e-8 * np.abs(C_ref).max())


def test_two_lobe_without_preload_but_with_grooves_is_not_the_plain_bearing():
    """The control: m = 0 with 150° lobes leaves two 30° grooves without film, and the cross-coupled
    stiffness k_xy drops by 10-30 % (measured 0.71 x Ocvirk at ε 0.1, 0.88 at 0.5) - the check above
    is sensitive to the lobe geometry, not only to the preload."""
    b = EllipticalBearing(D, L, C, MU, preload=0.0, lobe_arc_deg=150.0)
    w, r = _static(b, 0.5)
    K, _ = b.coefficients(*r, W_RAD_S)
    K_ref, _ = ocvirk_coefficients(0.5, w)
    assert abs(K[0, 1] / K_ref[0, 1] - 1.0) > 0.05


# ----------------------------------------------------------------- (b), (c) tilting pads: cross-coupling, symmetry
@pytest.mark.parametrize("eps", EPS)
@pytest.mark.parametrize("name", list(PADS))
def test_tilting_pads_have_no_cross_coupled_stiffness(name, eps):
    """With the pads at moment equilibrium each pad's force acts along its pivot line and depends
    only on the journal's approach to it, so K = Σ k_p e_p e_pᵀ: symmetric, and diagonal for pads
    placed symmetrically about the load line (load on or between pads). Measured |k_xy|/k_yy ≤ 2e-10
    (central-difference round-off); tolerance 1e-8. The reduced (Lund) K and C likewise."""
    b = PADS[name]
    _, r = _static(b, eps)
    assert abs(r[0]) < 1e-9 * C                         # no attitude angle
    K, _ = b.coefficients(*r, W_RAD_S)
    assert max(abs(K[0, 1]), abs(K[1, 0])) < 1e-8 * K[1, 1]
    Kr, Cr = b.reduced_coefficients(*r, W_RAD_S)
    assert max(abs(Kr[0, 1]), abs(Kr[1, 0])) < 1e-8 * Kr[1, 1]
    assert max(abs(Cr[0, 1]), abs(Cr[1, 0])) < 1e-8 * Cr[1, 1]


def test_a_plain_or_two_lobe_bearing_under_the_same_load_is_cross_coupled():
    """The control for the test above: the fixed-geometry films are strongly cross-coupled."""
    for b in (PLAIN, TWO_LOBE[0]):
        _, r = _static(b, 0.5)
        K, _ = b.coefficients(*r, W_RAD_S)
        assert max(abs(K[0, 1]), abs(K[1, 0])) > 0.3 * K[1, 1]


@pytest.mark.parametrize("eps", EPS)
@pytest.mark.parametrize("name", ["4lbp", "4lbp_m0"])
def test_four_pads_loaded_between_pads_are_isotropic(name, eps):
    """Pads at ±45° and ±135°: cos² = sin² = 1/2 on every pivot line, so Σ k_p e_p e_pᵀ has k_xx = k_yy
    whatever the pads' shares of the load; the same for the reduced K, C (each pad's reduced
    impedance is radial) and for the quasi-static damping's diagonal. Measured ≤ 5e-10; tol 1e-8."""
    b = PADS[name]
    _, r = _static(b, eps)
    K, Cm = b.coefficients(*r, W_RAD_S)
    assert K[0, 0] == pytest.approx(K[1, 1], rel=1e-8)
    assert Cm[0, 0] == pytest.approx(Cm[1, 1], rel=1e-8)
    Kr, Cr = b.reduced_coefficients(*r, W_RAD_S)
    assert Kr[0, 0] == pytest.approx(Kr[1, 1], rel=1e-8)
    assert Cr[0, 0] == pytest.approx(Cr[1, 1], rel=1e-8)


def test_four_pads_loaded_on_a_pad_are_not_isotropic():
    """The control: pivots on the axes put the loaded pad's stiffness into k_yy alone
    (measured k_xx/k_yy 0.44 at the ε 0.5 load)."""
    _, r = _static(PADS["4lop"], 0.5)
    K, _ = PADS["4lop"].coefficients(*r, W_RAD_S)
    assert K[0, 0] < 0.8 * K[1, 1]


# ----------------------------------------------------------------- (d) pad assembly against a straightforward reference
def _pad_geometry(b):
    cp = C / (1.0 - b.preload)
    arc = math.radians(b.pad_arc_deg)
    out = []
    for th in b.pivot_angles_rad():
        e = np.array([math.cos(th), math.sin(th)])
        t = np.array([-e[1], e[0]])
        out.append((cp, -(cp - C) * e, th - b.pivot_offset * arc, th + (1.0 - b.pivot_offset) * arc, e, t))
    return out


def _pad_film(b, cp, centre, th1, th2, t, q, w, film=ref.film_force):
    """Reference film of one pad: q = (x, y, s, vx, vy, ṡ) with s the shift of the pad's centre of
    curvature along t (the small tilt) and ṡ its rate; returns (Fx, Fy, F·t)."""
    x, y, s, vx, vy, sd = q
    fx, fy = film(D / 2, b.length_m, MU, cp, centre, th1, th2, x, y, vx - sd * t[0], vy - sd * t[1], w,
                  shift=(s * t[0], s * t[1]))[:2]
    return np.array([fx, fy, fx * t[0] + fy * t[1]])


def _lund_reference(b, r, w, whirls, film=ref.film_force, scan=37):
    """Lund's pad assembly written out: for each pad the tilt where F·t = 0 (brentq on the reference
    film), the 3×3 impedance of (Fx, Fy, F·t) in (x, y, s) by central differences of the reference
    film, the tilt eliminated (Schur complement) at each whirl frequency, and the pads summed.
    ``scan`` shifts from −0.9 to 0.9 c_p bracket each pad's loaded root."""
    h = 1e-4 * C
    Z = {om: np.zeros((2, 2), dtype=complex) for om in whirls}
    tilts = []
    for cp, centre, th1, th2, e, t in _pad_geometry(b):
        ft = lambda s: _pad_film(b, cp, centre, th1, th2, t, (r[0], r[1], s, 0.0, 0.0, 0.0), w, film)[2]  # noqa: E731
        # loaded root: F·t rises through 0 with the shift (bracket scanned from the pad's trailing side)
        u0 = (np.asarray(r) - centre) @ t
        grid = u0 + cp * np.linspace(-0.9, 0.9, scan)
        vals = [ft(s) for s in grid]
        i = next((i for i in range(scan - 1) if vals[i] < 0.0 <= vals[i + 1] and vals[i + 1] != 0.0), None)
        if i is None:
            tilts.append(None)
            continue
        s0 = brentq(ft, grid[i], grid[i + 1], xtol=1e-15 * cp, rtol=1e-14)
        tilts.append(s0 / cp)
        q0 = np.array([r[0], r[1], s0, 0.0, 0.0, 0.0])
        Kp = np.empty((3, 3))
        Cp = np.empty((3, 3))
        for j in range(3):
            for M, step, off in ((Kp, h, 0), (Cp, h * w, 3)):
                dq = np.zeros(6)
                dq[off + j] = step
                M[:, j] = -(_pad_film(b, cp, centre, th1, th2, t, q0 + dq, w, film)
                            - _pad_film(b, cp, centre, th1, th2, t, q0 - dq, w, film)) / (2 * step)
        for om in whirls:
            Zp = Kp + 1j * om * Cp
            Z[om] += Zp[:2, :2] - np.outer(Zp[:2, 2], Zp[2, :2]) / Zp[2, 2]
    return Z, tilts


@pytest.mark.parametrize("name", ["4lbp", "5lop_offset", "4lop"])
def test_pad_assembly_equals_lund_reference_on_an_independent_film(name):
    """``reduced_coefficients`` (and ``coefficients``' K, the ω → 0 limit) against Lund's pad
    assembly written out on the scipy-quadrature film: each pad's tilt equals the kernel's, and K, C
    at synchronous and half-synchronous whirl agree. Reference error: central differences with step
    1e-4 c (truncation ~1e-8) of a quadrature at 1e-12; measured ≤ 9e-8 of the largest entry (tilts
    to 3e-15); tolerance 1e-6."""
    b = PADS[name]
    _, r = _static(b, 0.5)
    whirls = (W_RAD_S, 0.5 * W_RAD_S, 1e-9 * W_RAD_S)
    Z, tilts = _lund_reference(b, r, W_RAD_S, whirls)
    assert sum(u is not None for u in tilts) >= 2
    for u, u_k in zip(tilts, b.pad_tilts(*r, W_RAD_S), strict=True):
        if u is not None:
            assert u == pytest.approx(u_k, abs=1e-12)
    for om in whirls[:2]:
        K, Cm = b.reduced_coefficients(*r, W_RAD_S, whirl_rad_s=om)
        np.testing.assert_allclose(K, Z[om].real, rtol=0, atol=1e-6 * np.abs(K).max())
        np.testing.assert_allclose(Cm, Z[om].imag / om, rtol=0, atol=1e-6 * np.abs(Cm).max())
    Kq, _ = b.coefficients(*r, W_RAD_S)
    np.testing.assert_allclose(Kq, Z[whirls[2]].real, rtol=0, atol=1e-6 * np.abs(Kq).max())


def test_a_pad_force_depends_only_on_the_approach_to_its_pivot():
    """The reason for K = Σ k_p e_p e_pᵀ: moving the journal along a pad's pivot tangent is taken up
    by the pad's tilt (its centre of curvature shifts by the same amount, u by Δs/c_p), so the pad's
    film, and its force, do not change."""
    b = PADS["5lop_offset"]
    _, r = _static(b, 0.5)
    u0 = b.pad_tilts(*r, W_RAD_S)
    for k, (cp, _, _, _, _, t) in enumerate(_pad_geometry(b)):
        for ds in (-0.05 * C, 0.05 * C):
            u1 = b.pad_tilts(r[0] + ds * t[0], r[1] + ds * t[1], W_RAD_S)
            assert u1[k] - u0[k] == pytest.approx(ds / cp, rel=1e-9)


# ----------------------------------------------------------------- (e) energy: damping dissipates
@pytest.mark.parametrize("eps", EPS)
@pytest.mark.parametrize("b", [PLAIN, TWO_LOBE_ZERO, *TWO_LOBE, *PADS.values()],
                         ids=["plain", "two_lobe_m0", "two_lobe_m05", "two_lobe_m03", *PADS])
def test_damping_is_positive_semi_definite(b, eps):
    """A squeeze film only dissipates: the power vᵀ C v ≥ 0 for every velocity, i.e. the symmetric
    part of C is positive semi-definite (its skew part, present in the quasi-static tilting-pad C,
    does no work). Checked for ``coefficients`` and, for tilting pads, the synchronous reduced C."""
    _, r = _static(b, eps)
    mats = [b.coefficients(*r, W_RAD_S)[1], b.reduced_coefficients(*r, W_RAD_S)[1]]
    for Cm in mats:
        lam = np.linalg.eigvalsh(0.5 * (Cm + Cm.T))
        assert lam.min() >= -1e-9 * np.abs(Cm).max(), lam


# ----------------------------------------------------------------- (f) coefficients are the force's derivatives
@pytest.mark.parametrize("eps", EPS)
@pytest.mark.parametrize("b", [*TWO_LOBE, PADS["4lbp"], PADS["5lop_offset"]],
                         ids=["two_lobe_m05", "two_lobe_m03", "4lbp", "5lop_offset"])
def test_coefficients_are_fourth_order_differences_of_the_force(b, eps):
    """K, C against fourth-order central differences of ``force_n`` (step 1e-3 c, truncation ~1e-12;
    a different stencil and step from ``coefficients``) at the static position under three loads."""
    _, r = _static(b, eps)
    K, Cm = b.coefficients(*r, W_RAD_S)
    h = 1e-3 * C

    def d4(f, j, step):
        e = np.eye(2)[j] * step
        return (8 * (f(e) - f(-e)) - (f(2 * e) - f(-2 * e))) / (12 * step)

    for j in range(2):
        dk = d4(lambda d: np.array(b.force_n(r[0] + d[0], r[1] + d[1], 0.0, 0.0, W_RAD_S)), j, h)
        dc = d4(lambda d: np.array(b.force_n(r[0], r[1], d[0], d[1], W_RAD_S)), j, h * W_RAD_S)
        np.testing.assert_allclose(-dk, K[:, j], rtol=0, atol=1e-6 * np.abs(K).max())
        np.testing.assert_allclose(-dc, Cm[:, j], rtol=0, atol=1e-6 * np.abs(Cm).max())



# ----------------------------------------------------------------- the short films as the L/D → 0 limit of Reynolds
SLENDER = (0.1, 0.05, 0.025)      # L/D at which the finite-length reference is solved


def _slender(b, ld):
    """``b`` with length ld·D, and the load that puts a plain bearing of that length at ε 0.5."""
    return (b.__class__(**{k: v for k, v in b.to_dict().items() if k != "type"} | {"length_m": ld * D}),
            ocvirk_load(0.5) * (ld * D / L) ** 3)


def _finite_two_lobe_force(b, x, y, vx, vy):
    """Finite-length reference force of a two-lobe bore, lobes built from its public parameters."""
    cl = C / (1.0 - b.preload)
    half = 0.5 * math.radians(b.lobe_arc_deg)
    f = np.zeros(2)
    for th in (-0.5 * math.pi, 0.5 * math.pi):
        centre = (-b.preload * cl * math.cos(th), -b.preload * cl * math.sin(th))
        f += ref_fin.film_force(D / 2, b.length_m, MU, cl, centre, th - half, th + half, x, y, vx, vy, W_RAD_S)
    return f


def _rel(a, b_):
    return float(np.abs(np.asarray(a) - np.asarray(b_)).max() / np.abs(b_).max())


def _finite_coefficients(force, r, h):
    """K, C of a reference force(x, y, vx, vy) by central differences about the journal at rest at r."""
    K = np.empty((2, 2))
    Cm = np.empty((2, 2))
    for j in range(2):
        e = np.eye(2)[j] * h
        K[:, j] = -(force(r[0] + e[0], r[1] + e[1], 0.0, 0.0) - force(r[0] - e[0], r[1] - e[1], 0.0, 0.0)) / (2 * h)
        ev = e * W_RAD_S
        Cm[:, j] = -(force(r[0], r[1], ev[0], ev[1]) - force(r[0], r[1], -ev[0], -ev[1])) / (2 * h * W_RAD_S)
    return K, Cm


@pytest.mark.parametrize("b", [TWO_LOBE[0], pytest.param(TWO_LOBE[1], marks=pytest.mark.slow)],
                         ids=["m05_150deg", "m03_160deg"])
def test_two_lobe_film_is_the_short_length_limit_of_reynolds(b):
    """The two-lobe film (lobe geometry, preload, arcs, wedge and squeeze terms) against the
    finite-length Reynolds equation on the same lobes (tests/reference/finite_film.py): the
    short-bearing solution is its limit L/D → 0, so the force with squeeze and K, C at the static
    position must approach it as L/D halves. The finite film's pressure vanishes at the lobe ends
    over a layer ~L wide, so the approach is first order in L/(R·arc) (errors halve with L/D).
    Measured at L/D 0.1, 0.05, 0.025 (force, K, C): m 0.5, 150°: 2.6/5.2/2.6 %, 0.82/1.4/0.96 %,
    0.36/0.45/0.49 %; m 0.3, 160°: 1.7/3.9/4.7 %, 0.54/1.6/2.1 %, 0.23/0.90/1.1 %. Asserted: each
    halving cuts the force and K errors by ≥ 1.5×, and at L/D 0.025 all three are below 1.5 %."""
    errs = []
    for ld in SLENDER:
        bs, w = _slender(b, ld)
        r = bs.equilibrium(0.0, -w, W_RAD_S)
        v = (0.05 * C * W_RAD_S, -0.03 * C * W_RAD_S)
        e_f = _rel(_finite_two_lobe_force(bs, *r, *v), bs.force_n(*r, *v, W_RAD_S))
        Kf, Cf = _finite_coefficients(lambda *q, bs=bs: _finite_two_lobe_force(bs, *q), r, 1e-3 * C)
        K, Cm = bs.coefficients(*r, W_RAD_S)
        errs.append((e_f, _rel(Kf, K), _rel(Cf, Cm)))
    print("two-lobe finite/short errors (force, K, C) at L/D", SLENDER, ":", np.round(errs, 4).tolist())
    errs = np.array(errs)
    assert np.all(errs[:-1, :2] > 1.5 * errs[1:, :2]), errs
    assert np.all(errs[-1] < 0.015), errs


@pytest.mark.parametrize("name", ["4lbp", pytest.param("5lop_offset", marks=pytest.mark.slow)])
def test_tilting_pad_film_is_the_short_length_limit_of_reynolds(name):
    """Each pad's film at the tilts the kernel finds, on the finite-length Reynolds equation: the
    pads' summed force approaches the kernel's static force, and each loaded pad's tangential force
    F·t (zero at the kernel's tilt: moment equilibrium) vanishes relative to its load, as L/D halves
    (first order, as for the lobes). Measured at L/D 0.05, 0.025 (force error, max |F·t|/|F|): 4-pad
    LBP 1.1/0.76 %, 0.47/0.36 %; 5-pad LOP 0.6 offset 5.1/1.1 %, 2.5/0.59 % (60° pads: L/(R·arc)
    is larger). Asserted: halving L/D cuts both by ≥ 1.6×; at 0.025 force < 3 %, F·t < 1 %."""
    errs = []
    for ld in SLENDER[1:]:
        bs, w = _slender(PADS[name], ld)
        r = bs.equilibrium(0.0, -w, W_RAD_S)
        f = np.zeros(2)
        ft_rel = 0.0
        for (cp, centre, th1, th2, _, t), u in zip(_pad_geometry(bs), bs.pad_tilts(*r, W_RAD_S), strict=True):
            fp = _pad_film(bs, cp, centre, th1, th2, t, (r[0], r[1], u * cp, 0.0, 0.0, 0.0), W_RAD_S, ref_fin.film_force)
            f += fp[:2]
            if np.hypot(*fp[:2]) > 0.05 * w:
                ft_rel = max(ft_rel, abs(fp[2]) / np.hypot(*fp[:2]))
        errs.append((_rel(f, bs.force_n(*r, 0.0, 0.0, W_RAD_S)), ft_rel))
    print(f"tilting pad {name} finite/short (force error, max |F·t|/|F| of loaded pads) at L/D", SLENDER[1:], ":",
          np.round(errs, 5).tolist())
    errs = np.array(errs)
    assert np.all(errs[0] > 1.6 * errs[1]), errs
    assert errs[-1, 0] < 0.03 and errs[-1, 1] < 0.01, errs


@pytest.mark.slow
def test_pad_assembly_is_the_short_length_limit_of_lund_on_reynolds():
    """Lund's pad assembly on the finite-length film (its own tilts, 3×3 pad impedances, Schur
    complement) against ``reduced_coefficients`` at synchronous whirl, 4-pad LBP: the K, C errors
    fall as L/D halves and are below 2 % at L/D 0.025 (measured 4.1/3.4 % at 0.05, 1.8/1.5 % at 0.025)."""
    errs = []
    for ld in SLENDER[1:]:
        bs, w = _slender(PADS["4lbp"], ld)
        r = bs.equilibrium(0.0, -w, W_RAD_S)
        Z, _ = _lund_reference(bs, r, W_RAD_S, (W_RAD_S,), film=ref_fin.film_force, scan=19)
        K, Cm = bs.reduced_coefficients(*r, W_RAD_S)
        errs.append((_rel(Z[W_RAD_S].real, K), _rel(Z[W_RAD_S].imag / W_RAD_S, Cm)))
    print("4-pad LBP reduced K, C finite/short errors at L/D", SLENDER[1:], ":", np.round(errs, 4).tolist())
    errs = np.array(errs)
    assert np.all(errs[0] > errs[1]), errs
    assert np.all(errs[-1] < 0.02), errs
