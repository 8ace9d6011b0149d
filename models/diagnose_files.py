"""``rotordiag diagnose`` on files: options, one verdict per file, and the table of verdicts.

The recording is read by :func:`rotordiag.features.reader.read_recording` (the same reader
the service uses); the model is loaded once by the caller and reused for every file.
"""
from __future__ import annotations

import csv
import json
from collections.abc import Mapping, Sequence
from pathlib import Path
from typing import Any

from rotordiag.core.units import um_to
from rotordiag.features.reader import (
    FORMATS,
    ReadLimits,
    ReadOptions,
    ReadResult,
    parse_channel_map,
    parse_layout,
    read_recording,
)

__all__ = ["collect_files", "load_options", "diagnose_one", "diagnose_takes", "diagnose_read", "verdict_row", "verdict_json", "write_table", "CLI_LIMITS",
           "coupling_clearance_um", "slow_roll_from_file"]

#: a local file is the user's own: a dataset file may be large (its samples are read one at a time)
CLI_LIMITS = ReadLimits(max_file_bytes=2**31, max_hdf5_bytes=2**40, max_points=10_000_000, max_chunk_ratio=1e5,
                        hdf5_memory_bytes=4 * 2**30)
# (a dataset's unfinished rows are NaN and compress ~1000:1; only one row is ever decompressed)
_ENDINGS = tuple(e for endings in FORMATS.values() for e in endings)
_OPTION_KEYS = {f for f in ReadOptions.__dataclass_fields__}


def collect_files(items: Sequence[Path]) -> list[Path]:
    """Files given, with folders expanded to the recordings in them (sorted; sidecar ``.json`` files
    next to a recording of the same name are not recordings).

    Raises
    ------
    ValueError
        A path that does not exist, or a folder without recordings.
    """
    out: list[Path] = []
    for item in items:
        p = Path(item)
        if p.is_dir():
            found = sorted(f for f in p.iterdir() if f.is_file() and f.name.lower().endswith(_ENDINGS))
            stems = {f.stem for f in found if f.suffix.lower() != ".json"}
            found = [f for f in found if not (f.suffix.lower() == ".json" and f.stem in stems)]
            if not found:
                raise ValueError(f"{p}: the folder holds no recordings ({', '.join(_ENDINGS)})")
            out.extend(found)
        elif p.is_file():
            out.append(p)
        else:
            raise ValueError(f"{p}: no such file or folder")
    return out


def load_options(path: Path, sidecar: Path | None, given: Mapping[str, Any]) -> ReadOptions:
    """Reader options for ``path``: its sidecar JSON (``sidecar``, else ``path`` with ``.json`` when it
    exists), overridden by the options ``given`` (``None`` = not given).

    Raises
    ------
    ValueError
        An unreadable sidecar or unknown keys in it (the message lists the allowed ones).
    """
    from rotordiag.features.safe_io import loads_json_finite

    side: dict[str, Any] = {}
    side_path = sidecar if sidecar is not None else path.with_suffix(".json")
    if sidecar is not None and not side_path.is_file():
        raise ValueError(f"--sidecar: {side_path} does not exist")
    if side_path.is_file() and side_path != path:
        try:
            side = loads_json_finite(side_path.read_bytes())
        except (ValueError, UnicodeDecodeError) as exc:
            raise ValueError(f"sidecar {side_path}: not valid JSON ({exc})") from None
        if not isinstance(side, dict):
            raise ValueError(f"sidecar {side_path}: must be a JSON object")
        unknown = set(side) - _OPTION_KEYS
        if unknown:
            raise ValueError(f"sidecar {side_path}: unknown key(s) {sorted(unknown)}; allowed: {sorted(_OPTION_KEYS)}")
        if isinstance(side.get("clearance_um"), dict):
            side["clearance_um"] = {int(k): v for k, v in side["clearance_um"].items()}
    merged = {**side, **{k: v for k, v in given.items() if v is not None}}
    if isinstance(merged.get("channels"), str):
        merged["channels"] = parse_channel_map(merged["channels"])
    if merged.get("channels") is not None:
        try:
            if isinstance(merged["channels"], Mapping):
                parse_layout(list(merged["channels"].values()))
            else:
                parse_layout(merged["channels"])
        except ValueError as exc:
            raise ValueError(f"--channels / sidecar {exc}") from None
    kp = merged.get("keyphasor_channel")
    if isinstance(kp, str) and kp.strip().isdigit():
        merged["keyphasor_channel"] = int(kp)
    return ReadOptions(**merged)


