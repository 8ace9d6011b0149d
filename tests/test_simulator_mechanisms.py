"""The stationary shaft-line mechanisms ``offset`` and ``flexible`` (issue 13, docs/model.md)."""
import math

import numpy as np
import pytest

from rotordiag.simulator import Plant, build_system, simulate
from rotordiag.simulator import _kernels as K
from rotordiag.simulator.simulate import order_amplitudes

LINEAR = dict(bearing_model="linear", linear_bearing_stiffness_n_m=1.0e9, linear_bearing_damping_n_s_m=2.0e6,
              asymmetry=0.0)


def _hand_static_loads(pl: Plant, centres: np.ndarray) -> np.ndarray:
    """Static bearing reactions (N, (4, 2)) of the lumped chain with linear isotropic bearings and a
    rigid coupling (r3 = r4): nodes 1, 2, 3≡4, 5, 6; solved per direction as a 5×5 linear system."""
    kb, k1, k2, g = pl.linear_bearing_stiffness_n_m, pl.generator_stiffness_n_m, pl.exciter_stiffness_n_m, pl.gravity_m_s2
    m = np.array([pl.journal1_mass_kg, pl.generator_mass_kg, pl.journal3_mass_kg + pl.journal4_mass_kg,
                  pl.exciter_mass_kg, pl.journal6_mass_kg])
    # stiffness matrix: springs 1-2 (k1), 2-34 (k1), 34-5 (k2), 5-6 (k2); bearings at 1, 34 (two), 6
    Kmat = np.zeros((5, 5))
    for a, b, k in ((0, 1, k1), (1, 2, k1), (2, 3, k2), (3, 4, k2)):
        Kmat[a, a] += k
        Kmat[b, b] += k
        Kmat[a, b] -= k
        Kmat[b, a] -= k
    node_of_bearing = (0, 2, 2, 4)
    for n in node_of_bearing:
        Kmat[n, n] += kb
    loads = np.zeros((4, 2))
    for d in range(2):
        f = np.zeros(5)
        for b, n in enumerate(node_of_bearing):
            f[n] += kb * centres[b, d]
        if d == 1:
            f -= m * g
        u = np.linalg.solve(Kmat, f)
        for b, n in enumerate(node_of_bearing):
            loads[b, d] = kb * (centres[b, d] - u[n])
    return loads


@pytest.mark.parametrize("delta, angle_deg", [(0.3, -90.0), (0.5, 30.0)])
def test_offset_static_bearing_loads_match_hand_calculation(delta, angle_deg):
    pl = Plant.default().replace(**LINEAR)
    res = simulate(pl, 1950.0, delta, 0.0, mechanism="offset", offset_angle_rad=math.radians(angle_deg),
                   transient_revs=300, record_revs=4, samples_per_rev=16, settle_tol=1e-10)
    assert res.ok
    centres = np.zeros((4, 2))
    d = delta * pl.clearance_m * np.array([math.cos(math.radians(angle_deg)), math.sin(math.radians(angle_deg))])
    centres[2:] = d
    np.testing.assert_allclose(res.bearing_offset_m, centres, atol=1e-15)
    hand = _hand_static_loads(pl, centres)
    np.testing.assert_allclose(res.mean_bearing_load_n, hand, rtol=1e-6, atol=1e-3 * np.abs(hand).max() * 1e-3)
    # the offset really moves load between the bearings (not a test that the aligned loads come back)
    aligned = _hand_static_loads(pl, np.zeros((4, 2)))
    assert np.abs(hand - aligned).max() > 1e3
    # total vertical reaction = weight
    total = sum(getattr(pl, n) for n in ("journal1_mass_kg", "generator_mass_kg", "journal3_mass_kg",
                                         "journal4_mass_kg", "exciter_mass_kg", "journal6_mass_kg"))
    assert res.mean_bearing_load_n[:, 1].sum() == pytest.approx(total * pl.gravity_m_s2, rel=1e-6)


