"""The fixed feature schema: every name, its unit and its definition.

The vector always covers bearings 1–4 in the same order, whatever bearings a recording has:
features of a bearing that is not in the recording are NaN, and so are cross-bearing
features that need it. ``*_per_c`` features are NaN when the clearance is unknown.
"""
from __future__ import annotations

from dataclasses import dataclass

from ._config import ACROSS_ECC_FLOOR, ACROSS_MAJOR_FLOOR_UM, ACROSS_PAIRS, BEARINGS, PHASE_PAIRS, REPORTED_ORDERS

__all__ = ["FeatureSpec", "FEATURE_SPECS", "FEATURE_NAMES", "feature_names", "markdown_table"]


@dataclass(frozen=True)
class FeatureSpec:
    """One column of the feature vector."""

    name: str
    unit: str
    definition: str


def _bearing_specs(b: int) -> list[FeatureSpec]:
    p = f"b{b}_"
    out: list[FeatureSpec] = []
    add = lambda n, u, d: out.append(FeatureSpec(p + n, u, d))  # noqa: E731
    for d in ("x", "y"):
        dname = "horizontal (x)" if d == "x" else "vertical (y)"
        for k in REPORTED_ORDERS:
            add(f"{d}_{k}x_amp_um_pp", "µm pk-pk", f"{k}X amplitude of the {dname} displacement, peak-to-peak (2 × |C_{k}|)")
            add(f"{d}_{k}x_amp_pp_per_c", "1", f"{d}_{k}x_amp_um_pp / radial clearance")
            add(f"{d}_{k}x_phase_deg", "deg", f"{k}X phase lag of the {dname} displacement, [0, 360): "
                f"the {k}X component is A·cos({k}θ − φ), θ from the keyphasor (else the first sample)")
        add(f"{d}_2x_1x_ratio", "1", f"2X / 1X amplitude of the {dname} displacement")
        add(f"{d}_3x_1x_ratio", "1", f"3X / 1X amplitude of the {dname} displacement")
        add(f"{d}_direct_um_pp", "µm pk-pk", f"peak-to-peak of the unfiltered {dname} displacement")
        add(f"{d}_direct_pp_per_c", "1", f"{d}_direct_um_pp / radial clearance")
    for k in (1, 2):
        add(f"{k}x_fwd_um_pp", "µm pk-pk", f"forward {k}X component: 2|F_{k}|, the +{k}X line of the full spectrum of x + jy")
        add(f"{k}x_fwd_pp_per_c", "1", f"{k}x_fwd_um_pp / radial clearance")
        add(f"{k}x_rev_um_pp", "µm pk-pk", f"reverse {k}X component: 2|R_{k}|, the −{k}X line of the full spectrum of x + jy")
        add(f"{k}x_rev_pp_per_c", "1", f"{k}x_rev_um_pp / radial clearance")
        add(f"{k}x_rev_fwd_ratio", "1", f"|R_{k}| / |F_{k}|")
    for k in REPORTED_ORDERS:
        add(f"{k}x_major_um_pp", "µm pk-pk", f"major axis of the {k}X orbit ellipse, 2(|F_{k}| + |R_{k}|)")
        add(f"{k}x_major_pp_per_c", "1", f"{k}x_major_um_pp / radial clearance")
    add("2x_1x_major_ratio", "1", "2X / 1X orbit major axes (independent of the probe directions)")
    add("3x_1x_major_ratio", "1", "3X / 1X orbit major axes")
    add("1x_ellipticity", "1", "minor / major axis of the 1X orbit, ||F_1| − |R_1|| / (|F_1| + |R_1|) (1 circle, 0 line)")
    add("1x_whirl_index", "1", "(|F_1| − |R_1|) / (|F_1| + |R_1|): +1 circular forward, −1 circular backward whirl")
    add("1x_whirl_dir", "1", "direction of the 1X whirl: +1 forward (with the shaft), −1 backward, 0 straight line")
    add("orbit12_um_pp", "µm pk-pk", "peak-to-peak (largest diameter) of the filtered 1X + 2X orbit")
    add("orbit12_pp_per_c", "1", "orbit12_um_pp / radial clearance")
    add("orbit12_area_um2", "µm²", "signed area ½∮(x dy − y dx) of the 1X + 2X orbit; > 0 forward; loops count by winding")
    add("orbit12_area_per_c2", "1", "orbit12_area_um2 / clearance²")
    add("orbit12_ellipticity", "1", "sqrt(λmin/λmax) of the second moments of the 1X + 2X orbit")
    add("orbit12_turning_number", "1", "tangent turning of the 1X + 2X orbit / 2π: +1 simple forward, "
        "+2 inner loop, 0 figure-8, negative backward")
    add("orbit12_loop", "1", "inner-loop / figure-8 indicator: 1 when the turning number is not ±1, else 0")
    add("orbit12_concavity", "1", "fraction of the tangent turning against the orbit's direction "
        "(0 convex, grows as a loop forms, 0.5 figure-8)")
    for key, what in (("subsync", "sub-synchronous band 0.05–0.95X"), ("whirl_band", "oil-whirl band 0.38–0.49X"),
                      ("half_x", "1/2X line (band ±max(0.02X, 2 bins))"),
                      ("third_x", "1/3X line (band ±max(0.02X, 2 bins))")):
        add(f"{key}_rms_um", "µm rms", f"RMS displacement of the orbit (x and y together) in the {what}, "
            "from the non-synchronous residual")
        add(f"{key}_rms_per_c", "1", f"{key}_rms_um / radial clearance")
        add(f"{key}_frac", "1", f"mean-square in the {what} / total AC mean-square (x and y)")
    add("subsync_peak_order", "X", "order of the largest sub-synchronous line (0.05–0.95X); NaN when no bin stands "
        "10× above the band's median and holds 1e-6 of the AC mean-square")
    add("nonsync_frac", "1", "non-synchronous mean-square (everything but orders 1..K and the mean) / total AC mean-square")
    add("poincare_rms_um", "µm rms", "RMS scatter of the once-per-revolution (θ = 2πm) orbit points about their centroid")
    add("poincare_rms_per_c", "1", "poincare_rms_um / radial clearance")
    add("poincare_disp", "1", "poincare_rms_um / RMS AC orbit displacement (0 for period-1 motion)")
    add("centre_x_per_c", "1", "static (mean) horizontal journal position / radial clearance; NaN when the clearance "
        "is unknown or the mean lies > 1.5 c from the probes' zero (a raw gap, not a position)")
    add("centre_y_per_c", "1", "static (mean) vertical journal position / radial clearance (< 0: below the centre); "
        "NaN as centre_x_per_c")
    add("centre_ecc_per_c", "1", "static eccentricity ratio hypot(centre_x, centre_y) / clearance; NaN as centre_x_per_c")
    return out


