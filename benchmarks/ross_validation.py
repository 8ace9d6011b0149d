"""Independent-code validation set: machines of another design built with ROSS (issue 15, item 7).

    .venv/bin/pip install -e '.[validation]'                      # ross-rotordynamics, plotly<6
    .venv/bin/python benchmarks/ross_validation.py [--out benchmarks/ross_set.npz]
    .venv/bin/python benchmarks/ross_validation.py --band          # benchmarks/ross_band_set.npz (issue 17)

ROSS (``ross-rotordynamics`` 2.3.0, a finite-element rotordynamics code independent of this
project) is used **only here, for validation**: nothing is trained on this set, and rotordiag
never imports ROSS. The generated set is a small ``.npz`` of complex harmonic amplitudes; the
probe waveforms are synthesised from it by :func:`load_ross_set` (NumPy only, seeded), so the
benchmark and the tests run without ROSS installed.

Machines (:data:`MACHINES`): generator–exciter shaft lines of Timoshenko beam elements
(``ross.ShaftElement``: steel, shear, rotary inertia, gyroscopics), the generator body and the
exciter as thick shaft sections (distributed mass, not lumped disks), a flexible coupling
between them (``ross.CouplingElement`` with radial stiffness ``coupling_stiffness_n_m``),
four **linear, anisotropic** bearings (``ross.BearingElement``, k_yy = 1.6 k_xx, damping
c = 4e-4 s · k), coupling hubs overhung beyond bearings 2 and 3. They differ from the
project's own plant family (lumped 11-DOF model, nonlinear short-bearing oil films, pin/rigid
constraints) in structure, bearing model and coupling model.

Forcing: generator-body and exciter unbalance (ISO balance grades, seeded phases) and, for the
misaligned cases, ROSS's own **flexible-coupling parallel-misalignment** reaction force
(``ross.faults.misalignment.MisalignmentFlex``, ``mis_type="parallel"``, after Xia et al. 2019,
hexangular flexible coupling): with coupling hub radius R, offset (δx, δy), δ = |(δx, δy)|,
φ = atan(δx/δy) + θ and radial stiffness k_r,

    F_x(θ) = k_r Σ_{a ∈ {0, π/6, π/3}} (√(R² + δ² + 2Rδ f_a(φ + a)) − R) · sin(θ + 4a)

(F_y with cos; f_a = sin, cos, −sin), applied equal and opposite at the coupling element's two
nodes; for δ ≪ R it is ≈ k_r δ times products of sines, i.e. a static load plus a **2X** force
of amplitude ≈ k_r δ (measured here: 2X 2000 N, static 960 N for k_r δ = 2000 N).

Steady state: ROSS's time-domain fault run (``rotor.run_misalignment``, Newmark) is replaced by
ROSS's **harmonic-balance** solver (``ross.harmonic_balance.HarmonicBalance``), fed the same
misalignment force over one revolution (Fourier-expanded by ROSS) plus the unbalance as a 1X
harmonic force, ``n_harmonics = 4``, gravity on. The model is linear (linear bearings, no crack),
so harmonic balance *is* the exact periodic steady state (no transient to wait out); it takes
about 0.5 s per case instead of minutes. The static (DC) and 1X–4X displacements of the bearing
nodes are stored.

Cases per machine: healthy (unbalance only) at balance grades G1, G2.5 and G6.3; parallel
misalignment Δ = δ/c ∈ :data:`DELTAS` (c = the stated radial bearing clearance) at G2.5 with the
same unbalance phases as the healthy G2.5 case.

The speed-band set (``--band``, :func:`generate_band`, for the asset-baseline benchmark): per machine
the healthy G2.5 case at the rated speed, :data:`BAND_HEALTHY` healthy ones and :data:`BAND_PER_DELTA`
of each misaligned case at speeds uniform within ±:data:`BAND_SPREAD` of rated, each solved by ROSS at its
own speed with the rated speed's unbalance (a fixed mass eccentricity).
"""
from __future__ import annotations

import argparse
import math
import time
import warnings
from dataclasses import dataclass
from pathlib import Path

import numpy as np

