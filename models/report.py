"""A report to hand on (issue 46): the verdict of a recording with its status, reasons and evidence, an asset's
trend, and the start-up plots, as a PDF (matplotlib's ``PdfPages``) and a self-contained HTML page.

:func:`build_report` gathers the content (:class:`ReportContent`) from what the callers already have — a
``Verdict.to_dict()``, the reader's notes, an asset's history as plain dicts, and the figures of
:func:`rotordiag.features.plots.transient_figures` — and :func:`write_report` writes both files, each to a
temporary name first (a failure leaves no half-written report). The CLI (``rotordiag report``) reads the files
and, when asked for an asset, its history from the service's database.
"""
from __future__ import annotations

import base64
import datetime as dt
import html
import io
import os
import tempfile
import textwrap
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

from .headline import headline_dict

__all__ = ["ReportContent", "build_report", "report_bytes", "transient_summary", "write_report", "summary_lines"]


@dataclass
class ReportContent:
    """What a report holds.

    Attributes
    ----------
    title : str
    asset_id : str or None
    recordings : list of dict
        ``{"file", "role" ("steady" / "start-up"), "format", "notes"}``.
    verdict : dict or None
        ``Verdict.to_dict()`` of the steady recording (None: no verdict, ``verdict_note`` says why).
    history : list of dict
        The asset's stored diagnoses, oldest first: ``created_at``, ``severity``, ``misalignment``,
        ``misalignment_low``, ``misalignment_high``, ``speed_rpm``, ``status``.
    transient : dict or None
        The start-up's summary: kind, speed range, speed source, 1X/2X peaks, conventions, notes.
    figures : dict of name → matplotlib Figure
    notes : list of str
        What the report leaves out and why (e.g. a service report has no start-up plots: waveforms are not stored).
    units : {"um", "mil"}
        The lengths' units of the text (the verdict is given already in them: ``models.output_units``).
    """

    title: str
    asset_id: str | None = None
    recordings: list[dict] = field(default_factory=list)
    verdict: dict | None = None
    verdict_note: str | None = None
    history: list[dict] = field(default_factory=list)
    transient: dict | None = None
    figures: dict[str, Any] = field(default_factory=dict)
    generated_at: str = field(default_factory=lambda: dt.datetime.now(dt.UTC).strftime("%Y-%m-%d %H:%M UTC"))
    code_version: str = ""
    notes: list[str] = field(default_factory=list)
    units: str = "um"


def transient_summary(track: Any, units: str = "um") -> dict:
    """A start-up's summary (a ``features.transient.OrderTrack``): kind, speed source and range, steps tracked,
    the 1X and 2X resonance peaks (``amp_um_pp``), conventions (lengths in ``units``) and notes (plain data; the
    report and the web page show it)."""
    from rotordiag.features.transient import conventions

    return {"kind": track.kind, "speed_source": track.speed_source,
            "speed_range_rpm": [float(track.speed_rpm.min()), float(track.speed_rpm.max())],
            "n_steps": int(track.speed_rpm.size), "peaks": track.peaks(1) + track.peaks(2),
            "conventions": track.conventions if units == "um" else conventions(units), "notes": list(track.notes)}


def build_report(*, title: str, asset_id: str | None = None, recordings: list[dict] | None = None,
                 verdict: dict | None = None, verdict_note: str | None = None, history: list[dict] | None = None,
                 track: Any = None, figures: dict[str, Any] | None = None,
                 notes: list[str] | None = None, units: str = "um") -> ReportContent:
    """Assemble a :class:`ReportContent`; ``track`` (a ``features.transient.OrderTrack``) gives the start-up summary;
    ``units`` (``"um"`` / ``"mil"``) are those of the lengths in the text — ``verdict`` must be given in them
    (``models.output_units.verdict_in_units``), the figures drawn in them."""
    from rotordiag.core.units import um_to
    from rotordiag.core.version import code_version

    um_to(None, units)
    units = "mil" if units.strip().lower().startswith("mil") else "um"
    if verdict is not None and verdict.get("output_units", "um") != units:
        raise ValueError(f"the verdict's lengths are in {verdict.get('output_units', 'um')}, the report's in {units}: "
                         "convert it with models.output_units.verdict_in_units")
    transient = transient_summary(track, units) if track is not None else None
    if history:
        figures = dict(figures or {})
        figures = {"trend": _trend_figure(history, asset_id), **figures}
    return ReportContent(title=title, asset_id=asset_id, recordings=list(recordings or []), verdict=verdict,
                         verdict_note=verdict_note, history=list(history or []), transient=transient,
                         figures=dict(figures or {}), code_version=code_version(), notes=list(notes or []),
                         units=units)


def _fmt(v: Any, nd: int = 3) -> str:
    return "–" if v is None else f"{v:.{nd}f}" if isinstance(v, float) else str(v)


