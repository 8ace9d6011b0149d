"""Setpoint alarms and their delivery by webhook (issue 45, item 3).

Per asset, alert and danger setpoints on the largest over the bearings and probes of the overall
(direct) pk-pk amplitude, the 1X and the 2X amplitude (µm pk-pk), and on the misalignment estimate Δ.
Each stored diagnosis is compared with them in the transaction that stores it; a change of level
(normal → alert → danger and back) is stored as an event (``raised`` or ``cleared``), as is a change of
the baseline-change alarm (``service.baseline``). Events are acknowledged by a person
(``POST /assets/{id}/events/{event_id}/ack``).

Each event is queued, in the same transaction, for every webhook that covers its asset
(``webhook_deliveries``); a background thread (:class:`WebhookSender`) POSTs it, signed with the
webhook's secret (header :data:`SIGNATURE_HEADER`: ``sha256=`` and the hex HMAC-SHA256 of the body),
retrying with a doubling wait. One webhook gets its events in order: a delivery waits while an earlier one to
the same webhook is pending or being retried (a ``cleared`` never overtakes its ``raised``); a delivery that
has used up its tries is marked ``failed`` and the next goes. A delivery is claimed with a conditional update before it is sent, so two
replicas never send one twice. Nothing of the delivery runs in the request that stores the diagnosis.

No standard zone table (ISO 20816 and the like) is shipped: setpoints are the user's numbers.
"""
from __future__ import annotations

import datetime as dt
import hashlib
import hmac
import json
import logging
import queue
import threading
import urllib.error
import urllib.request
from typing import TYPE_CHECKING, Any

from sqlalchemy import exists, func, select, update
from sqlalchemy.orm import aliased

from rotordiag.core.timefmt import iso_utc

from .core.db import AlarmEvent, AssetSettings, Webhook, WebhookDelivery, utcnow

if TYPE_CHECKING:
    from sqlalchemy.orm import Session, sessionmaker

log = logging.getLogger("rotordiag.service.alarms")

#: setpoint quantities: name → (what it is, unit)
QUANTITIES: dict[str, tuple[str, str]] = {
    "overall_um_pp": ("overall (direct) amplitude, largest probe", "µm pk-pk"),
    "x1_um_pp": ("1X amplitude, largest probe", "µm pk-pk"),
    "x2_um_pp": ("2X amplitude, largest probe", "µm pk-pk"),
    "misalignment": ("misalignment estimate Δ = δ/c", "1"),
}
#: the baseline-change alarm's quantity name in events
CHANGE = "change"
LEVELS = ("normal", "alert", "danger")
#: header carrying the signature of a webhook POST: ``sha256=<hex HMAC-SHA256 of the body, key = secret>``
SIGNATURE_HEADER = "X-Rotordiag-Signature"
#: header carrying the delivery id (the same on every retry of one delivery: receivers may drop repeats)
DELIVERY_HEADER = "X-Rotordiag-Delivery"
#: a claimed delivery not finished within this long may be claimed again (its sender died), s
CLAIM_S = 120.0


def check_setpoints(setpoints: dict[str, Any]) -> dict[str, dict[str, float]]:
    """The setpoints in stored form; ``ValueError`` naming what is wrong (unknown quantity or level, a value
    that is not a finite non-negative number, danger not above alert)."""
    out: dict[str, dict[str, float]] = {}
    for q, levels in setpoints.items():
        if q not in QUANTITIES:
            raise ValueError(f"unknown quantity {q!r}; known: {', '.join(QUANTITIES)}")
        if not isinstance(levels, dict) or not levels:
            raise ValueError(f"{q}: give {{\"alert\": number, \"danger\": number}} (either or both)")
        row: dict[str, float] = {}
        for lv, v in levels.items():
            if lv not in ("alert", "danger"):
                raise ValueError(f"{q}: unknown level {lv!r}; use alert and danger")
            if isinstance(v, bool) or not isinstance(v, int | float) or not (0 <= float(v) < 1e9):
                raise ValueError(f"{q}.{lv}: must be a non-negative number ({QUANTITIES[q][1]})")
            row[lv] = float(v)
        if "alert" in row and "danger" in row and row["danger"] <= row["alert"]:
            raise ValueError(f"{q}: danger ({row['danger']:g}) must be above alert ({row['alert']:g})")
        out[q] = row
    return out


