"""An asset's report to hand on (``GET /assets/{id}/report``, ``rotordiag report --asset``) from the service's
store: the asset, its stored recordings (the trend), the latest verdict with its status, reasons and evidence,
and the trend plot, rendered by :mod:`rotordiag.models.report` (the same content and layout as the CLI's report).

:func:`asset_report_inputs` reads the store (plain dicts, so a diagnosis worker can render them);
:func:`render_asset_report` builds the PDF or HTML bytes (matplotlib: seconds, run in a worker or a thread).
"""
from __future__ import annotations

from typing import TYPE_CHECKING, Any

from .store import asset_history, history_dicts

if TYPE_CHECKING:
    from sqlalchemy.orm import Session

__all__ = ["NO_WAVEFORMS_NOTE", "REPORT_HISTORY_LIMIT", "asset_report_inputs", "render_asset_report"]

#: the latest stored diagnoses a report shows in its trend
REPORT_HISTORY_LIMIT = 200

#: why a report from the store has no start-up plots
NO_WAVEFORMS_NOTE = ("the service stores verdicts, not waveforms: the start-up / coast-down plots (Bode, polar, "
                     "cascade, full spectrum, centreline) are drawn from a recording — on the web page after an "
                     "upload, or with `rotordiag report --startup FILE`")


def asset_report_inputs(session: Session, asset_id: str, limit: int = REPORT_HISTORY_LIMIT,
                        units: str = "um") -> dict[str, Any] | None:
    """What a report of ``asset_id`` shows, from the store: ``{"asset_id", "history", "verdict", "recordings",
    "notes", "units"}`` (plain data), or None when the asset has no stored diagnosis.

    The verdict is the latest stored diagnosis that still holds its full verdict (retention keeps only the
    summary of old ones), with the asset's latest start-up compared with its baseline start-up
    (``service.startups``), in ``units`` (``"um"`` or ``"mil"``: its texts rendered again from their stored typed
    values, ``models.output_units``); the recordings are the stored diagnoses, oldest first (the trend)."""
    from rotordiag.models.output_units import revive_typed_texts, verdict_in_units

    from .startups import attach_startup

    rows = asset_history(session, asset_id, limit, None)
    if not rows:
        return None
    full = [r for r in rows if r.verdict]
    latest = full[-1] if full else None
    notes = [NO_WAVEFORMS_NOTE]
    recordings = []
    if latest is not None:
        v = latest.verdict
        recordings.append({"file": f"stored diagnosis #{latest.id} of {latest.created_at:%Y-%m-%d %H:%M} UTC"
                                   + (f", plant {latest.plant}" if latest.plant else ""),
                           "role": "latest", "format": f"model {latest.model_version}",
                           "notes": [str(n) for n in (v.get("input_notes") or [])]})
        if latest is not rows[-1]:
            notes.append(f"the latest diagnosis (#{rows[-1].id}) keeps only its summary; the verdict shown is "
                         f"#{latest.id}'s")
        verdict: dict[str, Any] | None = verdict_in_units(attach_startup(session, asset_id, revive_typed_texts(v)),
                                                          units)
    else:
        verdict = None
    recordings.append({"file": f"{len(rows)} stored diagnos{'is' if len(rows) == 1 else 'es'}, {rows[0].created_at:%Y-%m-%d %H:%M} to "
                               f"{rows[-1].created_at:%Y-%m-%d %H:%M} UTC (the trend below)",
                       "role": "trend", "format": "stored summaries", "notes": []})
    return {"asset_id": asset_id, "history": history_dicts(rows), "verdict": verdict, "recordings": recordings,
            "notes": notes, "units": units,
            "verdict_note": None if verdict is not None else
            "no stored diagnosis of this asset keeps its full verdict (retention keeps only summaries): no verdict"}


def render_asset_report(inputs: dict[str, Any], fmt: str) -> bytes:
    """The report of :func:`asset_report_inputs`'s ``inputs`` as PDF (``fmt="pdf"``) or HTML (``"html"``) bytes."""
    import matplotlib.pyplot as plt

    from rotordiag.models.report import build_report, report_bytes

    content = build_report(title=f"rotordiag report — {inputs['asset_id']}", asset_id=inputs["asset_id"],
                           recordings=inputs["recordings"], verdict=inputs["verdict"],
                           verdict_note=inputs["verdict_note"], history=inputs["history"], notes=inputs["notes"],
                           units=inputs.get("units", "um"))
    try:
        return report_bytes(content, fmt)
    finally:
        for f in content.figures.values():
            plt.close(f)
