"""Helpers shared by the service tests (not a test module)."""
from __future__ import annotations

import os
import time
from collections.abc import Callable
from pathlib import Path
from typing import TypeVar

API_KEY = "test-key-0123456789"

#: how long a readiness wait polls before it gives up (a server, a worker, a job): generous, because on a loaded
#: machine a server's start takes minutes, and a wait that polls returns as soon as the thing is ready anyway
READY_CEILING_S = float(os.environ.get("ROTORDIAG_TEST_READY_S", "600"))

_T = TypeVar("_T")


def wait_until(ready: Callable[[], _T], what: str, *, ceiling_s: float | None = None, every_s: float = 0.1) -> _T:
    """Poll ``ready()`` until it returns something true (returned), for at most ``ceiling_s`` (default
    :data:`READY_CEILING_S`); an ``OSError`` counts as not ready yet. Raises ``AssertionError`` naming ``what``."""
    limit = READY_CEILING_S if ceiling_s is None else ceiling_s
    t0 = time.monotonic()
    while True:
        try:
            got = ready()
        except OSError:
            got = None
        if got:
            return got
        if time.monotonic() - t0 > limit:
            raise AssertionError(f"{what}: not ready after {limit:.0f} s (ROTORDIAG_TEST_READY_S)")
        time.sleep(every_s)


def make_settings(tmp_path: Path, **overrides):
    """Settings for an isolated app: its own data dir, database and registry under ``tmp_path``.

    Diagnoses run in the test process (``diagnosis_workers=0``) unless a test asks for worker
    processes (``tests/test_service_pool.py``, the end-to-end test with a real uvicorn).
    """
    from rotordiag.service.core.config import Settings

    values = dict(data_dir=tmp_path / "data", api_key=API_KEY, environment="development",
                  dask_local_workers=1, diagnosis_workers=0, _env_file=None)
    values.update(overrides)
    return Settings(**values)


def auth() -> dict[str, str]:
    return {"X-API-Key": API_KEY}


def probe_signals_um(journal_displacements_m, angles_deg=(45.0, 135.0), bearings=(1, 2, 3, 4)):
    """Probe readings (µm) of the simulated journals: p = x cos θ + y sin θ for each bearing and probe angle.

    Returns ``(bearing, angle_deg, data)`` triples, bearing-major.
    """
    import numpy as np

    d = np.asarray(journal_displacements_m) * 1e6
    out = []
    for b in bearings:
        for a in angles_deg:
            t = np.deg2rad(a)
            out.append((b, a, d[:, b - 1, 0] * np.cos(t) + d[:, b - 1, 1] * np.sin(t)))
    return out


_SIM_CACHE: dict = {}


def simulated_channels(misalignment=0.2, speed_rpm=1800.0, sample_rate_hz=2048.0, record_revs=24,
                       mechanism="rigid"):
    """A simulated recording of the default plant as ``(sample_rate_hz, [(bearing, angle_deg, data_um), ...])``."""
    key = (misalignment, speed_rpm, sample_rate_hz, record_revs, mechanism)
    if key not in _SIM_CACHE:
        from rotordiag.simulator import Plant, simulate

        res = simulate(Plant.default(), speed_rpm, misalignment, 0.05, mechanism=mechanism,
                       transient_revs=200, record_revs=record_revs, sample_rate_hz=sample_rate_hz)
        assert res.status == "ok", res.status
        _SIM_CACHE[key] = (sample_rate_hz, probe_signals_um(res.journal_displacements_m))
    return _SIM_CACHE[key]


def diagnose_json(sample_rate_hz, channels, **extra):
    """JSON body of POST /diagnose."""
    body = {"sample_rate_hz": sample_rate_hz,
            "channels": [{"bearing": b, "angle_deg": a, "units": "um", "data": [float(v) for v in d]}
                         for b, a, d in channels]}
    body.update(extra)
    return body


