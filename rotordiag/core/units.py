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


#: input units a reader accepts: the displacement units plus ``"V"`` and ``"mV"`` (proximity-probe output
#: voltage, converted with a probe sensitivity and a gap voltage, :func:`volts_to_um`)
INPUT_UNITS: tuple[str, ...] = (*ALLOWED_UNITS, "V", "mV")
#: volts per unit of the voltage units
VOLTS_PER: dict[str, float] = {"V": 1.0, "mV": 1e-3}
#: spellings of the input units seen in file headers and unit rows (lower case, brackets stripped) → INPUT_UNITS
UNIT_SPELLINGS: dict[str, str] = {
    "um": "um", "µm": "um", "μm": "um", "micron": "um", "microns": "um", "micrometer": "um", "micrometre": "um",
    "micrometers": "um", "micrometres": "um", "mm": "mm", "m": "m", "mil": "mil", "mils": "mil",
    "v": "V", "volt": "V", "volts": "V", "mv": "mV", "millivolt": "mV", "millivolts": "mV"}


def input_unit(text: str) -> str | None:
    """The input unit a header or unit-row spelling names (``"[mV]"`` → ``"mV"``, ``"Volts"`` → ``"V"``,
    ``"µm"`` → ``"um"``), or ``None`` for anything else."""
    key = str(text).strip().strip("[]()").strip()
    if key in ("mV", "V"):
        return key
    return UNIT_SPELLINGS.get(key.lower())


#: the distance units a probe sensitivity may be stated per, in mm
_MM_PER = {"mm": 1.0, "um": 1e-3, "µm": 1e-3, "μm": 1e-3, "mil": UM_PER_MIL * 1e-3, "m": 1e3}

def sensitivity_v_per_mm(value: float | str) -> float:
    """A probe sensitivity as the datasheet states it → V/mm.

    ``7.87`` (a bare number: V/mm), ``"7.87 V/mm"``, ``"200 mV/mil"``, ``"7.87 mV/um"`` (= mV/µm),
    ``"0.2 V/mil"`` all give 7.87 V/mm (200 mV/mil = 0.2 V / 0.0254 mm = 7.874 V/mm).

    Raises
    ------
    ValueError
        For text that is not ``NUMBER [m]V/(mm|um|µm|mil|m)`` or a value that is not finite and positive.
    """
    import math
    import re

    if isinstance(value, str):
        m = re.fullmatch(r"\s*([-+]?\d+(?:\.\d*)?(?:[eE][-+]?\d+)?|[-+]?\.\d+)\s*"
                         r"(?:(mV|V)\s*/\s*(mm|um|µm|μm|mils?|m))?\s*", value)
        if m is None:
            raise ValueError(f"probe sensitivity {value!r}: give a number and its units, e.g. '7.87 V/mm', "
                             "'200 mV/mil' or '7.87 mV/um' (a bare number is V/mm)")
        number = float(m.group(1))
        if m.group(2):
            per = m.group(3).rstrip("s") if m.group(3).startswith("mil") else m.group(3)
            number = number * VOLTS_PER[m.group(2)] / _MM_PER[per]
    else:
        try:
            number = float(value)
        except (TypeError, ValueError):
            raise ValueError(f"probe sensitivity {value!r} is not a number of V/mm (e.g. 7.87)") from None
    if not (math.isfinite(number) and number > 0):
        raise ValueError(f"probe sensitivity must be a positive number (e.g. 7.87 V/mm = 200 mV/mil), got {value!r}")
    return number
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