def test_offset_tends_to_aligned():
    pl = Plant.default()
    kw = dict(transient_revs=200, record_revs=8, samples_per_rev=32, settle_tol=1e-9)
    ref = simulate(pl, 1950.0, 0.0, 0.05, mechanism="aligned", **kw)
    diffs = []
    for delta in (1e-2, 1e-3):
        r = simulate(pl, 1950.0, delta, 0.05, mechanism="offset", offset_angle_rad=-math.pi / 2, **kw)
        assert r.inputs["mechanism"] == "offset"
        diffs.append(np.abs(r.journal_displacements_m - ref.journal_displacements_m).max() / pl.clearance_m)
    assert diffs[0] < 2e-2 and diffs[1] < 2e-3
    assert diffs[1] / diffs[0] == pytest.approx(0.1, rel=0.2)  # first order in Δ
    # Δ = 0 is exactly aligned
    r0 = simulate(pl, 1950.0, 0.0, 0.05, mechanism="offset", **kw)
    assert r0.inputs["mechanism"] == "aligned"
    np.testing.assert_array_equal(r0.positions_m, ref.positions_m)


def _u_closed_form(tau, delta, psi, phi0):
    """Docs/model.md: u = (δ/2)·[cos(2τ+ψ) e_δ + sin(2τ+ψ) e_⊥], written with a rotation matrix."""
    R = np.array([[math.cos(phi0), -math.sin(phi0)], [math.sin(phi0), math.cos(phi0)]])
    return 0.5 * delta * R @ np.array([math.cos(2 * tau + psi), math.sin(2 * tau + psi)])


def test_flexible_coupling_force_is_gradient_of_its_potential_and_closed_form():
    pl = Plant.default().replace(coupling_damping_n_s_m=0.0)
    sysm = build_system(pl, 1950.0, 0.3, 0.05, mechanism="flexible", coupling_phase_rad=0.7, offset_angle_rad=-1.1)
    p = sysm.params
    kc = p[K.P_KC]
    rng = np.random.default_rng(3)
    for _ in range(20):
        y = rng.normal(scale=0.3, size=K.N_STATE_FLEXIBLE)
        tau = rng.uniform(0, 20)
        u = _u_closed_form(tau, 0.3, 0.7, -1.1)

        def V(r3, r4):
            e = r4 - r3 - u
            return 0.5 * kc * e @ e

        r3, r4 = y[22:24].copy(), y[4:6].copy()
        h = 1e-6
        grad3 = np.array([(V(r3 + h * e, r4) - V(r3 - h * e, r4)) / (2 * h) for e in np.eye(2)])
        grad4 = np.array([(V(r3, r4 + h * e) - V(r3, r4 - h * e)) / (2 * h) for e in np.eye(2)])
        f3 = np.array(K.coupling_force(tau, y, p))
        np.testing.assert_allclose(f3, -grad3, rtol=1e-7, atol=1e-9 * kc)
        np.testing.assert_allclose(-f3, -grad4, rtol=1e-7, atol=1e-9 * kc)
    # with the hubs held together the force is a pure 2X of amplitude k_c·δ/2 (0-pk), phase ψ
    tau = np.arange(64) * 2 * math.pi / 64
    y = np.zeros(K.N_STATE_FLEXIBLE)
    f = np.array([K.coupling_force(t, y, p) for t in tau]) * pl.clearance_m * sysm.speed_rad_s**2
    spec = np.fft.fft(f[:, 0] + 1j * f[:, 1]) / 64
    amp = pl.coupling_stiffness_n_m * 0.3 * pl.clearance_m / 2
    assert abs(spec[2]) == pytest.approx(amp, rel=1e-12)  # forward whirl at +2X
    assert np.abs(np.delete(spec, 2)).max() < 1e-9 * amp
    assert np.angle(spec[2]) == pytest.approx(math.remainder(0.7 - 1.1 + math.pi, 2 * math.pi), abs=1e-9)