DEFAULT_PATH = Path(__file__).resolve().parent / "ross_set.npz"
#: the speed-band set (:func:`generate_band`): healthy and misaligned recordings within ±BAND_SPREAD of rated speed
BAND_PATH = Path(__file__).resolve().parent / "ross_band_set.npz"
BAND_HEALTHY = 12
BAND_PER_DELTA = 2
BAND_SPREAD = 0.048
#: stated parallel offsets, as fractions of the radial bearing clearance
DELTAS = (0.1, 0.2, 0.3, 0.45, 0.6)
#: balance grades of the healthy cases, mm/s (ISO 21940-11); misaligned cases use the middle one
GRADES_MM_S = (1.0, 2.5, 6.3)
N_HARMONICS = 4
SEED = 1507


@dataclass(frozen=True)
class MachineSpec:
    """One machine of another design (dimensions in m, stiffness N/m, speed r/min).

    ``generator`` / ``exciter``: (length, outer diameter, number of elements) segments from the
    non-drive end; the last generator segment and the first exciter segment are the overhung
    coupling hubs. ``bearing_segments``: index of the segment whose *right* node carries bearing
    b (b = 1..4 in order; bearing 1 at the generator's free end uses the left node of segment 0).
    """

    name: str
    speed_rpm: float
    generator: tuple[tuple[float, float, int], ...]
    exciter: tuple[tuple[float, float, int], ...]
    coupling_stiffness_n_m: float
    coupling_hub_diameter_m: float
    coupling_mass_kg: float
    bearing_stiffness_n_m: tuple[float, float, float, float]
    clearance_um: float
    offset_angle_deg: float
    instrumented: tuple[int, ...]


MACHINES: tuple[MachineSpec, ...] = (
    MachineSpec(
        name="ross_2pole_3000", speed_rpm=3000.0,
        generator=((0.3, 0.25, 1), (0.5, 0.40, 1), (3.0, 1.0, 6), (0.5, 0.40, 1), (0.3, 0.25, 1), (0.3, 0.20, 1)),
        exciter=((0.25, 0.15, 1), (0.2, 0.15, 1), (1.2, 0.30, 3), (0.2, 0.15, 1), (0.2, 0.15, 1)),
        coupling_stiffness_n_m=2e7, coupling_hub_diameter_m=0.30, coupling_mass_kg=80.0,
        bearing_stiffness_n_m=(1.2e9, 1.2e9, 0.8e9, 0.8e9), clearance_um=190.0, offset_angle_deg=-90.0,
        instrumented=(1, 2, 3, 4)),
    MachineSpec(
        name="ross_4pole_1800", speed_rpm=1800.0,
        generator=((0.4, 0.35, 1), (0.7, 0.55, 1), (4.0, 1.6, 8), (0.7, 0.55, 1), (0.4, 0.35, 1), (0.35, 0.28, 1)),
        exciter=((0.3, 0.22, 1), (0.3, 0.22, 1), (1.5, 0.45, 3), (0.3, 0.22, 1), (0.3, 0.22, 1)),
        coupling_stiffness_n_m=5e7, coupling_hub_diameter_m=0.45, coupling_mass_kg=200.0,
        bearing_stiffness_n_m=(2.5e9, 2.5e9, 1.2e9, 1.2e9), clearance_um=260.0, offset_angle_deg=-60.0,
        instrumented=(1, 2, 3, 4)),
    MachineSpec(
        name="ross_small_3600", speed_rpm=3600.0,
        generator=((0.2, 0.16, 1), (0.35, 0.25, 1), (1.8, 0.65, 5), (0.35, 0.25, 1), (0.2, 0.16, 1), (0.2, 0.13, 1)),
        exciter=((0.15, 0.10, 1), (0.15, 0.10, 1), (0.8, 0.20, 3), (0.15, 0.10, 1), (0.15, 0.10, 1)),
        coupling_stiffness_n_m=8e6, coupling_hub_diameter_m=0.20, coupling_mass_kg=25.0,
        bearing_stiffness_n_m=(5e8, 5e8, 3e8, 3e8), clearance_um=120.0, offset_angle_deg=180.0,
        instrumented=(1, 2, 3)),
)


