"""Reference figures of ROSS 2.3.0 for the finite-element train ``reference_machine`` (docs/train.md).

The same machine is built here in ROSS (``ross.ShaftElement`` Timoshenko elements with shear, rotary
inertia and gyroscopics, ``ross.DiskElement``, linear ``ross.BearingElement``) and in
``rotordiag.simulator.train``; ROSS is a validation dependency only. ``python benchmarks/train_ross_reference.py``
writes ``benchmarks/train_ross_reference.json`` (needs ``pip install -e '.[validation]'``); the default
test suite compares our model against that file and a slow test recomputes it when ROSS is installed.

Figures: lateral damped natural frequencies (Campbell, 0–4000 r/min), undamped critical speeds
(bearing damping off; speeds where a lateral natural frequency equals the running speed, by Brent's
method on ROSS's own eigenvalues) and the 1X unbalance response (complex x and y at the four bearing
nodes, 500–4000 r/min).
"""
from __future__ import annotations

import json
import math
import os
import sys
from pathlib import Path

os.environ.setdefault("OMP_NUM_THREADS", "1")
os.environ.setdefault("OPENBLAS_NUM_THREADS", "1")

import numpy as np

OUT = Path(__file__).with_name("train_ross_reference.json")

#: (length m, outer diameter m, elements) per segment, from the coupling-free end
GENERATOR = ((0.3, 0.25, 2), (0.5, 0.40, 2), (3.0, 1.0, 15), (0.5, 0.40, 2), (0.3, 0.25, 2), (0.3, 0.20, 2))
EXCITER = ((0.25, 0.15, 2), (0.2, 0.15, 2), (1.2, 0.30, 6), (0.2, 0.15, 2), (0.2, 0.15, 2))
YOUNG_PA, SHEAR_PA, DENSITY = 2.05e11, 7.9e10, 7850.0
BEARING_K = (1.2e9, 1.2e9, 0.8e9, 0.8e9)  # kxx; kyy = 1.6 kxx; c = 4e-4 s × k
HUB_KG, HUB_D = 80.0, 0.30
CAMPBELL_RPM = (0.0, 1000.0, 2000.0, 3000.0, 4000.0)
RESPONSE_RPM = tuple(float(s) for s in np.arange(500.0, 4001.0, 250.0))
N_MODES = 8
N_CRITICAL = 6
#: first, last, count of the speed grid that brackets the critical speeds, r/min
CRITICAL_GRID_RPM = (50.0, 9000.0, 90)


def KC(kxx: float, kyy: float, cxx: float, cyy: float):
    """A linear bearing f = −K d − C v, diagonal."""
    from rotordiag.simulator.bearings import LinearBearing

    return LinearBearing(diameter_m=0.2, length_m=0.1, clearance_m=2e-4, stiffness_n_m=[[kxx, 0.0], [0.0, kyy]],
                         damping_n_s_m=[[cxx, 0.0], [0.0, cyy]])


def _layout():
    """Element list (length, diameter), the station of each segment end, for both rotors."""
    out = []
    for segs in (GENERATOR, EXCITER):
        el, ends = [], []
        for length, d, n in segs:
            el += [(length / n, d)] * n
            ends.append(len(el))
        out.append((el, ends))
    return out


def bearing_stations() -> tuple[tuple[int, int], ...]:
    """(rotor, station) of the four bearings: generator free end, generator journal before the overhang,
    exciter journal after its overhang, exciter free end."""
    (_, ge), (ee_el, ee) = _layout()
    return (0, 0), (0, ge[-2]), (1, ee[0]), (1, len(ee_el))