def test_flexible_rhs_couples_nodes_3_and_4_by_the_coupling_force():
    pl = Plant.default()
    sysm = build_system(pl, 1950.0, 0.2, 0.05, mechanism="flexible")
    y = sysm.initial_state()
    assert y.shape == (K.N_STATE_FLEXIBLE,)
    dy = sysm.rhs(0.3, y)
    p = sysm.params
    stiff = sysm.params.copy()
    stiff[K.P_KC] *= 2.0
    dy2 = K.rhs_alloc(0.3, y, stiff)
    fc = np.array(K.coupling_force(0.3, y, p))
    # doubling k_c adds F_c/m3 to node 3's acceleration and −F_c/m4 to node 4's; nothing else changes
    np.testing.assert_allclose(dy2[24:26] - dy[24:26], fc / p[K.P_M3], rtol=1e-10)
    np.testing.assert_allclose(dy2[15:17] - dy[15:17], -fc / p[K.P_M4], rtol=1e-10)
    others = np.r_[0:15, 17:24]
    np.testing.assert_array_equal(dy2[others], dy[others])


def test_flexible_stiff_coupling_small_offset_tends_to_aligned():
    kw = dict(transient_revs=200, record_revs=8, samples_per_rev=32, settle_tol=1e-9)
    ref = order_amplitudes(simulate(Plant.default(), 1950.0, 0.0, 0.05, mechanism="aligned", **kw), (1, 2))
    errs = []
    for kc in (1e9, 1e10):
        r = simulate(Plant.default().replace(coupling_stiffness_n_m=kc), 1950.0, 1e-5, 0.05, mechanism="flexible", **kw)
        errs.append(np.abs(order_amplitudes(r, (1, 2)) - ref).max() / np.abs(ref).max())
    # converges like 1/k_c as the coupling stiffens (measured 0.14, 0.016, 0.0016 for 1e9, 1e10, 1e11 N/m)
    assert errs[1] < 0.03
    assert errs[0] / errs[1] == pytest.approx(10.0, rel=0.3)


def test_flexible_2x_grows_with_offset_at_the_exciter_coupling_bearing():
    kw = dict(transient_revs=200, record_revs=8, samples_per_rev=32, settle_tol=1e-9)
    pl = Plant.default().replace(asymmetry=0.0)  # no 2X of the generator's own: only the coupling's
    two_x = [order_amplitudes(simulate(pl, 1950.0, d, 0.05, mechanism="flexible", **kw), (2,))[2, 0, 0]
             for d in (0.05, 0.1, 0.2)]
    # nearly a forced linear response: 2X at journal 4 proportional to Δ (the coupling drives it directly)
    assert two_x[1] / two_x[0] == pytest.approx(2.0, rel=0.1)
    assert two_x[2] / two_x[1] == pytest.approx(2.0, rel=0.1)


def test_bad_inputs_name_the_parameter():
    pl = Plant.default()
    with pytest.raises(ValueError, match="mechanism must be one of"):
        simulate(pl, 1950.0, 0.1, 0.05, mechanism="parallel")
    with pytest.raises(ValueError, match="coupling_phase_rad"):
        simulate(pl, 1950.0, 0.1, 0.05, mechanism="flexible", coupling_phase_rad=float("nan"))
    with pytest.raises(ValueError, match="coupling_stiffness_n_m"):
        Plant.default().replace(coupling_stiffness_n_m=0.0)
    with pytest.raises(ValueError, match="coupling_damping_n_s_m"):
        Plant.default().replace(coupling_damping_n_s_m=-1.0)
    with pytest.raises(ValueError, match=r"shape \(26,\)"):
        simulate(pl, 1950.0, 0.1, 0.05, mechanism="flexible", initial_state=np.zeros(22))


def test_new_plant_fields_keep_earlier_plant_ids():
    # ids written by the code before the coupling fields existed (main at cf8bd97)
    assert Plant.default().plant_id() == "468b143a1dc382b0"
    assert Plant.default().replace(clearance_m=3e-4).plant_id() == "d0d9ba92dd66afd1"
    changed = Plant.default().replace(coupling_stiffness_n_m=2e8)
    assert changed.plant_id() != Plant.default().plant_id()


