"""The ROSS validation machines described as shaft lines of ours (issue 48, item 5's last target).

    .venv/bin/python benchmarks/ross_shaftline.py            # writes benchmarks/ross_shaftlines/<machine>.toml

Each machine of :data:`ross_validation.MACHINES` becomes a shaft-line file (docs/train.md, the layout of
``examples/shaftline_200mw.toml``) generated from its :class:`~ross_validation.MachineSpec`, so a retrain
(``rotordiag retrain --shaftline FILE``) sees the plant a plant engineer with ROSS's drawing would describe:

- generator segments from bearing 1 up to bearing 2 (all ``spec.generator`` segments but the last), the
  last one the overhang to the coupling flange; exciter overhang its first segment (flange to bearing 3),
  its segments the rest (bearing 3 to bearing 4); no body masses (ROSS's bodies are thick steel sections);
- bearings **linear** with ROSS's anisotropic coefficients: k_xx = k, k_yy = 1.6 k, c = 4e-4 s · k, no
  cross-coupling; bore = the journal's diameter, length half of it (ROSS's bearings have no length; the
  linear force does not use it), radial clearance ``spec.clearance_um``;
- a **flexible** coupling of radial stiffness ``coupling_stiffness_n_m`` and ROSS's rotational stiffness
  (``kr_x`` = 1e5 N·m/rad); each coupling half's mass as a disk at its coupling-end bearing (the generator's 2 % of the span inside it) (a shaft line
  places disks within the span, ROSS at the flange, one overhang further out);
- no two-pole asymmetry and no structural damping (ROSS's shafts have neither), the generator's residual
  unbalance of ISO 21940-11 G2.5 at the rated speed (ROSS's misaligned cases are at G2.5) and the rated
  speed ``rated_speed_rpm`` (the sweep's centre).

Differences that stay (the point of the check): ROSS's misalignment is its ``MisalignmentFlex`` reaction
force (a static load plus a 2X force ≈ k_r δ), ours the flexible coupling's kinematic offset; ROSS's
unbalance sits at the bodies' middle nodes of both rotors, ours at the generator's mid-span only; Young's
modulus 2.05e11 Pa in ROSS, 2.07e11 in our ``steel``; the coupling element's own 0.1 m length is left out.
"""
from __future__ import annotations

import argparse
import math
import sys
from pathlib import Path
from typing import Any

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parent))

from ross_validation import MACHINES, MachineSpec  # noqa: E402

from rotordiag.simulator.shaftline import ShaftLine, balance_grade_unbalance_kg_m  # noqa: E402

OUT_DIR = Path(__file__).resolve().parent / "ross_shaftlines"
#: ROSS's bearings: k_yy / k_xx and damping c / k (s), as ``ross_validation._build``
K_YY_OVER_K_XX = 1.6
C_OVER_K_S = 4e-4
#: ROSS's coupling element's rotational stiffness (N·m/rad), as ``ross_validation._build``
COUPLING_ROTATIONAL_STIFFNESS_N_M_RAD = 1e5
#: the generator hub's disk sits this fraction of the span inside bearing 2, so it stays within the span when a
#: retrain's dataset shortens the span by its 1 % tolerance (a shaft line's disk positions are not scaled)
HUB_INSET = 0.02
#: balance grade of ROSS's misaligned cases (mm/s)
GRADE_MM_S = 2.5


def _segments(segs: tuple[tuple[float, float, int], ...]) -> list[list[float]]:
    return [[float(length), float(d)] for length, d, _ in segs]