def unbalances() -> tuple[tuple[int, int, float, float], ...]:
    """(rotor, station, kg·m, rad): the generator body's middle and the exciter body."""
    (_, ge), (_, ee) = _layout()
    return (0, (ge[1] + ge[2]) // 2, 0.05, 0.0), (1, (ee[1] + ee[2]) // 2, 0.01, math.pi / 2)


def _hub():
    ip = 0.5 * HUB_KG * (HUB_D / 2) ** 2
    return HUB_KG, ip, 0.5 * ip


def reference_train(damped: bool = True, n_scale: int = 1):
    """The machine in ``rotordiag.simulator.train`` (rigid coupling; ``n_scale`` multiplies every segment's
    element count, for the mesh study)."""
    from rotordiag.simulator.train import Coupling, Disk, Material, Rotor, ShaftElement, Support, Train, Unbalance

    mat = Material(YOUNG_PA, SHEAR_PA, DENSITY)
    rotors = []
    brg = bearing_stations()
    ub = unbalances()
    for r, (el, _) in enumerate(_layout()):
        elements = tuple(ShaftElement(L / n_scale, d) for L, d in el for _ in range(n_scale))
        sup = tuple(Support(s * n_scale, KC(k, 1.6 * k, 4e-4 * k * damped, 6.4e-4 * k * damped), name=f"B{b + 1}")
                    for b, ((ri, s), k) in enumerate(zip(brg, BEARING_K, strict=True)) if ri == r)
        unb = tuple(Unbalance(s * n_scale, me, a) for ri, s, me, a in ub if ri == r)
        m, ip, idd = _hub()
        disks = (Disk(len(elements), m, ip, idd),) if r == 0 else ()
        rotors.append(Rotor(("generator", "exciter")[r], elements, disks, sup, unb, material=mat))
    return Train(tuple(rotors), (Coupling("rigid"),), gravity_m_s2=0.0)


def _ross_rotor(damped: bool):
    import ross as rs  # type: ignore[import-not-found]

    steel = rs.Material(name="steel_train_ref", rho=DENSITY, E=YOUNG_PA, G_s=SHEAR_PA)
    (gel, _), (eel, _) = _layout()
    elems = [rs.ShaftElement(L=L, idl=0.0, odl=d, material=steel, shear_effects=True, rotary_inertia=True,
                             gyroscopic=True) for L, d in gel + eel]
    for i, e in enumerate(elems):
        e.n = i
    off = (0, len(gel))
    m, ip, idd = _hub()
    disks = [rs.DiskElement(n=len(gel), m=m, Id=idd, Ip=ip)]
    bearings = [rs.BearingElement(n=off[r] + s, kxx=k, kyy=1.6 * k, cxx=4e-4 * k * damped, cyy=6.4e-4 * k * damped)
                for (r, s), k in zip(bearing_stations(), BEARING_K, strict=True)]
    return rs.Rotor(elems, disks, bearings), off


def _lateral_frequencies_hz(rotor, speed_rad_s: float, n: int) -> np.ndarray:
    """Lowest ``n`` lateral damped natural frequencies (axial and torsional modes left out by their shapes)."""
    modal = rotor.run_modal(speed_rad_s, num_modes=4 * n + 24, sparse=False)
    lam = np.asarray(modal.evalues)
    vec = np.asarray(modal.evectors)
    ndof = rotor.ndof
    nd = rotor.number_dof
    keep = []
    for k in range(len(lam)):
        if lam[k].imag <= 1e-3:
            continue
        v = vec[:ndof, k]
        lat = sum(np.sum(np.abs(v[j::nd]) ** 2) for j in (0, 1, 3, 4))
        other = sum(np.sum(np.abs(v[j::nd]) ** 2) for j in (2, 5))
        if lat > other:
            keep.append(lam[k].imag)
    return np.sort(np.array(keep))[:n] / (2 * math.pi)


def ross_figures() -> dict:
    """Compute every reference figure with ROSS."""
    import ross as rs  # type: ignore[import-not-found]
    from scipy.optimize import brentq

    rotor, off = _ross_rotor(True)
    campbell = [_lateral_frequencies_hz(rotor, s * math.pi / 30, N_MODES).tolist() for s in CAMPBELL_RPM]
    undamped, _ = _ross_rotor(False)
    grid = np.linspace(CRITICAL_GRID_RPM[0], CRITICAL_GRID_RPM[1], CRITICAL_GRID_RPM[2])
    n_track = 2 * N_CRITICAL + 4
    freqs = np.array([_lateral_frequencies_hz(undamped, s * math.pi / 30, n_track) for s in grid])
    crit = []
    for k in range(n_track):
        g = freqs[:, k] - grid / 60
        for j in range(len(grid) - 1):
            if g[j] > 0 >= g[j + 1]:
                crit.append(brentq(lambda s, k=k: _lateral_frequencies_hz(undamped, s * math.pi / 30, n_track)[k]
                                   - s / 60, grid[j], grid[j + 1], xtol=1e-4))
    crit = sorted(crit)[:N_CRITICAL]
    nodes = [off[r] + s for r, s in bearing_stations()]
    ub = unbalances()
    w = np.array(RESPONSE_RPM) * math.pi / 30
    resp = rotor.run_unbalance_response([off[r] + s for r, s, _, _ in ub], [me for *_, me, _ in ub],
                                        [a for *_, a in ub], frequency=w)
    fr = np.asarray(resp.forced_resp)
    nd = rotor.number_dof
    probes = [[[[float(fr[nd * n + ax, k].real), float(fr[nd * n + ax, k].imag)] for ax in (0, 1)] for n in nodes]
              for k in range(len(w))]
    return {"ross_version": rs.__version__, "campbell_rpm": list(CAMPBELL_RPM), "campbell_hz": campbell,
            "critical_speeds_rpm": crit, "response_rpm": list(RESPONSE_RPM), "probe_response_m": probes}


def main() -> int:
    fig = ross_figures()
    OUT.write_text(json.dumps(fig, indent=1) + "\n", encoding="utf-8")
    print(f"wrote {OUT} (ROSS {fig['ross_version']}): critical speeds {np.round(fig['critical_speeds_rpm'], 1)} r/min")
    return 0


if __name__ == "__main__":
    sys.exit(main())