def coupling_clearance_um(recording: Any) -> float | None:
    """The clearance that converts Δ to an offset: the recording's one value, or the mean of the
    coupling bearings' (2 and 3) when it gives one per bearing."""
    cl = getattr(recording, "clearance_um", None)
    if isinstance(cl, (int, float)):
        return float(cl)
    if isinstance(cl, Mapping):
        cands = [float(cl[b]) for b in (2, 3) if cl.get(b)]
        return sum(cands) / len(cands) if cands else None
    return None


def slow_roll_from_file(path: Path, options: ReadOptions) -> Any:
    """The runout vectors (``features.SlowRollVectors``) of a slow-roll recording file, read like any
    recording; ValueError (naming the file) says what to fix."""
    from rotordiag.features import slow_roll_vectors

    try:
        return slow_roll_vectors(read_recording(path, options=options, limits=CLI_LIMITS).recording)
    except ValueError as exc:
        raise ValueError(f"--slow-roll {path}: {exc}") from None


def diagnose_one(bundle: Any, path: Path, options: ReadOptions,
                 slow_roll: Any = None, plant_model: str | None = None) -> tuple[Any, ReadResult, dict[str, Any]]:
    """Read ``path`` and diagnose it with ``bundle`` (a loaded model, or a callable that loads it: the
    file is read first, so a bad file is reported before the model is loaded); ValueError says what to fix.
    ``slow_roll`` (``features.SlowRollVectors``, :func:`slow_roll_from_file`): runout vectors subtracted
    from the recording's 1X/2X (the reader's notes say so and what was left out). ``plant_model``: the machine's
    plant model (``models.pipeline.diagnose_recording``).

    Returns the verdict, the reader's result and the recording's ``features.signature`` (what an asset
    baseline compares, ``models.change.compare``)."""
    return diagnose_read(bundle, read_recording(path, options=options, limits=CLI_LIMITS), slow_roll, plant_model)


def diagnose_takes(bundle: Any, paths: Sequence[Path], sidecar: Path | None, given: Mapping[str, Any],
                   slow_roll: Any = None, plant_model: str | None = None) -> tuple[Any, ReadResult, dict[str, Any]]:
    """Read ``paths`` as the takes of one recording (each with :func:`load_options`: its own sidecar), merge them
    (``features.take_files.merge_takes``: each file one acquisition, its keyphasor that take's) and diagnose the
    merged recording as :func:`diagnose_one`. ValueError names the file."""
    from rotordiag.features.take_files import merge_takes

    if given.get("acquisitions") is not None:
        raise ValueError("--takes: each file is one acquisition; leave --acquisitions out")
    results = []
    for path in paths:
        try:
            results.append(read_recording(path, options=load_options(path, sidecar, given), limits=CLI_LIMITS))
        except ValueError as exc:
            raise ValueError(f"{path}: {exc}") from None
    return diagnose_read(bundle, merge_takes(results, [p.name for p in paths]), slow_roll, plant_model)


