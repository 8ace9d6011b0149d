"""Recordings written the way three common collector / DAQ exports write them (not a test module).

Each writer takes probe waveforms in µm (channels × points, in the layout ``LAYOUT``) and writes them
in another tool's text layout, in that tool's units, with the channels named as that tool names them:

- :func:`write_lvm`: National Instruments LabVIEW "Write To Measurement File", text (.lvm), as NI's
  "LabVIEW Measurement File (.lvm) Format" describes it: a file header (``LabVIEW Measurement``,
  ``Writer_Version``, ``Separator Tab``, ``X_Columns One``, ``Time_Pref Relative``, ``Date``, ``Time``,
  ``***End_of_Header***``), one segment header per channel column (``Channels``, ``Samples``,
  ``Y_Unit_Label``, ``X_Dimension``, ``X0``, ``Delta_X``, ``***End_of_Header***``), then the column
  names ``X_Value``, the channel names (``Untitled``, ``Untitled 1``, … as LabVIEW names unnamed
  signals) and ``Comment``, and one tab-separated row per sample. Probe output in volts.
- :func:`write_daq_csv`: a generic DAQ CSV (the name row / unit row pair of DAQ exports such as
  catman's or DEWESoft's CSV export): a name row with ``Time [ms]`` and the channel names, a unit row
  below it, comma separated; probe output in mV, plus a bearing-temperature column in °C that is no probe.
- :func:`write_collector_export`: a data collector's waveform export: a ``Key: value`` metadata block
  (site, machine, point, date, ``Sample Rate: 2560 Hz``, ``Units: mils``), a blank line, then
  ``Sample`` (the sample number) and one column per measurement point, semicolon separated; mils.

The layouts follow the published descriptions above; the files are written here, not copied from a tool.
"""
from __future__ import annotations

from pathlib import Path

import numpy as np

#: the probes of the shipped examples (features/examples), in file order
LAYOUT = [(b, a) for b in (1, 2, 3, 4) for a in (45.0, 135.0)]
#: measurement-point names a plant would give them
POINT_NAMES = ["GEN NDE X", "GEN NDE Y", "GEN DE X", "GEN DE Y", "EXC DE X", "EXC DE Y", "EXC NDE X", "EXC NDE Y"]
#: probe systems of the exports in volts (gap -10 V): the .lvm's stated as 7.87 V/mm, the DAQ CSV's as
#: 200 mV/mil (= 7.874 V/mm), the way each datasheet would say it
LVM_SENSITIVITY = "7.87 V/mm"
DAQ_SENSITIVITY = "200 mV/mil"
GAP_V = -10.0


def mapping(names: list[str]) -> str:
    """The channel mapping text (CLI --channels, API channel_map) of ``names`` in ``LAYOUT`` order."""
    return ";".join(f"{n}=b{b}@{a:g}" for n, (b, a) in zip(names, LAYOUT))


def _volts(data_um: np.ndarray, v_per_mm: float) -> np.ndarray:
    """Probe output (V) for a displacement toward the probe (µm): the inverse of ``core.units.volts_to_um``."""
    return GAP_V + data_um * 1e-3 * v_per_mm


def write_lvm(path: Path, data_um: np.ndarray, sample_rate_hz: float) -> list[str]:
    """LabVIEW .lvm text file, volts; returns the channel names it used."""
    n_ch, n = data_um.shape
    names = ["Untitled"] + [f"Untitled {k}" for k in range(1, n_ch)]
    tab = "\t"
    per = lambda v: tab.join([v] * n_ch)  # noqa: E731
    lines = ["LabVIEW Measurement\t", "Writer_Version\t2", "Reader_Version\t2", "Separator\tTab",
             "Decimal_Separator\t.", "Multi_Headings\tNo", "X_Columns\tOne", "Time_Pref\tRelative",
             "Operator\tfield engineer", "Date\t2026/11/28", "Time\t04:10:03.1234567", "***End_of_Header***", "\t",
             f"Channels\t{n_ch}\t", f"Samples\t{per(str(n))}\t", f"Date\t{per('2026/11/28')}\t",
             f"Time\t{per('04:10:03.1234567')}\t", f"Y_Unit_Label\t{per('Volts')}\t",
             f"X_Dimension\t{per('Time')}\t", f"X0\t{per('0.0000000000000000E+0')}\t",
             f"Delta_X\t{per(f'{1 / sample_rate_hz:.6E}')}\t", "***End_of_Header***\t",
             tab.join(["X_Value", *names, "Comment"])]
    volts = _volts(data_um, 7.87)
    t = np.arange(n) / sample_rate_hz
    for i in range(n):
        lines.append(tab.join([f"{t[i]:.6f}", *(f"{v:.6f}" for v in volts[:, i])]))
    path.write_text("\r\n".join(lines) + "\r\n")
    return names


def write_daq_csv(path: Path, data_um: np.ndarray, sample_rate_hz: float) -> list[str]:
    """Generic DAQ CSV: name row with ``Time [ms]``, unit row, mV; returns the probe column names."""
    n = data_um.shape[1]
    mv = _volts(data_um, 0.2 / 0.0254) * 1e3               # 200 mV/mil
    t_ms = np.arange(n) / sample_rate_hz * 1e3
    temp = 61.5 + 0.01 * np.sin(np.arange(n) / 500.0)
    lines = [",".join(["Time [ms]", *POINT_NAMES, "BRG 2 TEMP"]),
             ",".join(["[ms]", *(["[mV]"] * len(POINT_NAMES)), "[°C]"])]
    for i in range(n):
        lines.append(",".join([f"{t_ms[i]:.4f}", *(f"{v:.3f}" for v in mv[:, i]), f"{temp[i]:.2f}"]))
    path.write_text("\n".join(lines) + "\n", encoding="utf-8")
    return POINT_NAMES


def write_collector_export(path: Path, data_um: np.ndarray, sample_rate_hz: float) -> list[str]:
    """Data-collector export: metadata block, ``Sample`` column, semicolon separated, mils; returns the
    measurement-point names."""
    n = data_um.shape[1]
    names = [f"{p} {d}" for p in ("1", "2", "3", "4") for d in ("H45", "V135")]
    mils = data_um / 25.4
    lines = ["Waveform export", "Site: Riverside", "Machine: Unit 3 generator-exciter", "Point: coupling train",
             "Date: 2026-11-28 04:10:03", f"Sample Rate: {sample_rate_hz:g} Hz", f"Samples: {n}", "Units: mils",
             "Speed: 1800 RPM", "", ";".join(["Sample", *names])]
    for i in range(n):
        lines.append(";".join([str(i), *(f"{v:.5f}" for v in mils[:, i])]))
    path.write_text("\n".join(lines) + "\n", encoding="utf-8")
    return names
