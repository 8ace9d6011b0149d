"""Setpoint alarms and their delivery (issue 45, item 3): GET/PUT /assets/{id}/setpoints, GET
/assets/{id}/events, POST /assets/{id}/events/{event_id}/ack, and the webhooks (POST/GET /webhooks,
DELETE /webhooks/{id}, POST /webhooks/{id}/test, GET /webhooks/{id}/deliveries). See ``service.alarms``."""
from __future__ import annotations

import secrets
from typing import Annotated

from fastapi import APIRouter, Path, Query
from sqlalchemy import select

from ...alarms import (
    QUANTITIES,
    SIGNATURE_HEADER,
    check_setpoints,
    current_levels,
    delivery_dict,
    enqueue,
    event_dict,
    get_setpoints,
    put_setpoints,
)
from ...core.db import AlarmEvent, Webhook, WebhookDelivery, utcnow
from ...schemas import (
    AckIn,
    AlarmEventOut,
    AlarmEventsOut,
    DeliveryOut,
    SetpointsIn,
    SetpointsOut,
    WebhookIn,
    WebhookOut,
)
from ..deps import ApiKeyDep, JsonBodyDep, SessionDep, StateDep
from ..errors import InputError, error_responses
from .assets import AssetPath

router = APIRouter(tags=["assets"])

_ERRORS = error_responses({404: "No such event or webhook.", 422: "The body is not valid; `detail` says what to fix."},
                          key="always", body="json")
IdPath = Annotated[int, Path(ge=1, le=2**31 - 1)]


def _setpoints_out(session, asset_id: str) -> SetpointsOut:
    return SetpointsOut(asset_id=asset_id, setpoints=get_setpoints(session, asset_id),
                        units={q: u for q, (_, u) in QUANTITIES.items()},
                        levels=current_levels(session, asset_id))


@router.get("/assets/{asset_id}/setpoints", response_model=SetpointsOut, summary="An asset's alarm setpoints")
def get_asset_setpoints(asset_id: AssetPath, session: SessionDep) -> SetpointsOut:
    return _setpoints_out(session, asset_id)


@router.put("/assets/{asset_id}/setpoints", response_model=SetpointsOut, dependencies=[ApiKeyDep, JsonBodyDep],
            responses=_ERRORS, summary="Set an asset's alert/danger setpoints",
            description="Alert and danger setpoints on the overall (direct) pk-pk, 1X and 2X amplitude (µm pk-pk, "
            "the largest over the asset's probes) and on the misalignment estimate Δ. Each stored diagnosis of the "
            "asset is compared with them; a change of level is stored as an event and sent to the webhooks. No "
            "standard zone table is shipped: the numbers are yours. `{}` removes them.")
def put_asset_setpoints(asset_id: AssetPath, body: SetpointsIn, state: StateDep, session: SessionDep) -> SetpointsOut:
    try:
        stored = check_setpoints(body.setpoints)
    except ValueError as exc:
        raise InputError(f"setpoints: {exc}") from None
    with state.sessions.begin() as s:
        put_setpoints(s, asset_id, stored)
    return _setpoints_out(session, asset_id)


@router.get("/assets/{asset_id}/events", response_model=AlarmEventsOut, summary="An asset's alarm events")
def list_events(
    asset_id: AssetPath, session: SessionDep,
    unacked: Annotated[bool, Query(description="Only raised events not yet acknowledged.")] = False,
    limit: Annotated[int, Query(ge=1, le=10_000)] = 200,
) -> AlarmEventsOut:
    q = select(AlarmEvent).where(AlarmEvent.asset_id == asset_id)
    if unacked:
        q = q.where(AlarmEvent.acked_at.is_(None), AlarmEvent.event == "raised")
    rows = session.scalars(q.order_by(AlarmEvent.id.desc()).limit(limit))
    return AlarmEventsOut(asset_id=asset_id, events=[AlarmEventOut(**event_dict(r)) for r in rows])


@router.post("/assets/{asset_id}/events/{event_id}/ack", response_model=AlarmEventOut, dependencies=[ApiKeyDep],
             responses=_ERRORS, summary="Acknowledge an alarm event")
