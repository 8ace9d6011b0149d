"""Setpoint alarms and webhooks (issue 45, item 3): setpoints checked, levels of a verdict's quantities, events
raised and cleared by stored diagnoses and acknowledged with the key, delivery to a real HTTP receiver on
loopback (signature checked with an independent HMAC, a retry after a 500, the test endpoint, nothing sent
twice even with two senders claiming at once, on SQLite and PostgreSQL), and a dead receiver never failing a
diagnosis."""
from __future__ import annotations

import hashlib
import hmac
import json
import socket
import threading
import time
from http.server import BaseHTTPRequestHandler, ThreadingHTTPServer
from types import SimpleNamespace

import pytest
from fastapi.testclient import TestClient

from rotordiag.service.alarms import SIGNATURE_HEADER, WebhookSender, check_setpoints, level_of, verdict_quantities
from rotordiag.service.core.db import Webhook, WebhookDelivery, init_db, make_engine
from rotordiag.service.main import create_app
from tests.service_util import auth, make_settings, shipped_or_tiny_registry, wait_until
from tests.test_service_baseline import _body

SECRET = "s3cret-for-the-test-0123456789"


class Receiver:
    """A webhook receiver on a loopback port: answers the first ``fail_first`` POSTs with HTTP 500, then 200,
    and keeps every request (headers and body)."""

    def __init__(self, fail_first: int = 0) -> None:
        self.fail_left = fail_first
        self.requests: list[tuple[int, dict[str, str], bytes]] = []
        self.lock = threading.Lock()
        outer = self

        class Handler(BaseHTTPRequestHandler):
            def do_POST(self) -> None:  # noqa: N802 - http.server's name
                body = self.rfile.read(int(self.headers.get("Content-Length", "0")))
                with outer.lock:
                    code = 500 if outer.fail_left > 0 else 200
                    outer.fail_left -= 1
                    outer.requests.append((code, dict(self.headers), body))
                self.send_response(code)
                self.send_header("Content-Length", "0")
                self.end_headers()

            def log_message(self, *args) -> None:
                pass

        self.server = ThreadingHTTPServer(("127.0.0.1", 0), Handler)
        self.url = f"http://127.0.0.1:{self.server.server_address[1]}/hook"
        self.thread = threading.Thread(target=self.server.serve_forever, daemon=True)
        self.thread.start()

    def accepted(self) -> list[dict]:
        """The bodies answered 200, decoded, after checking each signature with an independent HMAC."""
        out = []
        with self.lock:
            reqs = list(self.requests)
        for code, headers, body in reqs:
            expected = "sha256=" + hmac.new(SECRET.encode(), body, hashlib.sha256).hexdigest()
            assert headers[SIGNATURE_HEADER] == expected
            if code == 200:
                out.append({"delivery": headers["X-Rotordiag-Delivery"], **json.loads(body)})
        return out

    def close(self) -> None:
        self.server.shutdown()
        self.server.server_close()


def test_setpoints_are_checked():
    assert check_setpoints({"x1_um_pp": {"alert": 50, "danger": 90}}) == {"x1_um_pp": {"alert": 50.0, "danger": 90.0}}
    for bad, words in [({"x3_um_pp": {"alert": 1}}, "unknown quantity"), ({"x1_um_pp": {"trip": 1}}, "unknown level"),
                       ({"x1_um_pp": {"alert": -1}}, "non-negative"), ({"x1_um_pp": {"alert": True}}, "non-negative"),
                       ({"x1_um_pp": {"alert": 90, "danger": 50}}, "above alert"), ({"x1_um_pp": {}}, "either")]:
        with pytest.raises(ValueError, match=words):
            check_setpoints(bad)