def _build(spec: MachineSpec):
    """The ROSS rotor of ``spec``, its bearing nodes (b1..b4) and the coupling element's number."""
    import ross as rs  # type: ignore[import-not-found]

    steel = rs.Material(name="steel_rotordiag", rho=7850.0, E=2.05e11, G_s=7.9e10)
    elems = []
    right_nodes: list[int] = []

    def add(segments):
        for length, d, n_el in segments:
            for _ in range(n_el):
                elems.append(rs.ShaftElement(L=length / n_el, idl=0.0, odl=d, material=steel,
                                             shear_effects=True, rotary_inertia=True, gyroscopic=True))
            right_nodes.append(len(elems))

    add(spec.generator)
    gen_right = list(right_nodes)
    n_coupling = len(elems)
    hub_ip = 0.5 * (spec.coupling_mass_kg / 2) * (spec.coupling_hub_diameter_m / 2) ** 2
    elems.append(rs.CouplingElement(m_l=spec.coupling_mass_kg / 2, m_r=spec.coupling_mass_kg / 2, Ip_l=hub_ip,
                                    Ip_r=hub_ip, kt_x=spec.coupling_stiffness_n_m, kt_y=spec.coupling_stiffness_n_m,
                                    kr_x=1e5, kr_y=1e5, kr_z=1e7, o_d=spec.coupling_hub_diameter_m, L=0.1))
    right_nodes.clear()
    add(spec.exciter)
    exc_right = list(right_nodes)
    for i, e in enumerate(elems):
        e.n = i
    # bearings: gen free end (node 0), gen journal before the hub (right node of the 2nd-last segment),
    # exciter journal after the hub (right node of its first segment), exciter free end (last node)
    nodes = (0, gen_right[-2], exc_right[0], exc_right[-1])
    bearings = [rs.BearingElement(n=n, kxx=k, kyy=1.6 * k, cxx=4e-4 * k, cyy=4e-4 * 1.6 * k)
                for n, k in zip(nodes, spec.bearing_stiffness_n_m)]
    gen_body_node = (gen_right[1] + gen_right[2]) // 2
    exc_body_node = (exc_right[1] + exc_right[2]) // 2
    rotor = rs.Rotor(elems, [], bearings)
    return rotor, nodes, n_coupling, gen_body_node, exc_body_node


def _mass_kg(rotor, first_node: int, last_node: int) -> float:
    return float(sum(e.m for e in rotor.shaft_elements if first_node <= e.n < last_node))


def solve_case(spec: MachineSpec, built, delta: float, grade_mm_s: float, phases_rad: tuple[float, float],
               speed_rpm: float | None = None) -> np.ndarray:
    """DC and 1X..4X displacement of the bearing nodes, µm: complex array (4 bearings, 2 [x, y], 1 + N_HARMONICS).

    Index 0 is the static position (real); index k the complex amplitude of order k, the motion
    being ``Re(X_k exp(i k Ω t))``. ``speed_rpm`` (default the machine's rated speed) is the running
    speed; the unbalance is the balance grade's at the rated speed (a fixed mass eccentricity).
    """
    from ross.faults.misalignment import MisalignmentFlex  # type: ignore[import-not-found]
    from ross.harmonic_balance import HarmonicBalance  # type: ignore[import-not-found]

    rotor, nodes, n_coupling, gen_node, exc_node = built
    omega = (spec.speed_rpm if speed_rpm is None else speed_rpm) * math.pi / 30.0
    omega_rated = spec.speed_rpm * math.pi / 30.0
    n_t = 512
    t = np.arange(n_t) / n_t * 2 * math.pi / omega
    f_ext = None
    if delta > 0:
        offset_m = delta * spec.clearance_um * 1e-6
        ang = math.radians(spec.offset_angle_deg)
        fault = MisalignmentFlex(rotor, n=n_coupling, mis_type="parallel", mis_distance_x=offset_m * math.cos(ang),
                                 mis_distance_y=offset_m * math.sin(ang), mis_angle=0.0,
                                 radial_stiffness=spec.coupling_stiffness_n_m, bending_stiffness=0.0)
        f_ext = fault.compute_reaction_force(omega * t)
    m_gen = _mass_kg(rotor, 0, n_coupling)
    m_exc = _mass_kg(rotor, n_coupling + 1, len(rotor.shaft_elements))
    e_m = grade_mm_s * 1e-3 / omega_rated                # ISO 21940: G = e·Ω at the rated speed
    forces = [
        {"node": gen_node, "magnitudes": [m_gen * e_m * omega ** 2], "phases": [phases_rad[0]], "harmonics": [1]},
        {"node": exc_node, "magnitudes": [m_exc * e_m * omega ** 2], "phases": [phases_rad[1]], "harmonics": [1]},
    ]
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        res = HarmonicBalance(rotor, n_harmonics=N_HARMONICS).run(forces=forces, speed=omega, t=t, gravity=True,
                                                                   F_ext=f_ext)
    out = np.zeros((4, 2, 1 + N_HARMONICS), dtype=complex)
    for b, node in enumerate(nodes):
        for j in range(2):
            dof = rotor.number_dof * node + j
            out[b, j, 0] = res.Qo[dof] / 2.0           # ROSS: y(t) = Qo/2 + Σ Re(dQ_k e^{ikΩt})
            out[b, j, 1:] = res.dQ[dof, :N_HARMONICS]
    return out * 1e6