def ack_event(asset_id: AssetPath, event_id: IdPath, state: StateDep, body: AckIn | None = None) -> AlarmEventOut:
    with state.sessions.begin() as s:
        ev = s.get(AlarmEvent, event_id)
        if ev is None or ev.asset_id != asset_id:
            raise InputError(f"asset {asset_id!r} has no alarm event {event_id}; GET /assets/{asset_id}/events "
                             "lists them", "not_found")
        if ev.acked_at is None:
            ev.acked_at = utcnow()
            ev.ack_note = body.note if body is not None else None
        out = AlarmEventOut(**event_dict(ev))
    return out


def _hook_out(h: Webhook, secret: str | None = None) -> WebhookOut:
    return WebhookOut(id=h.id, url=h.url, asset_id=h.asset_id, created_at=h.created_at, secret=secret,
                      signature_header=SIGNATURE_HEADER)


@router.post("/webhooks", response_model=WebhookOut, status_code=201, dependencies=[ApiKeyDep, JsonBodyDep],
             responses=_ERRORS, summary="Add a webhook for alarm events",
             description=f"Every alarm event (of `asset_id`, or of all assets) is POSTed to `url` as JSON, with "
             f"the header `{SIGNATURE_HEADER}: sha256=<hex HMAC-SHA256 of the body, key = secret>` and "
             "`X-Rotordiag-Delivery: <delivery id>` (the same on each retry). A failed delivery (no 2xx answer) is "
             "retried with a doubling wait. The secret is shown only in this answer.")
def add_webhook(body: WebhookIn, state: StateDep) -> WebhookOut:
    secret = body.secret or secrets.token_hex(32)
    with state.sessions.begin() as s:
        h = Webhook(url=body.url, secret=secret, asset_id=body.asset_id)
        s.add(h)
        s.flush()
        out = _hook_out(h, secret)
    return out


@router.get("/webhooks", response_model=list[WebhookOut], dependencies=[ApiKeyDep], responses=_ERRORS,
            summary="List the webhooks")
def list_webhooks(session: SessionDep) -> list[WebhookOut]:
    return [_hook_out(h) for h in session.scalars(select(Webhook).order_by(Webhook.id))]


@router.delete("/webhooks/{webhook_id}", status_code=204, dependencies=[ApiKeyDep], responses=_ERRORS,
               summary="Remove a webhook (its unsent deliveries fail)")
def delete_webhook(webhook_id: IdPath, state: StateDep) -> None:
    with state.sessions.begin() as s:
        h = s.get(Webhook, webhook_id)
        if h is None:
            raise InputError(f"no webhook {webhook_id}", "not_found")
        s.delete(h)


@router.post("/webhooks/{webhook_id}/test", response_model=DeliveryOut, status_code=202, dependencies=[ApiKeyDep],
             responses=_ERRORS, summary="Send a sample event to a webhook")
def test_webhook(webhook_id: IdPath, state: StateDep) -> DeliveryOut:
    """Queue a sample event (``"test": true``) for this webhook; GET /webhooks/{id}/deliveries shows whether it
    arrived."""
    now = utcnow()
    with state.sessions.begin() as s:
        h = s.get(Webhook, webhook_id)
        if h is None:
            raise InputError(f"no webhook {webhook_id}", "not_found")
        sample = AlarmEvent(id=0, asset_id=h.asset_id or "example-asset", created_at=now, quantity="x1_um_pp",
                            level="alert", event="raised", value=80.0, setpoint=75.0, diagnosis_id=None,
                            message="test event from rotordiag (no alarm was raised)", acked_at=None, ack_note=None)
        payload = {"type": "rotordiag.alarm", "test": True, "event": event_dict(sample)}
        d = enqueue(s, state.settings, h.id, None, payload)
        out = DeliveryOut(**delivery_dict(d))
    if state.webhooks is not None:
        state.webhooks.wake()
    return out


@router.get("/webhooks/{webhook_id}/deliveries", response_model=list[DeliveryOut], dependencies=[ApiKeyDep],
            responses=_ERRORS, summary="A webhook's deliveries, newest first")
def list_deliveries(webhook_id: IdPath, session: SessionDep,
                    limit: Annotated[int, Query(ge=1, le=10_000)] = 100) -> list[DeliveryOut]:
    if session.get(Webhook, webhook_id) is None:
        raise InputError(f"no webhook {webhook_id}", "not_found")
    rows = session.scalars(select(WebhookDelivery).where(WebhookDelivery.webhook_id == webhook_id)
                           .order_by(WebhookDelivery.id.desc()).limit(limit))
    return [DeliveryOut(**delivery_dict(d)) for d in rows]