def verdict_quantities(verdict: dict[str, Any]) -> dict[str, float]:
    """The setpoint quantities of a verdict: the largest over its bearings' probes of the direct, 1X and 2X
    amplitudes (µm pk-pk) and Δ; a quantity the verdict does not give is left out."""
    keys = {"overall_um_pp": "_direct_um_pp", "x1_um_pp": "_1x_amp_um_pp", "x2_um_pp": "_2x_amp_um_pp"}
    out: dict[str, float] = {}
    for b in verdict.get("bearings") or []:
        feats = b.get("features") or {}
        n = b.get("bearing")
        for q, tail in keys.items():
            for probe in ("x", "y"):
                v = feats.get(f"b{n}_{probe}{tail}")
                if isinstance(v, int | float) and v == v and abs(v) != float("inf"):
                    out[q] = max(out.get(q, 0.0), float(v))
    m = verdict.get("misalignment")
    if isinstance(m, int | float) and m == m:
        out["misalignment"] = float(m)
    return out


#: hysteresis: a raised level clears only when the value falls this fraction below its setpoint, so a value
#: wandering around a setpoint (noise, load) does not raise and clear an alarm on every recording
CLEAR_BELOW_FRAC = 0.05


def level_of(value: float, levels: dict[str, float], held: str = "normal") -> tuple[str, float | None]:
    """``(level, setpoint)`` of ``value``: at or above danger, at or above alert, or normal — where a level
    ``held`` (the asset's present one) is kept down to :data:`CLEAR_BELOW_FRAC` below its setpoint."""
    rank = LEVELS.index(held) if held in LEVELS else 0
    for lv in ("danger", "alert"):
        if lv not in levels:
            continue
        sp = levels[lv]
        if value >= sp or (rank >= LEVELS.index(lv) and value >= sp * (1.0 - CLEAR_BELOW_FRAC)):
            return lv, sp
    return "normal", None


def get_setpoints(session: Session, asset_id: str) -> dict[str, dict[str, float]]:
    row = session.get(AssetSettings, asset_id)
    return dict(row.setpoints or {}) if row is not None else {}


def put_setpoints(session: Session, asset_id: str, setpoints: dict[str, dict[str, float]]) -> None:
    """Replace the asset's setpoints (``{}`` removes them); call inside a transaction."""
    row = session.get(AssetSettings, asset_id)
    if row is None:
        session.add(AssetSettings(asset_id=asset_id, thresholds={}, setpoints=setpoints or None))
    else:
        row.setpoints = setpoints or None


def current_levels(session: Session, asset_id: str) -> dict[str, str]:
    """The level each quantity of the asset is at (that of its latest event; normal without one)."""
    last = (select(AlarmEvent.quantity, func.max(AlarmEvent.id).label("id"))
            .where(AlarmEvent.asset_id == asset_id).group_by(AlarmEvent.quantity).subquery())
    q = select(AlarmEvent.quantity, AlarmEvent.level).join(last, AlarmEvent.id == last.c.id)
    return {quantity: level for quantity, level in session.execute(q)}