def build_tiny_registry(root, n_plants=3, seed=0):
    """A small model registry trained here with the models package's own estimator, for when the
    repository does not ship ``models/default_registry`` yet.

    Recordings: the default plant and ``n_plants - 1`` variants (asymmetry, generator mass) at
    two speeds and four Δ (one per severity band), `rigid` coupling, 24 revolutions at 2048 Hz.
    """
    import numpy as np

    from rotordiag.features import ProbeChannel, Recording, extract_features
    from rotordiag.models.config import TrainConfig
    from rotordiag.models.registry import Registry
    from rotordiag.simulator import Plant, simulate

    rng = np.random.default_rng(seed)
    base = Plant.default()
    X, y, groups, names = [], [], [], None
    for plant_id in range(n_plants):
        plant = base if plant_id == 0 else base.replace(
            asymmetry=float(base.asymmetry * rng.uniform(0.6, 1.4)),
            generator_mass_kg=float(base.generator_mass_kg * rng.uniform(0.9, 1.1)))
        for speed in (1600.0, 2000.0):
            for delta in (0.0, 0.1, 0.25, 0.5):
                res = simulate(plant, speed, delta, 0.05, mechanism="rigid", transient_revs=150,
                               record_revs=24, sample_rate_hz=2048.0)
                if res.status != "ok":
                    continue
                rec = Recording(sample_rate_hz=2048.0, speed_rpm=speed, channels=[
                    ProbeChannel(bearing=b, angle_deg=a, units="um", data=d)
                    for b, a, d in probe_signals_um(res.journal_displacements_m)])
                fr = extract_features(rec)
                names = fr.names
                X.append(fr.values)
                y.append(delta)
                groups.append(plant_id)
    X = np.array(X)
    # HistGradientBoosting's binning fails on a column that is all-NaN within a CV fold:
    # train on the columns measured in every row; the verdict maps features by name.
    keep = np.isfinite(X).all(axis=0)
    names = tuple(n for n, k in zip(names, keep) if k)
    small = {"max_iter": 40, "min_samples_leaf": 3}
    cfg = TrainConfig.from_dict({"seed": seed, "classifier": small, "regressor": small})
    model = cfg.make_model(names).fit(X[:, keep], np.array(y), groups=np.array(groups))
    reg = Registry(root)
    version = reg.register(model, {"note": "tiny test model (tests/service_util.py)", "feature_names": list(names),
                                   "bands": cfg.bands.to_dict(), "training_data": {"n_rows_used": len(y)}},
                           activate=True)
    return reg, version


def _source_hash():  # noqa: ANN202 - a hashlib object
    """SHA-256 over the source of the features and models packages and this file."""
    import hashlib

    repo = Path(__file__).resolve().parent.parent
    h = hashlib.sha256()
    for pkg in ("features", "models"):
        for f in sorted((repo / pkg).glob("*.py")):
            h.update(f.name.encode() + f.read_bytes())
    h.update(Path(__file__).read_bytes())
    return h


def shipped_registry_usable() -> bool:
    """The repository ships ``models/default_registry`` and its active model runs with this code.

    Loading the model takes 1-2 s, and test modules ask at collection (``test_service_fuzz.py`` builds its app
    there): a positive answer is remembered under ``test-artifacts/`` (git-ignored), keyed by the model file, the
    features and models source and the versions of the libraries that load it, so any change asks again.
    """
    from importlib.metadata import version

    from rotordiag.service.core.config import SHIPPED_REGISTRY_DIR
    from rotordiag.service.inference import ModelStore, ModelUnavailable

    active = SHIPPED_REGISTRY_DIR / "active"
    if not active.is_file():
        return False
    h = _source_hash()
    model_file = SHIPPED_REGISTRY_DIR / active.read_text().strip() / "model.skops"
    try:
        h.update(model_file.read_bytes())
    except OSError:
        return False
    for lib in ("numpy", "scipy", "scikit-learn", "skops"):
        h.update(f"{lib}={version(lib)}".encode())
    marker = Path(__file__).resolve().parent.parent / "test-artifacts" / f"shipped_usable-{h.hexdigest()[:16]}"
    if marker.is_file():
        return True
    try:
        ModelStore(SHIPPED_REGISTRY_DIR).load()
    except ModelUnavailable:
        return False
    marker.parent.mkdir(parents=True, exist_ok=True)
    marker.touch()
    return True


