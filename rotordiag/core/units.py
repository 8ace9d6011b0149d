"""Displacement units accepted at the edges of the product, and their conversion to µm."""
from __future__ import annotations

#: accepted unit spellings → factor to µm (``"µm"`` is an alias of ``"um"``; 1 mil = 25.4 µm)
UNITS_TO_UM: dict[str, float] = {"um": 1.0, "µm": 1.0, "mm": 1e3, "m": 1e6, "mil": 25.4}
#: the public spelling of the allowed units (for error messages)
ALLOWED_UNITS: tuple[str, ...] = ("um", "mm", "m", "mil")
#: micrometres per mil (thousandth of an inch)
UM_PER_MIL: float = 25.4


def factor_to_um(units: str) -> float:
    """Multiplier that turns a value in ``units`` into µm.

    Raises
    ------
    ValueError
        For a unit outside :data:`ALLOWED_UNITS` (the message lists them).
    """
    key = units.strip() if isinstance(units, str) else units
    if key not in UNITS_TO_UM:
        raise ValueError(f"units {units!r} not understood: use one of {list(ALLOWED_UNITS)} (mil = 25.4 µm)")
    return UNITS_TO_UM[key]


#: input units a reader accepts: the displacement units plus ``"V"`` (proximity-probe output voltage,
#: converted with a probe sensitivity and a gap voltage, :func:`volts_to_um`)
INPUT_UNITS: tuple[str, ...] = (*ALLOWED_UNITS, "V")
#: units amplitudes can be reported in (µm or mils)
OUTPUT_UNITS: tuple[str, ...] = ("um", "mil")
#: the sensitivity of the common 8 mm proximity probe system (200 mV/mil)
TYPICAL_SENSITIVITY_V_PER_MM: float = 7.87


def volts_to_um(volts, sensitivity_v_per_mm: float, gap_voltage_v: float | None = None):
    """Probe output voltage → displacement toward the probe, µm.

    A proximity probe's output is negative and grows more negative as the gap opens
    (the shaft moves away from the probe): ``V = V_gap − S · (displacement toward the probe)``
    would read positive towards the probe with ``S`` negative; with the sensitivity given as
    a positive magnitude ``S`` (7.87 V/mm = 200 mV/mil) the displacement toward the probe is
    ``(V − V_gap) / S`` (the voltage rises toward 0 V as the gap closes).

    Parameters
    ----------
    volts : array_like
        Probe output, V.
    sensitivity_v_per_mm : float
        Positive magnitude of the probe system's scale factor, V/mm (e.g. 7.87).
    gap_voltage_v : float, optional
        The DC gap voltage at the reference (centred) position, V (e.g. -10.0). When omitted
        the mean of ``volts`` is removed: the waveform keeps its vibration, not its static position.

    Raises
    ------
    ValueError
        For a sensitivity that is not a finite positive number, or a non-finite gap voltage.
    """
    import math

    import numpy as np

    from .input_bounds import SENSITIVITY_RANGE_V_PER_MM, check_range

    s = check_range(sensitivity_v_per_mm, "probe sensitivity", SENSITIVITY_RANGE_V_PER_MM, "V/mm", "e.g. 7.87")
    v = np.asarray(volts, dtype=np.float64)
    if gap_voltage_v is None:
        ref = float(v.mean()) if v.size else 0.0
    else:
        ref = float(gap_voltage_v)
        if not math.isfinite(ref):
            raise ValueError(f"gap voltage must be a finite number of volts (e.g. -10.0), got {gap_voltage_v!r}")
    return (v - ref) / s * 1e3


def um_to(values, units: str):
    """Convert µm values to an output unit (``"um"`` or ``"mil"``); ``None``/NaN pass through.

    Raises
    ------
    ValueError
        For a unit outside :data:`OUTPUT_UNITS`.
    """
    key = units.strip().replace("µm", "um").lower() if isinstance(units, str) else units
    if key in ("mils",):
        key = "mil"
    if key not in OUTPUT_UNITS:
        raise ValueError(f"output units {units!r} not understood: use 'um' (micrometres) or 'mil' (thousandths of an inch)")
    if values is None:
        return None
    return values if key == "um" else values / UM_PER_MIL


def _length_key(key: str, units: str) -> tuple[str, float] | None:
    """``(new_key, divisor)`` for a key whose name carries a µm unit token (``offset_um``,
    ``b1_2x_major_um_pp``, ``b1_orbit12_area_um2``), else ``None``."""
    tokens = key.split("_")
    for i, tok in enumerate(tokens):
        if tok in ("um", "um2"):
            power = 2 if tok == "um2" else 1
            tokens[i] = units + ("2" if power == 2 else "")
            return "_".join(tokens), (UM_PER_MIL if units == "mil" else 1.0) ** power
    return None


def lengths_in(obj, units: str):
    """A copy of a JSON-like verdict with every µm-named length expressed in ``units``.

    Keys whose name carries the unit (``offset_um`` → ``offset_mil``, ``b2_1x_major_um_pp`` →
    ``b2_1x_major_mil_pp``, ``…_area_um2`` → ``…_area_mil2``) are renamed and their numbers
    converted — also inside lists and inside dicts whose own keys carry no unit (e.g.
    ``amplitudes_um_pp: {"b2": 3.1}``). Everything else, NaN and ``None`` pass unchanged;
    ``units="um"`` returns ``obj`` itself.

    Parameters
    ----------
    obj : dict, list or scalar
    units : {"um", "mil"}

    Raises
    ------
    ValueError
        For units outside :data:`OUTPUT_UNITS`.
    """
    um_to(None, units)  # checks the name
    key_units = "mil" if units.strip().lower().startswith("mil") else "um"
    if key_units == "um":
        return obj

    def convert(value, factor):
        if isinstance(value, dict):
            out = {}
            for k, v in value.items():
                renamed = _length_key(k, key_units) if isinstance(k, str) else None
                if renamed is not None:
                    out[renamed[0]] = convert(v, renamed[1])
                else:
                    out[k] = convert(v, factor)
            return out
        if isinstance(value, list):
            return [convert(v, factor) for v in value]
        if factor is not None and isinstance(value, (int, float)) and not isinstance(value, bool):
            return value / factor
        return value

    return convert(obj, None)