def shaftline_dict(spec: MachineSpec) -> dict[str, Any]:
    """The shaft-line mapping (``ShaftLine.from_dict`` layout, plus ``rated_speed_rpm``) of one ROSS machine."""
    gen_segments = _segments(spec.generator[:-1])
    exc_segments = _segments(spec.exciter[1:])
    gen_span = sum(s[0] for s in gen_segments)
    hub_kg = spec.coupling_mass_kg / 2
    hub_polar = 0.5 * hub_kg * (spec.coupling_hub_diameter_m / 2) ** 2      # as ross_validation._build's Ip
    journals = (gen_segments[0][1], gen_segments[-1][1], exc_segments[0][1], exc_segments[-1][1])
    options = [{"stiffness_n_m": [[k, 0.0], [0.0, K_YY_OVER_K_XX * k]],
                "damping_n_s_m": [[C_OVER_K_S * k, 0.0], [0.0, C_OVER_K_S * K_YY_OVER_K_XX * k]]}
               for k in spec.bearing_stiffness_n_m]
    d: dict[str, Any] = {
        "material": "steel",
        "generator_asymmetry": 0.0,
        "damping_ratio": 0.0,
        "generator": {"segments": gen_segments, "overhang": _segments(spec.generator[-1:]),
                      "disks": [[(1.0 - HUB_INSET) * gen_span, hub_kg, hub_polar, hub_polar / 2]]},
        "exciter": {"segments": exc_segments, "overhang": _segments(spec.exciter[:1]),
                    "disks": [[0.0, hub_kg, hub_polar, hub_polar / 2]]},
        "bearings": {"diameter_m": list(journals), "length_m": [0.5 * j for j in journals],
                     "clearance_m": spec.clearance_um * 1e-6, "type": ["linear"] * 4, "options": options},
        "coupling": {"type": "flexible", "stiffness_n_m": spec.coupling_stiffness_n_m,
                     "angular_stiffness_n_m_rad": COUPLING_ROTATIONAL_STIFFNESS_N_M_RAD},
    }
    line = ShaftLine.from_dict(d)
    d["generator_unbalance_kg_m"] = balance_grade_unbalance_kg_m(line.generator, GRADE_MM_S, spec.speed_rpm)
    d["rated_speed_rpm"] = [spec.speed_rpm]
    return d


def shaftline(spec: MachineSpec) -> ShaftLine:
    """The validated :class:`ShaftLine` of one ROSS machine (``rated_speed_rpm`` is not a shaft-line field)."""
    return ShaftLine.from_dict({k: v for k, v in shaftline_dict(spec).items() if k != "rated_speed_rpm"})


def write_all(out_dir: Path = OUT_DIR) -> list[Path]:
    """Write one ``<machine>.toml`` per machine of :data:`MACHINES`; returns the paths."""
    import tomli_w

    out_dir.mkdir(parents=True, exist_ok=True)
    paths = []
    for spec in MACHINES:
        p = out_dir / f"{spec.name}.toml"
        head = (f"# {spec.name}: the ROSS validation machine of benchmarks/ross_validation.py as a shaft line,\n"
                f"# generated by benchmarks/ross_shaftline.py from MACHINES (do not edit by hand).\n")
        p.write_text(head + tomli_w.dumps(shaftline_dict(spec)), encoding="utf-8")
        paths.append(p)
    return paths


def ross_masses_kg(spec: MachineSpec, rho_kg_m3: float = 7850.0) -> tuple[float, float]:
    """Generator and exciter mass of the ROSS machine from ``spec`` alone (solid steel segments + half the
    coupling each), the figure ``ross_validation._build``'s elements carry."""
    def steel(segs):
        return sum(math.pi * d * d / 4 * length * rho_kg_m3 for length, d, _ in segs)

    return steel(spec.generator) + spec.coupling_mass_kg / 2, steel(spec.exciter) + spec.coupling_mass_kg / 2


def main(argv: list[str] | None = None) -> int:
    from rotordiag.models.plant_retrain import describe_plant
    from rotordiag.simulator.shaftline import rotor_mass_kg
    from rotordiag.simulator.train.linear import critical_speeds
    from rotordiag.simulator.train.shaftline import train_from_shaftline

    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--out-dir", type=Path, default=OUT_DIR)
    args = ap.parse_args(argv)
    for p, spec in zip(write_all(args.out_dir), MACHINES, strict=True):
        desc = describe_plant(shaftline=p)
        line = ShaftLine.from_dict(desc.shaftline)
        m_gen, m_exc = ross_masses_kg(spec)
        crit = critical_speeds(train_from_shaftline(line), 4, 2.0 * spec.speed_rpm, n_grid=40)
        print(f"{p.name}: rated {desc.rated_speed_rpm} r/min; generator {rotor_mass_kg(line.generator):.0f} kg "
              f"(ROSS {m_gen:.0f}), exciter {rotor_mass_kg(line.exciter):.0f} kg (ROSS {m_exc:.0f}); "
              f"critical speeds below {2 * spec.speed_rpm:.0f} r/min: {np.round(crit).tolist()}")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