def generate(path: Path = DEFAULT_PATH, seed: int = SEED) -> dict:
    """Build every machine, solve every case, write ``path`` (npz); returns the arrays written."""
    import ross  # type: ignore[import-not-found]

    rng = np.random.default_rng(seed)
    rows: dict[str, list] = {k: [] for k in _ROW_KEYS}
    for spec in MACHINES:
        t0 = time.perf_counter()
        built = _build(spec)
        phases = (float(rng.uniform(0, 2 * math.pi)), float(rng.uniform(0, 2 * math.pi)))
        cases = [(0.0, g, (float(rng.uniform(0, 2 * math.pi)), float(rng.uniform(0, 2 * math.pi))))
                 for g in GRADES_MM_S if g != GRADES_MM_S[1]]
        cases.append((0.0, GRADES_MM_S[1], phases))
        cases += [(d, GRADES_MM_S[1], phases) for d in DELTAS]
        for delta, grade, ph in cases:
            _add_case(rows, spec, built, delta, grade, ph, spec.speed_rpm)
        print(f"{spec.name}: {len(cases)} cases in {time.perf_counter() - t0:.1f} s")
    return _write_set(rows, path, seed, ross.__version__)


_ROW_KEYS = ("machine", "speed_rpm", "clearance_um", "delta", "grade_mm_s", "harmonics_um", "instrumented",
             "phases_rad")


def _add_case(rows: dict[str, list], spec: MachineSpec, built, delta: float, grade: float,
              phases: tuple[float, float], speed_rpm: float) -> None:
    """Solve one case with ROSS and append it to ``rows`` (the set's columns)."""
    rows["machine"].append(spec.name)
    rows["speed_rpm"].append(speed_rpm)
    rows["clearance_um"].append(spec.clearance_um)
    rows["delta"].append(delta)
    rows["grade_mm_s"].append(grade)
    rows["harmonics_um"].append(solve_case(spec, built, delta, grade, phases,
                                           None if speed_rpm == spec.speed_rpm else speed_rpm))
    rows["instrumented"].append([b in spec.instrumented for b in (1, 2, 3, 4)])
    rows["phases_rad"].append(phases)


def _write_set(rows: dict[str, list], path: Path, seed: int, ross_version: str) -> dict:
    arrays = {k: np.asarray(v) for k, v in rows.items()}
    arrays["ross_version"] = np.asarray(str(ross_version))
    arrays["seed"] = np.asarray(seed)
    path.parent.mkdir(parents=True, exist_ok=True)
    np.savez_compressed(path, **arrays)
    return arrays