def evaluate(session: Session, settings: Any, asset_id: str, diagnosis_id: int, verdict: dict[str, Any],
             change_alarm: bool | None) -> list[AlarmEvent]:
    """Compare a just-stored diagnosis with the asset's setpoints and its baseline-change state; store an event
    for each quantity whose level changed and queue it for the asset's webhooks. Runs in the storing
    transaction; returns the new events."""
    setpoints = get_setpoints(session, asset_id)
    have = current_levels(session, asset_id)
    values = verdict_quantities(verdict)
    new: list[tuple[str, str, float | None, float | None, str]] = []
    for q, levels in setpoints.items():
        if q not in values:
            continue
        lv, sp = level_of(values[q], levels, have.get(q, "normal"))
        if lv != have.get(q, "normal"):
            what, unit = QUANTITIES[q]
            unit_text = "" if unit == "1" else f" {unit}"
            text = (f"{asset_id}: {what} {values[q]:.4g}{unit_text} at the {lv} level (setpoint {sp:g}{unit_text})"
                    if sp is not None else f"{asset_id}: {what} {values[q]:.4g}{unit_text}, back below its setpoints "
                    f"(by more than {100 * CLEAR_BELOW_FRAC:.0f} %)")
            new.append((q, lv, values[q], sp, text))
    if change_alarm is not None:
        lv = "alert" if change_alarm else "normal"
        if lv != have.get(CHANGE, "normal"):
            new.append((CHANGE, lv, None, None, f"{asset_id}: changed since its baseline" if change_alarm
                        else f"{asset_id}: no longer changed since its baseline"))
    events = []
    for q, lv, value, sp, text in new:
        ev = AlarmEvent(asset_id=asset_id, quantity=q, level=lv, event="cleared" if lv == "normal" else "raised",
                        value=value, setpoint=sp, diagnosis_id=diagnosis_id, message=text)
        session.add(ev)
        events.append(ev)
    if events:
        session.flush()
        hooks = list(session.scalars(select(Webhook).where(
            (Webhook.asset_id.is_(None)) | (Webhook.asset_id == asset_id))))
        for ev in events:
            for hook in hooks:
                enqueue(session, settings, hook.id, ev.id, event_payload(ev))
    return events


def event_dict(ev: AlarmEvent) -> dict[str, Any]:
    """The API (and webhook) form of an event."""
    return {"id": ev.id, "asset_id": ev.asset_id, "time": iso_utc(ev.created_at), "quantity": ev.quantity,
            "unit": QUANTITIES[ev.quantity][1] if ev.quantity in QUANTITIES else None,
            "level": ev.level, "event": ev.event, "value": ev.value, "setpoint": ev.setpoint,
            "diagnosis_id": ev.diagnosis_id, "message": ev.message, "acked_at": iso_utc(ev.acked_at),
            "ack_note": ev.ack_note}


def event_payload(ev: AlarmEvent, *, test: bool = False) -> dict[str, Any]:
    """The JSON body a webhook receives for ``ev``."""
    return {"type": "rotordiag.alarm", "test": test, "event": event_dict(ev)}


def enqueue(session: Session, settings: Any, webhook_id: int, event_id: int | None,
            payload: dict[str, Any]) -> WebhookDelivery:
    """Store a delivery: ``pending``, or ``dropped`` when ``webhook_max_pending`` deliveries already wait."""
    waiting = session.scalar(select(func.count()).select_from(WebhookDelivery)
                             .where(WebhookDelivery.status.in_(("pending", "sending")))) or 0
    full = waiting >= int(settings.webhook_max_pending)
    row = WebhookDelivery(webhook_id=webhook_id, event_id=event_id, payload=payload,
                          status="dropped" if full else "pending", attempts=0, next_attempt_at=utcnow(),
                          last_error=(f"not sent: {waiting} deliveries were already waiting (ROTORDIAG_WEBHOOK_"
                                      "MAX_PENDING)") if full else None)
    session.add(row)
    session.flush()
    return row


def sign(secret: str, body: bytes) -> str:
    """The value of :data:`SIGNATURE_HEADER` for ``body``."""
    return "sha256=" + hmac.new(secret.encode(), body, hashlib.sha256).hexdigest()


def delivery_dict(d: WebhookDelivery) -> dict[str, Any]:
    return {"id": d.id, "webhook_id": d.webhook_id, "event_id": d.event_id, "status": d.status,
            "attempts": d.attempts, "last_error": d.last_error, "created_at": iso_utc(d.created_at),
            "next_attempt_at": iso_utc(d.next_attempt_at) if d.status == "pending" else None,
            "delivered_at": iso_utc(d.delivered_at)}