def test_dataset_spec_accepts_every_mechanism_coupling_phase_and_a_preset_plant():
    from rotordiag.simulator.dataset.design import build_design
    from rotordiag.simulator.dataset.spec import SpecError, parse_spec
    from rotordiag.simulator.shaftline import preset, to_plant
    from tests.dataset_support import SMALL_SPEC

    text = SMALL_SPEC.format(n_samples=16, seed=7, sample_rate_hz=1024.0, transient_revs=30)
    text = text.replace("mechanism = {pin = 1, rigid = 1}", "coupling_phase_rad = {min = 0.0, max = 6.28}\n"
                        "mechanism = {pin = 1, rigid = 1, offset = 1, flexible = 1}")
    text = text.replace("[plant.perturb]", "[plant]\npreset = \"gen600_4pole\"\n\n[plant.perturb]")
    r = parse_spec(text)
    assert r.base_plant == to_plant(preset("gen600_4pole"))
    design = build_design(r)
    mechs = {design[i].mechanism for i in range(len(design))}
    assert mechs == {"pin", "rigid", "offset", "flexible"}
    phases = [design[i].coupling_phase_rad for i in range(len(design))]
    assert min(phases) >= 0 and max(phases) <= 6.28 and len(set(phases)) == len(phases)
    with pytest.raises(SpecError, match="unknown mechanism"):
        parse_spec(text.replace("offset = 1", "parallel = 1"))


def test_mechanism_survey_table_and_figure(tmp_path, monkeypatch):
    from rotordiag.simulator.analysis import mechanisms as ms

    monkeypatch.setattr(ms, "PHASES_DEG", (0.0, 180.0))
    monkeypatch.setattr(ms, "COUPLING_STIFFNESSES_N_M", (1e8,))
    pts = ms.mechanism_survey(speeds_rpm=(1950.0,), deltas=(0.0, 0.2), record_revs=8, workers=0)
    assert len(pts) == 1 + len(ms.CASES) + 2 + 1
    assert all(p.status == "ok" for p in pts)
    by = {p.case: p for p in pts if p.coupling_phase_deg == 0 and p.case not in ("flexible-kc",)}
    # the survey's own numbers: flexible's 2X at bearing 3 exceeds 1X, rigid's 1X at bearing 3 dwarfs aligned's
    assert by["flexible"].ratio(2) > 1 > by["aligned"].ratio(2)
    assert by["rigid"].amp_1x_um_0pk[2][0] > 5 * by["aligned"].amp_1x_um_0pk[2][0]
    md = ms.survey_markdown(pts)
    assert "| flexible | 1950 | 0.2 |" in md and "| ψ (°) |" in md
    ms.survey_figure(pts, tmp_path / "m.png")
    assert (tmp_path / "m.png").stat().st_size > 10_000


# ---------------------------------------------------------------------------------- angular offset
@pytest.mark.parametrize("delta, alpha_mrad, angle_deg", [(0.0, 0.08, -90.0), (0.2, -0.05, 30.0)])
def test_angular_offset_static_bearing_loads_match_hand_calculation(delta, alpha_mrad, angle_deg):
    """Exciter line tilted about the coupling (bearing 3 at the coupling stays, bearing 4 moves by α·L),
    plus an optional parallel δ: the same 5×5 hand solution of the lumped chain as the parallel case."""
    pl = Plant.default().replace(**LINEAR, exciter_bearing_span_m=2.5)
    res = simulate(pl, 1950.0, delta, 0.0, mechanism="offset", offset_angle_rad=math.radians(angle_deg),
                   angular_misalignment_mrad=alpha_mrad, transient_revs=300, record_revs=4, samples_per_rev=16,
                   settle_tol=1e-10)
    assert res.ok and res.inputs["mechanism"] == "offset"
    assert res.inputs["angular_misalignment_mrad"] == alpha_mrad
    e = np.array([math.cos(math.radians(angle_deg)), math.sin(math.radians(angle_deg))])
    centres = np.zeros((4, 2))
    centres[2] = delta * pl.clearance_m * e
    centres[3] = (delta * pl.clearance_m + alpha_mrad * 1e-3 * 2.5) * e
    np.testing.assert_allclose(res.bearing_offset_m, centres, atol=1e-15)
    hand = _hand_static_loads(pl, centres)
    np.testing.assert_allclose(res.mean_bearing_load_n, hand, rtol=1e-6, atol=1e-6 * np.abs(hand).max())
    # the tilt itself moves load (against the same δ without it)
    centres_par = centres.copy()
    centres_par[3] = centres[2]
    assert np.abs(hand - _hand_static_loads(pl, centres_par)).max() > 1e3
    # static journal positions are reported relative to the moved bearing centres
    assert res.static_position_m.shape == (4, 2) and np.all(res.static_eccentricity < 1)


