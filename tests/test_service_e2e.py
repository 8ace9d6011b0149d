"""End to end: `rotordiag serve` as a real uvicorn process on 127.0.0.1, driven over HTTP."""
from __future__ import annotations

import json
import os
import signal
import socket
import subprocess
import sys
import time
import urllib.error
import urllib.request
from pathlib import Path

import pytest

from tests.service_util import API_KEY, diagnose_json, shipped_or_tiny_registry, simulated_channels

ROOT = Path(__file__).resolve().parent.parent


def _free_port() -> int:
    with socket.socket() as s:
        s.bind(("127.0.0.1", 0))
        return s.getsockname()[1]


def _request(url, body=None, headers=None, method=None):
    req = urllib.request.Request(url, data=body, headers=headers or {}, method=method)
    try:
        with urllib.request.urlopen(req, timeout=60) as r:
            return r.status, r.read()
    except urllib.error.HTTPError as e:
        return e.code, e.read()


@pytest.fixture(scope="module")
def server(tmp_path_factory):
    tmp = tmp_path_factory.mktemp("e2e")
    port = _free_port()
    env = dict(os.environ, ROTORDIAG_DATA_DIR=str(tmp / "data"), ROTORDIAG_API_KEY=API_KEY,
               ROTORDIAG_MAX_BODY_BYTES=str(8 * 1024 * 1024),
               ROTORDIAG_SHIPPED_REGISTRY_DIR=str(shipped_or_tiny_registry()))
    exe = Path(sys.executable).parent / "rotordiag"
    cmd = [str(exe), "serve", "--host", "127.0.0.1", "--port", str(port)]
    proc = subprocess.Popen(cmd, cwd=tmp, env=env, stdout=subprocess.PIPE, stderr=subprocess.STDOUT, text=True)
    base = f"http://127.0.0.1:{port}"
    t0 = time.monotonic()
    while True:
        if proc.poll() is not None:
            pytest.fail(f"server exited with {proc.returncode}:\n{proc.stdout.read()}")
        try:
            status, raw = _request(base + "/health")
            # 503 `starting` until a diagnosis worker has loaded and checked the model
            if status == 200 or (status == 503 and json.loads(raw)["status"] != "starting"):
                break
        except OSError:
            pass
        if time.monotonic() - t0 > 120:
            proc.kill()
            pytest.fail("server did not answer /health (other than `starting`) within 120 s")
        time.sleep(0.2)
    yield base, port, tmp
    proc.send_signal(signal.SIGINT)
    try:
        out, _ = proc.communicate(timeout=30)
    except subprocess.TimeoutExpired:
        proc.kill()
        out, _ = proc.communicate()
        pytest.fail(f"server did not stop on SIGINT:\n{out}")
    assert "Traceback" not in out, out


def test_fresh_data_dir_defaults(server):
    base, _, tmp = server
    status, body = _request(base + "/health")
    health = json.loads(body)
    assert status == 200, health                       # the shipped model was seeded into the new registry
    assert health["database"] and health["model_version"]
    assert (tmp / "data" / "rotordiag.sqlite3").is_file()
    assert (tmp / "data" / "registry" / "active").is_file()


def test_diagnose_simulated_waveform_over_http(server):
    base, _, _ = server
    fs, channels = simulated_channels(misalignment=0.2, record_revs=40)
    body = json.dumps(diagnose_json(fs, channels, speed_rpm=1800.0, clearance_um=350.0, asset_id="e2e-unit")).encode()
    status, raw = _request(base + "/diagnose", body, {"Content-Type": "application/json", "X-API-Key": API_KEY})
    assert status == 200, raw[:500]
    verdict = json.loads(raw)
    assert verdict["severity"] in verdict["bands"]["names"]
    assert abs(sum(verdict["probabilities"].values()) - 1) < 1e-6
    assert verdict["offset_um"] == pytest.approx(verdict["misalignment"] * 350.0)
    status, raw = _request(base + "/assets/e2e-unit/history")
    assert status == 200 and json.loads(raw)["count"] == 1
    status, raw = _request(base + "/metrics")
    assert status == 200 and b'handler="/diagnose"' in raw


def test_chunked_upload_is_cut_off_at_the_limit(server):
    """A chunked body without Content-Length: the server answers 413 before the client has sent it all."""
    _, port, _ = server
    with socket.create_connection(("127.0.0.1", port), timeout=30) as s:
        s.sendall(b"POST /diagnose HTTP/1.1\r\nHost: x\r\nContent-Type: application/json\r\n"
                  b"Transfer-Encoding: chunked\r\n\r\n")
        chunk = b"1" * 65536
        sent = 0
        answered = b""
        s.settimeout(0.01)
        for _ in range(1000):                   # up to 64 MiB, far over the 8 MiB limit
            try:
                s.sendall(b"%x\r\n%s\r\n" % (len(chunk), chunk))
                sent += len(chunk)
            except OSError:
                break                            # the server closed the connection
            try:
                answered += s.recv(4096)
                if answered:
                    break
            except TimeoutError:
                pass
            except OSError:
                break
        s.settimeout(10)
        try:
            while b"\r\n\r\n" not in answered:
                more = s.recv(4096)
                if not more:
                    break
                answered += more
        except OSError:
            pass
    assert answered.startswith(b"HTTP/1.1 413"), answered[:200]
    assert sent < 16 * 1024 * 1024