def shipped_or_tiny_registry(tmp_root=None):
    """The shipped default registry when the repository has a usable one, else a tiny one.

    (Whether the shipped model is usable is asserted by ``test_shipped_default_model_is_usable``.)

    The tiny registry is built once and cached under ``test-artifacts/`` (git-ignored), keyed by
    the source of the features and models packages, so it is rebuilt whenever either changes.
    """
    from rotordiag.service.core.config import SHIPPED_REGISTRY_DIR

    if shipped_registry_usable():
        return SHIPPED_REGISTRY_DIR
    repo = Path(__file__).resolve().parent.parent
    h = _source_hash()
    root = repo / "test-artifacts" / f"tiny_registry-{h.hexdigest()[:16]}"
    if not (root / "active").is_file():
        import shutil
        import tempfile

        root.parent.mkdir(parents=True, exist_ok=True)
        tmp = Path(tempfile.mkdtemp(dir=root.parent, prefix=".building-"))
        build_tiny_registry(tmp / "reg")
        try:
            (tmp / "reg").rename(root)
        except OSError:                      # another process finished first
            pass
        shutil.rmtree(tmp, ignore_errors=True)
        stale = sorted(root.parent.glob("tiny_registry-*"), key=lambda p: p.stat().st_mtime)[:-3]
        for old in stale:                    # keep the three newest builds
            shutil.rmtree(old, ignore_errors=True)
    return root


def two_takes(rec):
    """Bearings 1-2 and, 7 ms later, 3-4 of ``rec`` as two takes: (time, first take's rows, second's, a keyphasor
    channel for each, the samples between the takes, channel names ``b<k>_<angle>deg_um``)."""
    import numpy as np

    fs, channels = rec
    data = np.array([d for _, _, d in channels])
    late = int(round(0.007 * fs))
    second = np.empty_like(data[4:, :-late])
    second[:] = data[4:, late:]
    first = data[:4, :-late]
    n = first.shape[1]
    t = np.arange(n) / fs
    period = 60.0 / 1800.0
    kp_a = np.where(((t - 0.3 * period) / period) % 1.0 < 0.05, -12.0, -8.0)
    kp_b = np.where(((t + late / fs - 0.3 * period) / period) % 1.0 < 0.05, -12.0, -8.0)
    return t, first, second, kp_a, kp_b, late, [f"b{b}_{a:g}deg_um" for b, a, _ in channels]


def write_takes_csv(path, t, cols, col_names):
    """A take as CSV: a ``time_s`` column, then ``cols`` named ``col_names``; returns ``path``."""
    import numpy as np

    np.savetxt(path, np.column_stack([t, *cols]), delimiter=",", header=",".join(["time_s", *col_names]),
               comments="", fmt="%.9g")
    return path


def full_disk(engine, on: dict) -> Callable:
    """While ``on["full"]``, every INSERT/UPDATE/DELETE on ``engine`` fails as SQLite fails on a full disk: the
    ``sqlalchemy.exc.OperationalError`` wrapping ``sqlite3.OperationalError("database or disk is full")`` that
    the store sees from the driver (raised here already wrapped, so the fault is the same whatever SQLAlchemy
    version runs the event hook)."""
    import sqlite3

    from sqlalchemy import event
    from sqlalchemy.exc import OperationalError

    @event.listens_for(engine, "before_cursor_execute")
    def _raise(conn, cursor, statement, parameters, context, executemany):
        if on["full"] and statement.lstrip().upper().startswith(("INSERT", "UPDATE", "DELETE")):
            raise OperationalError(statement, parameters, sqlite3.OperationalError("database or disk is full"))

    return _raise


def pooled_and_plain_apps(tmp_path_factory):
    """Two apps on the shipped (or tiny) model, each with its own data folder: one diagnosing in a worker
    process (``diagnosis_workers=1``), one in the server's threads — for tests that both doors answer alike."""
    from rotordiag.service.main import create_app

    registry = shipped_or_tiny_registry(tmp_path_factory.mktemp("registry"))
    pooled = create_app(make_settings(tmp_path_factory.mktemp("pooled"), shipped_registry_dir=registry,
                                      diagnosis_workers=1))
    plain = create_app(make_settings(tmp_path_factory.mktemp("plain"), shipped_registry_dir=registry))
    return pooled, plain