def summary_lines(c: ReportContent) -> list[tuple[str, str]]:
    """The report's text as (kind, line): kind ``h`` heading, ``t`` text, ``b`` bullet."""
    from rotordiag.core.units import um_to

    mil = c.units == "mil"
    unit = "mil" if mil else "µm"
    out: list[tuple[str, str]] = [("t", f"generated {c.generated_at}; rotordiag {c.code_version}; lengths in {unit}")]
    if c.asset_id:
        out.append(("t", f"asset: {c.asset_id}"))
    out.append(("h", "Recordings"))
    for r in c.recordings:
        out.append(("b", f"{r.get('role', '')}: {r.get('file')} ({r.get('format', '?')})"))
        for n in r.get("notes") or []:
            out.append(("b", f"    note: {n}"))
    for n in c.notes:
        out.append(("b", f"note: {n}"))
    out.append(("h", "Verdict"))
    v = c.verdict
    if v is None:
        out.append(("t", c.verdict_note or "no steady recording: no verdict"))
    else:
        head = v.get("headline") or headline_dict(v)
        out.append(("t", f"WHAT TO DO ({head['urgency'].replace('_', ' ')}): {head['text']}"))
        severity = v.get("severity") if head.get("show_severity", True) else "not given (the measurement is in doubt)"
        out.append(("t", f"status: {v.get('status')}    severity: {severity}"))
        lo, hi = (v.get("misalignment_interval") or [None, None])[:2]
        out.append(("t", f"misalignment Δ = δ/c: {_fmt(v.get('misalignment'))} (interval {_fmt(lo)} – {_fmt(hi)})"))
        offset = v.get("offset_mil" if mil else "offset_um")
        if offset is not None:
            a, b = v.get("offset_interval_mil" if mil else "offset_interval_um") or [None, None]
            nd = 2 if mil else 1
            out.append(("t", f"offset δ: {_fmt(offset, nd)} {unit} ({_fmt(a, nd)} – {_fmt(b, nd)} {unit})"))
        out.append(("t", f"speed: {_fmt(v.get('speed_rpm'), 1)} r/min; motion type: {v.get('motion_type') or '–'}; "
                         f"model {v.get('model_version') or '–'}"))
        if (v.get("answered_by") or {}).get("text"):
            out.append(("t", f"answered by: {v['answered_by']['text']}"))
        probs = v.get("probabilities") or {}
        out.append(("t", "probabilities: " + ", ".join(f"{k} {p:.2f}" for k, p in probs.items())))
        out.append(("h", "Reasons"))
        for r in v.get("reasons") or []:
            out.append(("b", f"{r.get('status')}: {r.get('message')}"))
        for w in v.get("warnings") or []:
            out.append(("b", f"warning: {w}"))
        if not (v.get("reasons") or v.get("warnings")):
            out.append(("t", "none given"))
        out.append(("h", "Evidence (model-independent)"))
        for e in v.get("evidence") or []:
            out.append(("b", f"{e.get('scope')} · {e.get('name')}: {e.get('value')} — {e.get('meaning')}"))
    if c.transient is not None:
        t = c.transient
        out.append(("h", "Start-up / coast-down"))
        lo, hi = t["speed_range_rpm"]
        out.append(("t", f"{t['kind']}, {lo:.0f}–{hi:.0f} r/min, {t['n_steps']} revolutions tracked, speed from the "
                         f"{t['speed_source']}"))
        for p in t["peaks"]:
            amp = um_to(p["amp_um_pp"], c.units)
            out.append(("b", f"{p['order']}X peak at b{p['bearing']}@{p['angle_deg']:g}: {amp:.{2 if mil else 1}f} "
                             f"{unit} pk-pk at {p['speed_rpm']:.0f} r/min"))
        if not t["peaks"]:
            out.append(("b", "no 1X/2X resonance peak inside the run"))
        for n in t["notes"]:
            out.append(("b", f"note: {n}"))
        out.append(("t", f"conventions: {t['conventions']}"))
    if c.history:
        n = len(c.history)
        out.append(("h", f"Trend ({n} stored diagnos{'is' if n == 1 else 'es'})"))
        for h in c.history[-12:]:
            out.append(("b", f"{h.get('created_at')}: {h.get('severity')} Δ {_fmt(h.get('misalignment'))} "
                             f"({_fmt(h.get('misalignment_low'))} – {_fmt(h.get('misalignment_high'))}) at "
                             f"{_fmt(h.get('speed_rpm'), 0)} r/min, {h.get('status') or '–'}"))
    return out


def _plt():
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    return plt


def _trend_figure(history: list[dict], asset_id: str | None) -> Any:
    plt = _plt()
    fig, ax = plt.subplots(figsize=(9, 4.5))
    xs = list(range(len(history)))
    mis = [h.get("misalignment") for h in history]
    lo = [h.get("misalignment_low") for h in history]
    hi = [h.get("misalignment_high") for h in history]
    for x, m, a, b in zip(xs, mis, lo, hi):
        if a is not None and b is not None:
            ax.plot([x, x], [a, b], color="0.6", lw=2)
        if m is not None:
            ax.plot(x, m, "o", color="C0")
        else:
            ax.plot(x, 0, "x", color="C3")
    ax.set_xticks(xs)
    ax.set_xticklabels([str(h.get("created_at", ""))[:16] for h in history], rotation=45, ha="right", fontsize=7)
    ax.set_ylabel("misalignment Δ = δ/c (bar: interval; ×: inconclusive)")
    ax.set_title(f"Trend of {asset_id or 'the asset'}")
    ax.grid(alpha=0.3)
    fig.subplots_adjust(bottom=0.3)
    return fig