def generate_band(path: Path = BAND_PATH, seed: int = SEED, n_healthy: int = BAND_HEALTHY,
                  n_per_delta: int = BAND_PER_DELTA, spread: float = BAND_SPREAD) -> dict:
    """The speed-band set (issue 17's baselines): per machine the healthy G2.5 case at the rated speed, then
    ``n_healthy`` healthy re-recordings and ``n_per_delta`` recordings of each misaligned case (Δ ∈
    :data:`DELTAS`) at speeds uniform within ±``spread`` of the rated speed (same unbalance as the
    baseline). Same layout as :func:`generate` (``speed_rpm`` per case), written to ``path``."""
    import ross  # type: ignore[import-not-found]

    rng = np.random.default_rng(seed + 1)
    rows: dict[str, list] = {k: [] for k in _ROW_KEYS}
    for spec in MACHINES:
        t0 = time.perf_counter()
        built = _build(spec)
        phases = (float(rng.uniform(0, 2 * math.pi)), float(rng.uniform(0, 2 * math.pi)))
        cases = [(0.0, spec.speed_rpm)]
        cases += [(0.0, spec.speed_rpm * (1 + float(rng.uniform(-spread, spread)))) for _ in range(n_healthy)]
        cases += [(d, spec.speed_rpm * (1 + float(rng.uniform(-spread, spread)))) for d in DELTAS
                  for _ in range(n_per_delta)]
        for delta, rpm in cases:
            _add_case(rows, spec, built, delta, GRADES_MM_S[1], phases, rpm)
        print(f"{spec.name}: {len(cases)} cases in {time.perf_counter() - t0:.1f} s")
    return _write_set(rows, path, seed, ross.__version__)


@dataclass(frozen=True)
class RossCase:
    """One recording of the ROSS set: probe waveforms in µm at 45° and 135° per instrumented bearing."""

    machine: str
    speed_rpm: float
    clearance_um: float
    delta: float
    grade_mm_s: float
    bearings: tuple[int, ...]
    sample_rate_hz: float
    waveforms_um: np.ndarray          # (2 * len(bearings), n) — bearing order, probes 45°, 135°
    keyphasor_times_s: np.ndarray | None = None   # times at which the shaft angle passes 0 (mod 2π)


PROBE_ANGLES_DEG = (45.0, 135.0)