def diagnose_read(bundle: Any, res: ReadResult, slow_roll: Any = None,
                  plant_model: str | None = None) -> tuple[Any, ReadResult, dict[str, Any]]:
    """Diagnose a recording already read (:func:`diagnose_one` without the reading); a ``plant_model`` is the
    command line's (``--plant-model``, the verdict's ``answered_by``)."""
    from rotordiag.features import apply_slow_roll, signature

    from .pipeline import diagnose_recording

    recording = res.recording
    if slow_roll is not None:
        recording = apply_slow_roll(recording, slow_roll)[0]
        res.notes.append(f"slow-roll compensation: runout vectors measured at {slow_roll.speed_rpm:.0f} r/min "
                         f"({slow_roll.n_revs} revolutions) subtracted from the 1X/2X of every probe")
        res.notes.extend(slow_roll.notes)
    if callable(bundle):
        bundle = bundle()
    verdict, fr = diagnose_recording(bundle, recording, clearance_um=coupling_clearance_um(recording),
                                     plant_model=plant_model, declared_by="command line" if plant_model else None)
    return verdict, res, signature(fr)


def verdict_row(path: Path, verdict: Any, res: ReadResult, output_units: str = "um",
                baseline: dict[str, Any] | None = None) -> dict[str, Any]:
    """One row of the verdict table: the file, the headline, the verdict, lengths in ``output_units`` (µm or mil)."""
    from rotordiag.core.notes import Note

    from .headline import headline

    d = verdict.to_dict()
    um_to(None, output_units)  # checks the name
    u = "mil" if output_units.strip().lower().startswith("mil") else "um"
    head = headline(d, baseline=baseline, units=u)
    row: dict[str, Any] = {"file": str(path), "format": res.format, "action": head.action, "urgency": head.urgency,
                           "headline": head.text, "severity": d["severity"] if head.show_severity else None,
                           "misalignment": d["misalignment"],
                           "status": d.get("status"),
                           "misalignment_lo": (d.get("misalignment_interval") or [None, None])[0],
                           "misalignment_hi": (d.get("misalignment_interval") or [None, None])[1]}
    off, iv = d.get("offset_um"), d.get("offset_interval_um")
    row[f"offset_{u}"] = None if off is None else um_to(off, u)
    row[f"offset_lo_{u}"] = None if iv is None else um_to(iv[0], u)
    row[f"offset_hi_{u}"] = None if iv is None else um_to(iv[1], u)
    row.update({f"p_{k}": v for k, v in d["probabilities"].items()})
    row.update({"speed_rpm": d.get("speed_rpm"), "motion_type": d.get("motion_type"), "ood": d.get("ood"),
                "ood_score": d.get("ood_score"), "model_version": d.get("model_version"),
                "warnings": " | ".join(w.render(u) if isinstance(w, Note) else w for w in d.get("warnings") or []),
                "notes": " | ".join(res.notes),
                "truth_misalignment": (res.truth or {}).get("misalignment")})
    return row


def verdict_json(path: Path, verdict: Any, res: ReadResult, output_units: str = "um",
                 baseline: dict[str, Any] | None = None) -> dict[str, Any]:
    """The verdict as JSON (``Verdict.to_dict``) with the file, its format, the reader's notes, the
    dataset truth and the ``baseline`` comparison when there is one, its lengths in ``output_units``
    (:func:`rotordiag.models.output_units.verdict_in_units`, the same conversion and headline as the API's)."""
    from .output_units import verdict_in_units

    vd = verdict.to_dict()
    if baseline is not None:
        vd["baseline"] = baseline
    d: dict[str, Any] = {"file": str(path), "format": res.format,
                         **verdict_in_units(vd, output_units), "notes": res.notes}
    if res.truth:
        d["truth"] = res.truth
    return d


def write_table(out: Path, rows: list[dict[str, Any]]) -> None:
    """Write the rows as ``.csv`` (union of the columns, first-seen order) or ``.json`` (a list)."""
    suffix = out.suffix.lower()
    if suffix == ".json":
        out.write_text(json.dumps(rows, indent=2))
        return
    if suffix != ".csv":
        raise ValueError(f"--out {out}: write the table as .csv or .json")
    cols: list[str] = []
    for r in rows:
        cols.extend(k for k in r if k not in cols)
    with out.open("w", newline="") as fh:
        w = csv.DictWriter(fh, fieldnames=cols)
        w.writeheader()
        w.writerows(rows)