def test_angular_offset_tends_to_aligned_and_zero_is_aligned():
    pl = Plant.default()
    kw = dict(transient_revs=200, record_revs=8, samples_per_rev=32, settle_tol=1e-9)
    ref = simulate(pl, 1950.0, 0.0, 0.05, mechanism="aligned", **kw)
    diffs = []
    for alpha in (1e-2, 1e-3):
        r = simulate(pl, 1950.0, 0.0, 0.05, mechanism="offset", offset_angle_rad=-math.pi / 2,
                     angular_misalignment_mrad=alpha, **kw)
        assert r.inputs["mechanism"] == "offset"
        diffs.append(np.abs(r.journal_displacements_m - ref.journal_displacements_m).max() / pl.clearance_m)
    assert 0 < diffs[1] < diffs[0] < 0.1
    assert diffs[1] / diffs[0] == pytest.approx(0.1, rel=0.2)  # first order in α
    for mech in ("offset", "flexible"):
        r0 = simulate(pl, 1950.0, 0.0, 0.05, mechanism=mech, angular_misalignment_mrad=0.0, **kw)
        assert r0.inputs["mechanism"] == "aligned"
        np.testing.assert_array_equal(r0.positions_m, ref.positions_m)


def test_angular_offset_bad_input_names_the_parameter():
    pl = Plant.default()
    for mech in ("pin", "rigid", "aligned"):
        with pytest.raises(ValueError, match="angular_misalignment_mrad .*'offset' or 'flexible'"):
            simulate(pl, 1950.0, 0.1 if mech != "aligned" else 0.0, 0.05, mechanism=mech,
                     angular_misalignment_mrad=0.05)
    with pytest.raises(ValueError, match=r"angular_misalignment_mrad must be within ±0.09265 mrad"):
        simulate(pl, 1950.0, 0.1, 0.05, mechanism="offset", angular_misalignment_mrad=0.2)
    with pytest.raises(ValueError, match="angular_misalignment_mrad must be a finite number"):
        simulate(pl, 1950.0, 0.1, 0.05, mechanism="offset", angular_misalignment_mrad=float("nan"))
    with pytest.raises(ValueError, match="exciter_bearing_span_m must be > 0"):
        Plant.default().replace(exciter_bearing_span_m=0.0)
    # the new plant field keeps earlier plant ids at its default
    assert Plant.default().replace(exciter_bearing_span_m=3.4).plant_id() == "468b143a1dc382b0"