def _build() -> tuple[FeatureSpec, ...]:
    specs = [
        FeatureSpec("speed_rpm", "r/min", "running speed (keyphasor, given, or estimated: see speed_source)"),
        FeatureSpec("motion_period", "rev", "period of the once-per-revolution motion n (period-n); 0 when "
                    "non-periodic; NaN when the record is shorter than 32 revolutions"),
        FeatureSpec("motion_quasi_periodic", "1", "1 when the motion is quasi-periodic, else 0 (NaN as motion_period)"),
        FeatureSpec("motion_chaotic", "1", "1 when the motion is chaotic, else 0 (NaN as motion_period)"),
    ]
    for b in BEARINGS:
        specs.extend(_bearing_specs(b))
    for k in (1, 2):
        for i, j in PHASE_PAIRS:
            for d in ("x", "y"):
                specs.append(FeatureSpec(
                    f"dphase_{k}x_b{i}_b{j}_{d}_deg", "deg",
                    f"{k}X phase lag of bearing {i} minus bearing {j}, {d} direction, wrapped to (−180, 180]; NaN "
                    "when either phase is in the noise, or the two bearings were recorded in separate acquisitions"))
    specs.extend(across_specs(ACROSS_PAIRS))
    return tuple(specs)


def across_specs(pairs: tuple[tuple[int, int], ...]) -> list[FeatureSpec]:
    """The columns that compare two bearings' static positions and orbit sizes (``features._across``)."""
    out = []
    for i, j in pairs:
        out.append(FeatureSpec(f"centre_ecc_b{i}_b{j}_ratio", "1", f"b{i}_centre_ecc_per_c / b{j}_centre_ecc_per_c (the "
                               f"denominator floored at {ACROSS_ECC_FLOOR:g}): the load bearing {i} carries against "
                               f"bearing {j}'s; NaN where either position is"))
        for d, dname in (("x", "horizontal"), ("y", "vertical")):
            out.append(FeatureSpec(f"dcentre_{d}_b{i}_b{j}_per_c", "1", f"b{i}_centre_{d}_per_c − b{j}_centre_{d}_per_c: "
                                   f"{dname} static position of journal {i} relative to journal {j}; NaN where either "
                                   "position is"))
        for k in (1, 2):
            out.append(FeatureSpec(f"{k}x_major_b{i}_b{j}_ratio", "1", f"b{i}_{k}x_major_um_pp / b{j}_{k}x_major_um_pp "
                                   f"(the denominator floored at {ACROSS_MAJOR_FLOOR_UM:g} µm); NaN where either "
                                   "bearing is not recorded"))
    return out


FEATURE_SPECS: tuple[FeatureSpec, ...] = _build()
FEATURE_NAMES: tuple[str, ...] = tuple(s.name for s in FEATURE_SPECS)
assert len(set(FEATURE_NAMES)) == len(FEATURE_NAMES), "duplicate feature names"


def feature_names() -> tuple[str, ...]:
    """The fixed, ordered feature names (the columns models train on)."""
    return FEATURE_NAMES


def markdown_table() -> str:
    """The schema as a Markdown table (bearing 1 shown; bearings 2–4 repeat it with ``b2_`` …)."""
    rows = ["| name | unit | definition |", "|---|---|---|"]
    for s in FEATURE_SPECS:
        if s.name[:2] in ("b2", "b3", "b4") and s.name[2] == "_":
            continue
        rows.append(f"| `{s.name}` | {s.unit} | {s.definition} |")
    return "\n".join(rows)
