"""Shared builders for the shaft-train tests: linear K/C bearings and a small generator–exciter train."""
from __future__ import annotations

from rotordiag.simulator.bearings import LinearBearing
from rotordiag.simulator.train import Coupling, Disk, Rotor, Support, Train, Unbalance, uniform_elements


def KCBearing(kxx: float, kyy: float, kxy: float = 0.0, kyx: float = 0.0, cxx: float = 0.0, cyy: float = 0.0,
              cxy: float = 0.0, cyx: float = 0.0, clearance_m: float = 1e-3) -> LinearBearing:
    """A linear bearing f = −K·d − C·v with constant coefficients."""
    return LinearBearing(diameter_m=0.3, length_m=0.15, clearance_m=clearance_m,
                         stiffness_n_m=[[kxx, kxy], [kyx, kyy]], damping_n_s_m=[[cxx, cxy], [cyx, cyy]])


def iso(k: float, c: float = 0.0, clearance_m: float = 1e-3) -> LinearBearing:
    return KCBearing(k, k, cxx=c, cyy=c, clearance_m=clearance_m)


def two_rotor_train(bearing_gen=None, bearing_exc=None, *, coupling: Coupling | None = None, n_gen: int = 12,
                    n_exc: int = 8, asymmetry: float = 0.0, unbalance_kg_m: float = 0.0,
                    overhang_m: float = 0.4) -> Train:
    """A small generator (6 m, Ø 0.5 m body, 2 bearings) rigidly coupled to an exciter (3 m, Ø 0.2 m,
    2 bearings), each coupling-end bearing ``overhang_m`` inside the flange."""
    bg = bearing_gen or iso(2e9, 2e5)
    be = bearing_exc or iso(5e8, 5e4)
    # generator: journal 0.4 m, body 5.2 m (asymmetric), overhang to the flange
    elems = uniform_elements(0.4, 0.3, 2) + uniform_elements(5.2, 0.5, n_gen - 4, asymmetry) + \
        uniform_elements(overhang_m, 0.3, 2)
    gen = Rotor("generator", elems, disks=(Disk(len(elems) // 2, 500.0, 60.0, 30.0),),
                supports=(Support(1, bg, name="B1"), Support(len(elems) - 2, bg, name="B2")),
                unbalances=(Unbalance(len(elems) // 2, unbalance_kg_m, 0.0),) if unbalance_kg_m else ())
    e_el = uniform_elements(overhang_m, 0.15, 2) + uniform_elements(3.0 - overhang_m, 0.2, n_exc - 2)
    exc = Rotor("exciter", e_el, disks=(Disk(n_exc // 2 + 1, 300.0, 15.0, 8.0),),
                supports=(Support(2, be, name="B3"), Support(n_exc - 1, be, name="B4")))
    return Train((gen, exc), (coupling or Coupling("rigid"),))