def test_levels_and_quantities_of_a_verdict():
    levels = {"alert": 50.0, "danger": 90.0}
    assert level_of(49.9, levels) == ("normal", None)
    assert level_of(50.0, levels) == ("alert", 50.0)
    assert level_of(120.0, levels) == ("danger", 90.0)
    assert level_of(120.0, {"alert": 50.0}) == ("alert", 50.0)
    # hysteresis: a raised level holds down to 5 % below its setpoint, then clears (no chatter around a setpoint)
    assert level_of(48.0, levels, "alert") == ("alert", 50.0)
    assert level_of(47.4, levels, "alert") == ("normal", None)
    assert level_of(86.0, levels, "danger") == ("danger", 90.0)
    assert level_of(85.0, levels, "danger") == ("alert", 50.0)
    assert level_of(48.0, levels, "danger") == ("alert", 50.0)
    assert level_of(48.0, levels, "normal") == ("normal", None)
    verdict = {"misalignment": 0.2, "bearings": [
        {"bearing": 1, "features": {"b1_x_direct_um_pp": 30.0, "b1_y_direct_um_pp": 41.0, "b1_x_1x_amp_um_pp": 20.0,
                                    "b1_y_1x_amp_um_pp": 12.0, "b1_x_2x_amp_um_pp": 3.0}},
        {"bearing": 2, "features": {"b2_x_direct_um_pp": 35.0, "b2_y_1x_amp_um_pp": 25.0,
                                    "b2_y_2x_amp_um_pp": float("nan")}}]}
    assert verdict_quantities(verdict) == {"overall_um_pp": 41.0, "x1_um_pp": 25.0, "x2_um_pp": 3.0,
                                           "misalignment": 0.2}
    assert verdict_quantities({"misalignment": None, "bearings": []}) == {}


@pytest.fixture(scope="module")
def client(tmp_path_factory):
    tmp = tmp_path_factory.mktemp("svc")
    registry = shipped_or_tiny_registry(tmp_path_factory.mktemp("registry"))
    app = create_app(make_settings(tmp, shipped_registry_dir=registry, webhook_backoff_s=0.2))
    with TestClient(app) as c:
        yield c


def test_alarm_routes_need_the_key(client):
    assert client.put("/assets/a/setpoints", json={"setpoints": {}}).status_code == 401
    assert client.post("/assets/a/events/1/ack").status_code == 401
    assert client.post("/webhooks", json={"url": "http://127.0.0.1:9/x"}).status_code == 401
    assert client.get("/webhooks").status_code == 401
    assert client.post("/webhooks/1/test", headers={"X-API-Key": "wrong"}).status_code == 403


def test_bad_setpoints_and_webhooks_are_422(client):
    r = client.put("/assets/a/setpoints", json={"setpoints": {"x1_um_pp": {"alert": 90, "danger": 50}}},
                   headers=auth())
    assert r.status_code == 422 and "above alert" in r.text
    r = client.post("/webhooks", json={"url": "file:///etc/passwd"}, headers=auth())
    assert r.status_code == 422
    assert client.post("/webhooks/999/test", headers=auth()).status_code == 404


def test_setpoint_raises_and_clears_delivered_signed_after_a_500(client):
    rx = Receiver(fail_first=1)
    try:
        asset = "unit-alarm"
        hook = client.post("/webhooks", json={"url": rx.url, "secret": SECRET, "asset_id": asset}, headers=auth())
        assert hook.status_code == 201 and hook.json()["secret"] == SECRET
        hook_id = hook.json()["id"]
        assert all(h.get("secret") is None for h in client.get("/webhooks", headers=auth()).json())
        # the aligned sample's largest 1X is about 15 µm pk-pk: alert at 5 raises, danger at 1000 does not
        r = client.put(f"/assets/{asset}/setpoints", json={"setpoints": {"x1_um_pp": {"alert": 5, "danger": 1000}}},
                       headers=auth())
        assert r.status_code == 200 and r.json()["units"]["x1_um_pp"] == "µm pk-pk"
        v = client.post("/diagnose", json=_body(asset), headers=auth())
        assert v.status_code == 200, v.text
        events = client.get(f"/assets/{asset}/events").json()["events"]
        assert [(e["quantity"], e["event"], e["level"]) for e in events] == [("x1_um_pp", "raised", "alert")]
        raised = events[0]
        assert raised["setpoint"] == 5.0 and 5.0 < raised["value"] < 1000.0
        assert raised["diagnosis_id"] == v.json()["diagnosis_id"]
        assert f'rotordiag_asset_setpoint_level{{asset="{asset}",quantity="x1_um_pp"}} 1.0' in client.get("/metrics").text
        # a second diagnosis at the same level raises nothing new
        client.post("/diagnose", json=_body(asset, seed=1), headers=auth())
        assert len(client.get(f"/assets/{asset}/events").json()["events"]) == 1
        client.put(f"/assets/{asset}/setpoints", json={"setpoints": {"x1_um_pp": {"alert": 500}}}, headers=auth())
        client.post("/diagnose", json=_body(asset, seed=2), headers=auth())
        events = client.get(f"/assets/{asset}/events").json()["events"]
        assert [(e["event"], e["level"]) for e in events] == [("cleared", "normal"), ("raised", "alert")]

        got = wait_until(lambda: (lambda a: a if len(a) >= 2 else None)(rx.accepted()), "two deliveries",
                         ceiling_s=30)
        assert [g["event"]["event"] for g in got] == ["raised", "cleared"]   # in order, though the raised was retried
        assert got[0]["event"]["id"] == raised["id"] and got[0]["test"] is False
        assert rx.requests[0][0] == 500 and rx.requests[0][1]["X-Rotordiag-Delivery"] == got[0]["delivery"]
        assert len({g["delivery"] for g in got}) == len(got)          # nothing delivered twice
        deliveries = client.get(f"/webhooks/{hook_id}/deliveries", headers=auth()).json()
        assert sorted(d["status"] for d in deliveries) == ["delivered", "delivered"]
        assert sorted(d["attempts"] for d in deliveries) == [1, 2]

        # acknowledgement: with the key only; then the raised event no longer shows as unacknowledged
        assert client.get(f"/assets/{asset}/events?unacked=true").json()["events"][0]["id"] == raised["id"]
        r = client.post(f"/assets/{asset}/events/{raised['id']}/ack", json={"note": "R. Ortiz: checking 1X"},
                        headers=auth())
        assert r.status_code == 200 and r.json()["acked_at"] and r.json()["ack_note"] == "R. Ortiz: checking 1X"
        assert client.get(f"/assets/{asset}/events?unacked=true").json()["events"] == []
        assert client.post(f"/assets/other/events/{raised['id']}/ack", headers=auth()).status_code == 404

        metrics = client.get("/metrics").text
        assert f'rotordiag_asset_setpoint_level{{asset="{asset}",quantity="x1_um_pp"}} 0.0' in metrics
        assert 'rotordiag_webhook_deliveries{status="delivered"}' in metrics

        # the test endpoint sends a sample event, marked as a test
        t = client.post(f"/webhooks/{hook_id}/test", headers=auth())
        assert t.status_code == 202 and t.json()["event_id"] is None
        got = wait_until(lambda: (lambda a: a if len(a) >= 3 else None)(rx.accepted()), "the test", ceiling_s=30)
        assert got[2]["test"] is True and got[2]["event"]["asset_id"] == asset
    finally:
        rx.close()