def _text_pages(lines: list[tuple[str, str]], title: str) -> list[Any]:
    plt = _plt()
    wrapped: list[tuple[str, str]] = []
    for kind, text in lines:
        width = 100 if kind != "h" else 80
        for i, part in enumerate(textwrap.wrap(text, width) or [""]):
            wrapped.append((kind if i == 0 else ("c" if kind == "b" else kind), part))
    per_page = 52
    pages = []
    for start in range(0, len(wrapped), per_page):
        fig = plt.figure(figsize=(8.27, 11.69))  # A4
        fig.text(0.06, 0.965, title if start == 0 else f"{title} (continued)", fontsize=14, weight="bold")
        y = 0.935
        for kind, text in wrapped[start:start + per_page]:
            if kind == "h":
                y -= 0.006
                fig.text(0.06, y, text, fontsize=11, weight="bold")
            else:
                fig.text(0.08 if kind in ("b", "c") else 0.06, y,
                         ("• " if kind == "b" else "   " if kind == "c" else "") + text, fontsize=8.5)
            y -= 0.0172
        pages.append(fig)
    return pages


def _atomic(path: Path, write) -> None:
    path.parent.mkdir(parents=True, exist_ok=True)
    fd, tmp = tempfile.mkstemp(dir=path.parent, prefix=f".{path.name}.", suffix=path.suffix)
    os.close(fd)
    try:
        write(tmp)
        umask = os.umask(0)
        os.umask(umask)
        os.chmod(tmp, 0o666 & ~umask)  # mkstemp's 0600 → what a plain open() would give
        os.replace(tmp, path)
    finally:
        if os.path.exists(tmp):
            os.unlink(tmp)


def report_bytes(content: ReportContent, fmt: str = "pdf") -> bytes:
    """The report as bytes: ``fmt`` ``"pdf"`` (text pages, then one page per figure) or ``"html"`` (one
    self-contained page with the same text and the figures embedded as PNG)."""
    lines = summary_lines(content)
    if fmt == "html":
        return _html(content, lines).encode("utf-8")
    if fmt != "pdf":
        raise ValueError(f"report format {fmt!r}: give pdf or html")
    from matplotlib.backends.backend_pdf import PdfPages

    plt = _plt()
    text_pages = _text_pages(lines, content.title)
    buf = io.BytesIO()
    try:
        with PdfPages(buf, metadata={"Title": content.title, "Creator": f"rotordiag {content.code_version}"}) as pp:
            for f in text_pages:
                pp.savefig(f)
            for f in content.figures.values():
                pp.savefig(f)
    finally:
        for f in text_pages:
            plt.close(f)
    return buf.getvalue()


def write_report(content: ReportContent, pdf_path: str | Path, html_path: str | Path | None = None) -> list[Path]:
    """Write the PDF and, with ``html_path``, the HTML page (:func:`report_bytes`), each to a temporary name
    first. Returns the paths written."""
    pdf_path = Path(pdf_path)
    data = report_bytes(content, "pdf")
    _atomic(pdf_path, lambda tmp: Path(tmp).write_bytes(data))
    written = [pdf_path]
    if html_path is not None:
        html_path = Path(html_path)
        page = report_bytes(content, "html")
        _atomic(html_path, lambda tmp: Path(tmp).write_bytes(page))
        written.append(html_path)
    return written


def _html(c: ReportContent, lines: list[tuple[str, str]]) -> str:
    e = html.escape
    parts = ["<!doctype html><html lang='en'><head><meta charset='utf-8'>",
             f"<title>{e(c.title)}</title><style>body{{font-family:sans-serif;max-width:1100px;margin:auto;padding:1em}}"
             "img{max-width:100%;border:1px solid #ddd;margin:.5em 0}li{margin:.15em 0}</style></head><body>",
             f"<h1>{e(c.title)}</h1>"]
    in_list = False
    for kind, text in lines:
        if kind == "b":
            if not in_list:
                parts.append("<ul>")
                in_list = True
            parts.append(f"<li>{e(text.strip())}</li>")
            continue
        if in_list:
            parts.append("</ul>")
            in_list = False
        parts.append(f"<h2>{e(text)}</h2>" if kind == "h" else f"<p>{e(text)}</p>")
    if in_list:
        parts.append("</ul>")
    if c.figures:
        parts.append("<h2>Plots</h2>")
    for name, fig in c.figures.items():
        buf = io.BytesIO()
        fig.savefig(buf, format="png", dpi=90)
        data = base64.b64encode(buf.getvalue()).decode("ascii")
        parts.append(f"<figure><img alt='{e(name)}' src='data:image/png;base64,{data}'>"
                     f"<figcaption>{e(name.replace('_', ' '))}</figcaption></figure>")
    parts.append("</body></html>")
    return "\n".join(parts)