def test_angular_offset_cli_and_dataset_spec(tmp_path):
    import json

    from typer.testing import CliRunner

    from rotordiag.cli import app
    from rotordiag.simulator.dataset.design import build_design
    from rotordiag.simulator.dataset.spec import SpecError, parse_spec
    from rotordiag.simulator.dataset.store import ANGULAR_DATASETS, layout
    from tests.dataset_support import SMALL_SPEC

    out = CliRunner().invoke(app, ["simulate", "--speed-rpm", "1950", "--misalignment", "0", "--mechanism", "offset",
                                   "--angular-misalignment-mrad", "0.05", "--offset-angle-deg", "-90",
                                   "--transient-revs", "60", "--record-revs", "4", "--json"])
    assert out.exit_code == 0, out.output
    summary = json.loads(out.output)
    assert summary["mechanism"] == "offset" and summary["angular_misalignment_mrad"] == 0.05
    bad = CliRunner().invoke(app, ["simulate", "--speed-rpm", "1950", "--misalignment", "0.1", "--mechanism", "pin", "--angular-misalignment-mrad", "0.05",
                                   "--transient-revs", "10", "--record-revs", "2"], env={"COLUMNS": "400"})
    assert bad.exit_code != 0 and "angular_misalignment_mrad" in bad.output

    text = SMALL_SPEC.format(n_samples=8, seed=7, sample_rate_hz=1024.0, transient_revs=30)
    plain = parse_spec(text)
    angular = parse_spec(text.replace("mechanism = {pin = 1, rigid = 1}",
                                      "angular_misalignment_mrad = {min = -0.05, max = 0.05}\n"
                                      "mechanism = {offset = 1, flexible = 1}"))
    # a spec without it: same hash as an explicit 0, and a design and layout without it
    assert parse_spec(text.replace("mechanism = {pin = 1, rigid = 1}",
                                   "angular_misalignment_mrad = 0.0\nmechanism = {pin = 1, rigid = 1}")
                      ).spec_hash == plain.spec_hash
    assert angular.spec_hash != plain.spec_hash
    d_plain = build_design(plain)
    assert all(d_plain[i].angular_misalignment_mrad == 0.0 for i in range(len(d_plain)))
    d_ang = build_design(angular)
    alphas = [d_ang[i].angular_misalignment_mrad for i in range(len(d_ang))]
    assert min(alphas) >= -0.05 and max(alphas) <= 0.05 and len(set(alphas)) == len(alphas)
    L0 = layout(8, 64, 4, plain.base_plant.to_dict())
    L1 = layout(8, 64, 4, angular.base_plant.to_dict(), angular=True)
    assert not set(ANGULAR_DATASETS) & set(L0) and set(ANGULAR_DATASETS) <= set(L1)
    with pytest.raises(SpecError, match="angular_misalignment_mrad"):
        parse_spec(text.replace("mechanism = {pin = 1, rigid = 1}", "angular_misalignment_mrad = 50.0\n"
                                "mechanism = {pin = 1, rigid = 1}"))


def test_flexible_range_and_angular_surveys(tmp_path):
    from rotordiag.simulator.analysis import mechanisms as ms

    pts = ms.flexible_range_survey(speeds_rpm=(1950.0,), stiffnesses_n_m=(1e8,), phases_deg=(0.0, 180.0),
                                   deltas=(0.1, 0.3), record_revs=8, workers=0)
    assert len(pts) == 1 + 2 * 2 and all(p.status == "ok" for p in pts)
    v = ms._range_verdict(pts, 1950.0, 1e8, 2)
    # the verdict is the runs' own numbers: growth per phase, ratio range at the largest Δ
    last = [p for p in pts if p.misalignment == 0.3]
    assert v["ratio"] == (min(p.ratio(2) for p in last), max(p.ratio(2) for p in last))
    grows = sum(
        next(p for p in pts if p.misalignment == 0.3 and p.coupling_phase_deg == psi).amp_2x_um_0pk[2][0]
        > next(p for p in pts if p.misalignment == 0.1 and p.coupling_phase_deg == psi).amp_2x_um_0pk[2][0]
        for psi in (0.0, 180.0))
    assert v["grows"] == f"{grows}/2"
    md = ms.range_markdown(pts)
    assert "| 1950 | 1e+08 | 3 |" in md
    ms.range_figure(pts, tmp_path / "r.png")
    assert (tmp_path / "r.png").stat().st_size > 10_000

    ang = ms.angular_survey(speeds_rpm=(1950.0,), alphas_mrad=(0.06,), record_revs=8, workers=0)
    by = {p.case: p for p in ang}
    assert all(p.status == "ok" for p in ang)
    assert by["angular-down"].angular_misalignment_mrad == 0.06
    # a downward tilt lowers bearing 4: it unloads (lumped model) while bearing 3's load barely moves
    assert by["angular-down"].static_load_n[3][1] < by["aligned"].static_load_n[3][1] - 3e3
    assert abs(by["angular-down"].static_load_n[2][1] - by["aligned"].static_load_n[2][1]) < 1e3
    assert "| angular-down | 1950 | 0 | 0.06 |" in ms.angular_markdown(ang)