def test_unreachable_webhook_never_fails_a_diagnosis(client):
    with socket.socket() as s:
        s.bind(("127.0.0.1", 0))
        port = s.getsockname()[1]   # closed again: nothing listens there
    hook = client.post("/webhooks", json={"url": f"http://127.0.0.1:{port}/x", "asset_id": "unit-dead"},
                       headers=auth()).json()
    client.put("/assets/unit-dead/setpoints", json={"setpoints": {"overall_um_pp": {"alert": 1}}}, headers=auth())
    v = client.post("/diagnose", json=_body("unit-dead"), headers=auth())
    assert v.status_code == 200 and isinstance(v.json()["diagnosis_id"], int)
    d = wait_until(lambda: (lambda r: r if r and r[0]["attempts"] >= 1 else None)(
        client.get(f"/webhooks/{hook['id']}/deliveries", headers=auth()).json()), "a failed try", ceiling_s=30)
    assert d[0]["status"] in ("pending", "sending", "failed") and "not reached" in (d[0]["last_error"] or "")


def test_two_senders_never_send_one_delivery_twice(database_url):
    """Two senders (two replicas) drain one stored queue at once: every delivery arrives exactly once."""
    rx = Receiver()
    engine = make_engine(database_url)
    sessions = init_db(engine)
    settings = SimpleNamespace(webhook_timeout_s=5.0, webhook_max_attempts=3, webhook_backoff_s=0.1)
    try:
        with sessions.begin() as s:
            h = Webhook(url=rx.url, secret=SECRET, asset_id=None)
            s.add(h)
            s.flush()
            for i in range(30):
                s.add(WebhookDelivery(webhook_id=h.id, event_id=i + 1, payload={"n": i}, status="pending",
                                      attempts=0))
        senders = [WebhookSender(sessions, settings, f"replica-{k}") for k in range(2)]

        def drain(sender: WebhookSender) -> None:
            while sender.send_due():
                pass

        threads = [threading.Thread(target=drain, args=(snd,)) for snd in senders]
        t0 = time.monotonic()
        for t in threads:
            t.start()
        for t in threads:
            t.join(60)
        assert time.monotonic() - t0 < 60
        got = rx.accepted()
        assert sorted(g["n"] for g in got) == list(range(30))
        assert len(rx.requests) == 30
        with sessions() as s:
            assert {d.status for d in s.query(WebhookDelivery)} == {"delivered"}
    finally:
        rx.close()
        engine.dispose()