class WebhookSender:
    """The background sender: wakes on :meth:`wake` (a bounded queue of hints) or every ``poll_s``, claims
    due deliveries one by one and POSTs them. Several replicas may run one each."""

    def __init__(self, sessions: sessionmaker, settings: Any, replica: str, poll_s: float = 1.0) -> None:
        self.sessions, self.settings, self.replica, self.poll_s = sessions, settings, replica, poll_s
        self._hints: queue.Queue[int] = queue.Queue(maxsize=64)
        self._stop = threading.Event()
        self._thread = threading.Thread(target=self._run, name="rotordiag-webhooks", daemon=True)

    def start(self) -> None:
        self._thread.start()

    def stop(self, timeout_s: float = 5.0) -> None:
        self._stop.set()
        self.wake()
        self._thread.join(timeout_s)

    def wake(self) -> None:
        """Tell the sender there is something to send (dropped when its hint queue is full: it polls)."""
        try:
            self._hints.put_nowait(1)
        except queue.Full:
            pass

    def _run(self) -> None:
        while not self._stop.is_set():
            try:
                while not self._stop.is_set() and self.send_due():
                    pass
            except Exception:  # noqa: BLE001 - the sender must outlive a database hiccup
                log.exception("webhook sender: a pass failed; trying again")
            try:
                self._hints.get(timeout=self.poll_s)
            except queue.Empty:
                pass

    def send_due(self) -> bool:
        """Claim one due delivery (the oldest unsent one of its webhook) and send it; False when none was
        due."""
        now = utcnow()
        with self.sessions.begin() as s:
            earlier = aliased(WebhookDelivery)
            blocked = exists().where(earlier.webhook_id == WebhookDelivery.webhook_id,
                                     earlier.id < WebhookDelivery.id, earlier.status.in_(("pending", "sending")))
            due = ((((WebhookDelivery.status == "pending") & (WebhookDelivery.next_attempt_at <= now))
                    | ((WebhookDelivery.status == "sending") & (WebhookDelivery.claim_expires_at < now)))
                   & ~blocked)
            cand = s.scalar(select(WebhookDelivery.id).where(due).order_by(WebhookDelivery.next_attempt_at,
                                                                         WebhookDelivery.id).limit(1))
            if cand is None:
                return False
            claimed = s.execute(update(WebhookDelivery).where(WebhookDelivery.id == cand, due).values(
                status="sending", claimed_by=self.replica,
                claim_expires_at=now + dt.timedelta(seconds=CLAIM_S + float(self.settings.webhook_timeout_s))))
            if int(getattr(claimed, "rowcount", 0) or 0) != 1:
                return True   # another replica took it: look again
        with self.sessions() as s:
            d = s.get(WebhookDelivery, cand)
            hook = s.get(Webhook, d.webhook_id) if d is not None else None
            if d is None:
                return True
            payload, attempts = d.payload, d.attempts
            url, secret = (hook.url, hook.secret) if hook is not None else (None, "")
        error = "the webhook was deleted" if url is None else self._post(url, secret, cand, payload)
        attempts += 1
        with self.sessions.begin() as s:
            d = s.get(WebhookDelivery, cand)
            if d is None:
                return True
            d.attempts, d.claimed_by, d.claim_expires_at = attempts, None, None
            if error is None:
                d.status, d.delivered_at, d.last_error = "delivered", utcnow(), None
            elif url is None or attempts >= int(self.settings.webhook_max_attempts):
                d.status, d.last_error = "failed", error
            else:
                wait_s = min(3600.0, float(self.settings.webhook_backoff_s) * 2 ** (attempts - 1))
                d.status, d.last_error = "pending", error
                d.next_attempt_at = utcnow() + dt.timedelta(seconds=wait_s)
        return True

    def _post(self, url: str, secret: str, delivery_id: int, payload: dict[str, Any]) -> str | None:
        """POST ``payload``; None on a 2xx answer, else what went wrong."""
        body = json.dumps(payload, separators=(",", ":"), sort_keys=True).encode()
        req = urllib.request.Request(url, data=body, method="POST", headers={
            "Content-Type": "application/json", SIGNATURE_HEADER: sign(secret, body),
            DELIVERY_HEADER: str(delivery_id), "User-Agent": "rotordiag-webhook"})
        try:
            with urllib.request.urlopen(req, timeout=float(self.settings.webhook_timeout_s)) as resp:  # noqa: S310
                resp.read(4096)
                return None if 200 <= resp.status < 300 else f"the receiver answered HTTP {resp.status}"
        except urllib.error.HTTPError as exc:
            return f"the receiver answered HTTP {exc.code}"
        except (urllib.error.URLError, OSError, ValueError) as exc:
            return f"not reached: {getattr(exc, 'reason', None) or exc}"