def load_ross_set(path: Path = DEFAULT_PATH, *, sample_rate_hz: float = 2560.0, revs: float = 48.0,
                  snr_db: float = 40.0, seed: int = SEED, runout_1x_um: tuple[float, float] = (0.0, 0.0),
                  runout_2x_um: tuple[float, float] = (0.0, 0.0), runout_seed: int | None = None,
                  runout_per_machine: bool = False) -> list[RossCase]:
    """The cached ROSS set as probe waveforms (NumPy only; no ROSS needed).

    Each probe reads ``x cos α + y sin α`` (α from +x horizontal toward +y up, as
    ``rotordiag.core.conventions``), x/y from the stored DC + 1X..4X harmonics, sampled at
    ``sample_rate_hz`` for ``revs`` revolutions from a seeded random shaft angle, plus white
    noise at ``snr_db`` (of each channel's AC power). With ``runout_1x_um`` / ``runout_2x_um``
    ranges, each probe also reads a shaft-surface runout ``a1 cos(ψ − β1) + a2 cos(2ψ − β2)``,
    ψ = α − θ (as ``simulator.dataset.measurement``), amplitudes uniform in the range and phases
    uniform, drawn per bearing from a second generator (``runout_seed``, default ``seed + 10_000``) so the
    waveforms without runout stay what they were; the same ``runout_seed`` with another ``seed`` gives
    the same shaft runout with new noise and start angles (a re-recording of the same machine). With
    ``runout_per_machine`` every case of a machine gets that machine's one runout (drawn from
    ``(runout_seed, machine index)``): the same shaft in every recording of a set like the speed-band one.
    ``keyphasor_times_s`` gives the times at which θ passes 2πm.

    Raises
    ------
    FileNotFoundError
        If the cached set is missing (regenerate it with this module's command).
    """
    if not Path(path).exists():
        raise FileNotFoundError(f"{path}: ROSS validation set missing; regenerate it with "
                                "`.venv/bin/python benchmarks/ross_validation.py` (needs the [validation] extra)")
    z = np.load(path, allow_pickle=False)
    rng = np.random.default_rng(seed)
    rng_runout = np.random.default_rng(seed + 10_000 if runout_seed is None else runout_seed)
    with_runout = max(runout_1x_um) > 0 or max(runout_2x_um) > 0
    out = []
    for i in range(len(z["machine"])):
        rpm = float(z["speed_rpm"][i])
        omega = rpm * math.pi / 30.0
        n = int(round(revs * 60.0 / rpm * sample_rate_hz))
        theta = float(rng.uniform(0, 2 * math.pi)) + omega * np.arange(n) / sample_rate_hz
        h = z["harmonics_um"][i]                                   # (4, 2, 1 + N)
        k = np.arange(1, h.shape[-1])
        phasors = np.exp(1j * np.outer(k, theta))                  # (N, n)
        xy = h[..., :1].real + np.real(np.einsum("bjk,kn->bjn", h[..., 1:], phasors))  # (4, 2, n)
        bearings = tuple(b for b in (1, 2, 3, 4) if bool(z["instrumented"][i][b - 1]))
        if runout_per_machine:
            names = list(dict.fromkeys(str(m) for m in z["machine"]))
            rng_runout = np.random.default_rng([seed + 10_000 if runout_seed is None else runout_seed,
                                                names.index(str(z["machine"][i]))])
        chans = []
        for b in bearings:
            ro = (rng_runout.uniform(*runout_1x_um), rng_runout.uniform(0, 2 * math.pi),
                  rng_runout.uniform(*runout_2x_um), rng_runout.uniform(0, 2 * math.pi)) if with_runout else None
            for a in PROBE_ANGLES_DEG:
                r = math.radians(a)
                ch = xy[b - 1, 0] * math.cos(r) + xy[b - 1, 1] * math.sin(r)
                if ro is not None:
                    psi = r - theta
                    ch = ch + ro[0] * np.cos(psi - ro[1]) + ro[2] * np.cos(2 * psi - ro[3])
                chans.append(ch)
        w = np.asarray(chans)
        if math.isfinite(snr_db):
            sig = w.std(axis=1, keepdims=True)
            w = w + rng.standard_normal(w.shape) * sig * 10 ** (-snr_db / 20)
        out.append(RossCase(str(z["machine"][i]), rpm, float(z["clearance_um"][i]), float(z["delta"][i]),
                            float(z["grade_mm_s"][i]), bearings, sample_rate_hz, w,
                            keyphasor_times(theta, np.arange(n) / sample_rate_hz)))
    return out


def keyphasor_times(theta: np.ndarray, time_s: np.ndarray) -> np.ndarray:
    """Times (s) at which the shaft angle ``theta`` (increasing, rad, sampled at ``time_s``) passes 2πm."""
    t = time_s
    m = np.arange(math.ceil(theta[0] / (2 * math.pi)), math.floor(theta[-1] / (2 * math.pi)) + 1)
    return np.interp(2 * math.pi * m, theta, t)


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--out", type=Path, default=DEFAULT_PATH)
    ap.add_argument("--seed", type=int, default=SEED)
    ap.add_argument("--band", action="store_true", help="write the speed-band set (generate_band) instead, to "
                    "--out or benchmarks/ross_band_set.npz")
    args = ap.parse_args(argv)
    if args.band:
        out = BAND_PATH if args.out == DEFAULT_PATH else args.out
        arrays = generate_band(out, args.seed)
        print(f"wrote {out} ({out.stat().st_size / 1e3:.1f} kB, {len(arrays['machine'])} cases)")
        return 0
    arrays = generate(args.out, args.seed)
    h = arrays["harmonics_um"]
    for i in range(len(arrays["machine"])):
        amp = 2 * np.abs(h[i, :, :, 1:3])                            # pk-pk of 1X, 2X per bearing/axis
        print(f"  {arrays['machine'][i]:16s} Δ={arrays['delta'][i]:.2f} G{arrays['grade_mm_s'][i]:<4g} "
              f"1X pp b1..b4 x: {np.round(amp[:, 0, 0], 2).tolist()}  2X/1X b2,b3 x: "
              f"{np.round(amp[1:3, 0, 1] / np.maximum(amp[1:3, 0, 0], 1e-12), 2).tolist()}")
    print(f"wrote {args.out} ({args.out.stat().st_size / 1e3:.1f} kB)")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