def test_the_delivery_queue_is_bounded(tmp_path):
    """Beyond ``webhook_max_pending`` waiting deliveries a new one is stored as dropped, with the reason."""
    from rotordiag.service.alarms import enqueue

    sessions = init_db(make_engine(f"sqlite:///{tmp_path / 'q.sqlite3'}"))
    settings = SimpleNamespace(webhook_max_pending=2)
    with sessions.begin() as s:
        got = [enqueue(s, settings, 1, i, {"n": i}).status for i in range(3)]
        last = s.query(WebhookDelivery).order_by(WebhookDelivery.id.desc()).first()
        assert got == ["pending", "pending", "dropped"] and "2 deliveries were already waiting" in last.last_error


# --- recording time, operating-state tags and event notes (issue 45, item 2) ----------------------------

def test_backfilled_recording_lands_in_its_place_with_tags_and_note(client):
    asset = "unit-backfill"
    client.put(f"/assets/{asset}/setpoints", json={"setpoints": {"x1_um_pp": {"alert": 5}}}, headers=auth())
    late = client.post("/diagnose?recorded_at=2026-06-01T10:00:00Z&tags=load_mw=350;stator_temp_c=71.5",
                       json=_body(asset), headers=auth())
    assert late.status_code == 200, late.text
    early = client.post("/diagnose?recorded_at=2025-01-15T08:00:00%2B01:00&note=aligned on 2025-01-14",
                        json=_body(asset, seed=1), headers=auth())
    assert early.status_code == 200, early.text
    none_given = client.post("/diagnose", json=_body(asset, seed=2), headers=auth()).json()
    pts = client.get(f"/assets/{asset}/history").json()["points"]
    # ordered by recording time: the backfilled January 2025 recording first, the one without a time (stored now) last
    assert [p["id"] for p in pts] == [early.json()["diagnosis_id"], late.json()["diagnosis_id"],
                                      none_given["diagnosis_id"]]
    assert pts[0]["trend_time"].startswith("2025-01-15T07:00:00") and pts[0]["note"] == "aligned on 2025-01-14"
    assert pts[1]["tags"] == {"load_mw": 350.0, "stator_temp_c": 71.5} and pts[2]["recorded_at"] is None
    since = client.get(f"/assets/{asset}/history?since=2026-01-01T00:00:00Z").json()["points"]
    assert [p["id"] for p in since] == [p["id"] for p in pts[1:]]
    # the alarm was raised by the first live recording only: the backfilled one raised and cleared nothing
    events = client.get(f"/assets/{asset}/events").json()["events"]
    assert [(e["event"], e["diagnosis_id"]) for e in events] == [("raised", late.json()["diagnosis_id"])]


def test_bad_recording_time_and_tags_are_422(client):
    r = client.post("/diagnose?recorded_at=2999-01-01T00:00:00Z", json=_body("unit-bad"), headers=auth())
    assert r.status_code == 422 and "in the future" in r.text
    r = client.post("/diagnose?tags=Load MW=3", json=_body("unit-bad"), headers=auth())
    assert r.status_code == 422 and "name=value" in r.text


def test_assets_by_site_unit_train(client):
    key = auth()
    assert client.post("/diagnose", json=_body("unit-placed"), headers=key).status_code == 200
    assert client.put("/assets/unit-placed/hierarchy", json={"site": "Riverside"}).status_code == 401
    r = client.put("/assets/unit-placed/hierarchy", json={"site": "Riverside", "unit": "unit 3",
                                                             "train": "generator-exciter"}, headers=key)
    assert r.status_code == 200 and r.json()["unit"] == "unit 3" and r.json()["diagnoses"] == 1
    client.put("/assets/a-first/hierarchy", json={"site": "Avon", "unit": "unit 1", "train": "gt"}, headers=key)
    listed = client.get("/assets").json()
    places = [(a["site"], a["asset_id"]) for a in listed if a["site"] is not None]
    assert places == [("Avon", "a-first"), ("Riverside", "unit-placed")]        # by site, then unit, train
    has_site = [a["site"] is not None for a in listed]
    assert has_site == sorted(has_site, reverse=True)                            # those without a place last
    assert [a["asset_id"] for a in client.get("/assets?site=Riverside").json()] == ["unit-placed"]
    h = client.get("/assets/unit-placed/history").json()
    assert (h["site"], h["unit"], h["train"]) == ("Riverside", "unit 3", "generator-exciter")
    assert client.put("/assets/x/hierarchy", json={"site": "s" * 200}, headers=key).status_code == 422
