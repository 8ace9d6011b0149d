"""The model store: the service's registry, the loaded active model, and one diagnosis call.

The verdict itself is the models package's (``models.pipeline.diagnose_recording``: features, model scores,
checks, status, verdict); this module only caches loaded models per version and turns a request into that call
(in a diagnosis worker process, ``service.pool``, sent as a typed ``WorkerCall``).
"""
from __future__ import annotations

import hashlib
import logging
import math
import shutil
import threading
from pathlib import Path
from typing import TYPE_CHECKING, Any

from .core.config import Settings

if TYPE_CHECKING:
    from rotordiag.models.predict import ModelBundle

log = logging.getLogger("rotordiag.service")


class ModelUnavailable(RuntimeError):
    """No model can be loaded (empty registry, unknown version)."""


class ModelStore:
    """Registry access plus a per-version cache of loaded models.

    Parameters
    ----------
    root : Path
        Registry directory (``models.registry.Registry`` layout).
    """

    def __init__(self, root: Path) -> None:
        from rotordiag.models.registry import Registry

        self.root = Path(root)
        self.registry = Registry(self.root)
        self._cache: dict[str, Any] = {}
        self._files: dict[str, tuple[tuple[int, int, int], str]] = {}   # version -> (stat key, sha256)
        self._lock = threading.Lock()

    def _public(self, message: str, path: Path) -> str:
        """``message`` without the server's paths (the model file's and the registry's): a client sees the
        version and what is wrong, the log has the paths."""
        for text, name in ((str(path), path.name), (str(self.root.resolve()), "<registry>"), (str(self.root), "<registry>")):
            message = message.replace(text, name)
        return message

    @classmethod
    def open(cls, settings: Settings) -> ModelStore:
        """Open ``settings.registry_dir``, seeding it from the shipped registry when it is empty.

        The shipped registry is copied rather than used in place so activating or
        registering models never writes into the installed package.
        """
        root = settings.registry_dir
        shipped = settings.shipped_registry_dir
        if settings.model_registry_dir is None and (not root.exists() or not any(root.iterdir())):
            if shipped.is_dir() and any(shipped.iterdir()):
                log.info("seeding model registry %s from %s", root, shipped)
                root.parent.mkdir(parents=True, exist_ok=True)
                shutil.copytree(shipped, root, dirs_exist_ok=True)
            else:
                log.warning("no shipped model registry at %s; /diagnose answers 503 until a model is "
                            "registered (POST /models/retrain)", shipped)
        root.mkdir(parents=True, exist_ok=True)
        return cls(root)

    # -- registry -------------------------------------------------------------------------------
    def active_version(self) -> str | None:
        """Version the active pointer names, or ``None``."""
        try:
            return self.registry.active_version()
        except OSError:
            return None

    def versions(self) -> list[dict[str, Any]]:
        """Cards of every registered version, oldest first, with an ``active`` flag."""
        from rotordiag.models.checks.bearing_sets import probe_sets
        from rotordiag.models.registry import RegistryError

        out = []
        for v in self.registry.versions():
            try:
                card = dict(self.registry.card(v))
                card["probe_sets"] = probe_sets(card)
            except RegistryError as exc:
                card = {"error": str(exc)}
            card["version"] = v
            card["active"] = v == self.active_version()
            out.append(card)
        return out

    def activate(self, version: str, *, force: bool = False) -> None:
        """Point ``active`` at ``version`` (``KeyError`` when unknown; ``models.registry.ActivationRefused`` when
        a plant-retrained version's report says it is not better and ``force`` is not set)."""
        if version not in self.registry.versions():
            raise KeyError(version)
        self.registry.activate(version, force=force)

    def load(self, version: str | None = None) -> ModelBundle:
        """The ``models.predict.ModelBundle`` of ``version`` or the active model, loaded once and cached."""
        from rotordiag.models.predict import ModelBundle
        from rotordiag.models.registry import RegistryError

        if version is None:
            version = self.active_version()
            if version is None:
                raise ModelUnavailable("no active model in the registry; register one (POST /models/retrain) "
                                       "and activate it (POST /models/{version}/activate)")
        with self._lock:
            bundle = self._cache.get(version)
            key = self._stat_key(version)
            if bundle is not None and self._files.get(version, (None,))[0] != key:
                log.warning("model %s: its file changed on disk since it was loaded; loading it again", version)
                bundle = None          # replaced or corrupted under us: use (or fail on) what is there now
                self._cache.pop(version, None)
                self._files.pop(version, None)
            if bundle is None:
                if version not in self.registry.versions():
                    raise ModelUnavailable(f"model version {version!r} is not in the registry; "
                                           f"registered: {self.registry.versions()}")
                from rotordiag.models.registry import load_model_bytes

                path = self._model_file(version)
                try:
                    data = path.read_bytes()
                except OSError as exc:
                    log.error("model %s: cannot read %s: %s", version, path, exc)
                    raise ModelUnavailable(f"model {version}: its file cannot be read ({exc.strerror or 'I/O error'}); "
                                           "the server log names the file") from None
                digest = hashlib.sha256(data).hexdigest()   # of the bytes loaded, not a second read
                try:
                    model, card = load_model_bytes(data, str(path)), self.registry.card(version)
                except RegistryError as exc:
                    log.error("model %s: %s", version, exc)
                    raise ModelUnavailable(f"model {version}: {self._public(str(exc), path)}") from None
                _check_usable(model, version)
                bundle = ModelBundle(model=model, card=card, version=version)
                self._cache[version] = bundle
                self._files[version] = (key, digest)
        return bundle

    def _model_file(self, version: str) -> Path:
        from rotordiag.models.registry import MODEL_FILE

        return self.root / version / MODEL_FILE

    def _stat_key(self, version: str) -> tuple[int, int, int]:
        """(inode, size, mtime in ns) of the version's model file: a cheap test that it is the file loaded."""
        try:
            st = self._model_file(version).stat()
        except OSError:
            return (0, -1, 0)
        return (st.st_ino, st.st_size, st.st_mtime_ns)

    def file_sha256(self, version: str) -> str | None:
        """SHA-256 of the model file of ``version`` as loaded (after :meth:`load`), else ``None``."""
        entry = self._files.get(version)
        return entry[1] if entry is not None else None

    # -- diagnosis ------------------------------------------------------------------------------
    def diagnose(self, recording: Any, version: str | None = None, plant_model: str | None = None,
                 plant_shaftline: dict[str, Any] | None = None, declared_by: str | None = None) -> dict[str, Any]:
        """Features, then the verdict of the models package, as a JSON-able dict.

        ``plant_model`` / ``plant_shaftline``: the machine's plant model when known (the request's, else its
        asset's): a family the model was not trained on is never confident (``models.checks.family``);
        ``declared_by``: whose it is (``asset`` or ``request``), for the verdict's ``answered_by``.

        The verdict (``models.predict.Verdict``) is returned as is, plus
        ``bearings`` (the features package's per-bearing details) and
        ``key_features`` (the contributing features' values, stored in asset history) and
        ``signature`` (``features.signature``: what an asset baseline compares).

        Raises
        ------
        ValueError
            Bad recordings, with a message for the user (from ``features`` / ``models``).
        ModelUnavailable
            No model to diagnose with.
        """
        from rotordiag.features import signature

        bundle = self.load(version)
        verdict, fr = self._verdict(bundle, recording, plant_model=plant_model, plant_shaftline=plant_shaftline,
                                    declared_by=declared_by)
        out = _clean(verdict.to_dict())  # NaN/inf -> null: JSON has no non-finite numbers
        out["model_version"] = out.get("model_version") or bundle.version
        out["bearings"] = _bearings(fr)
        out["key_features"] = {f["name"]: f["value"] for f in out.get("top_features", [])}
        out["signature"] = signature(fr)   # for the asset baseline (service.baseline takes it out of the answer)
        return out


    @staticmethod
    def _verdict(bundle: Any, recording: Any, fr: Any = None, plant_model: str | None = None,
                 plant_shaftline: dict[str, Any] | None = None, declared_by: str | None = None) -> tuple[Any, Any]:
        """The verdict and the features it was computed from: the pipeline's features and sanity stages
        (``models.pipeline.read_features``, unless ``fr``, the recording's features, is given), refused here when a
        feature overflows, then ``models.pipeline.diagnose_recording`` (the verdict and a doubtful estimated speed
        judged by the model; ``plant_model``/``plant_shaftline``: the machine's declared plant)."""
        import numpy as np

        from rotordiag.models.pipeline import diagnose_recording, read_features

        if fr is None:
            fr = read_features(recording)
        overflowed = np.flatnonzero(np.isinf(np.asarray(fr.values, dtype=float)))
        if overflowed.size:
            raise ValueError(f"the waveforms are too large to analyse ({fr.names[overflowed[0]]} overflows); check the units: "
                             "`data` is in `units` (um by default), and a proximity probe reads at most a few "
                             "thousand µm")
        clearance = getattr(recording, "clearance_um", None)
        clearance = float(clearance) if isinstance(clearance, (int, float)) else None
        return diagnose_recording(bundle, recording, clearance_um=clearance, fr=fr, plant_model=plant_model,
                                  plant_shaftline=plant_shaftline, declared_by=declared_by)

    def plot_features(self, recording: Any) -> Any:
        """The features the web page's pictures are drawn from: those of the verdict (:meth:`diagnose`, the
        active model), so that the pictures mark the orders at the verdict's speed. Only an estimated speed in
        doubt can differ from the features package's own (``models.checks.speed_choice``): for any other the model is
        not run; nor when no model can be loaded."""
        from rotordiag.features import extract_features, speed_in_doubt

        fr = extract_features(recording)
        if fr.speed_source != "estimated" or not any(speed_in_doubt(w) for w in fr.warnings):
            return fr
        try:
            bundle = self.load(None)
        except ModelUnavailable:
            return fr
        return self._verdict(bundle, recording, fr)[1]


def _check_usable(model: Any, version: str) -> None:
    """Run the loaded model once on a row of missing features (every component accepts NaN).

    A model file written by an incompatible version of the models package loads but fails when
    used; this turns that into a clear 503 ("rebuild or retrain") instead of a 500 on every request.
    """
    import numpy as np

    try:
        row = np.full((1, len(model.feature_names_)), np.nan)
        model.predict_proba(row)
        model.predict_misalignment(row)
        model.ood_ratio(row)
    except Exception as exc:  # noqa: BLE001 - any failure means the file does not fit this code
        raise ModelUnavailable(
            f"model {version} cannot be used with this code version ({type(exc).__name__}: {exc}); "
            "retrain it (POST /models/retrain or `rotordiag train`) or activate another version") from None


def _clean(v: Any) -> Any:
    """JSON-able copy: dataclasses/arrays to dicts/lists, non-finite floats to ``None``."""
    import dataclasses

    import numpy as np

    t = type(v)   # fast paths for what a verdict is made of (a few hundred values per request)
    if t is float:
        return v if math.isfinite(v) else None
    if t is str or t is int or t is bool or v is None:
        return v
    if t is dict:
        return {str(k): _clean(x) for k, x in v.items()}
    if dataclasses.is_dataclass(v) and not isinstance(v, type):
        v = dataclasses.asdict(v)
    elif hasattr(v, "to_dict") and not isinstance(v, dict):
        v = v.to_dict()
    if isinstance(v, dict):
        return {str(k): _clean(x) for k, x in v.items()}
    if isinstance(v, (list, tuple)):
        return [_clean(x) for x in v]
    if isinstance(v, np.ndarray):
        return [_clean(x) for x in v.tolist()] if v.size <= 64 else None
    if isinstance(v, np.generic):
        v = v.item()
    if isinstance(v, float) and not math.isfinite(v):
        return None
    if isinstance(v, complex):
        return None
    return v


def _bearings(fr: Any) -> list[dict[str, Any]]:
    """Per-bearing key features of a ``features.FeatureResult``: bearing, probe angles, clearance and
    that bearing's entries of the feature vector (``b{n}_...`` names, units in the names)."""
    out = []
    for b, detail in sorted((getattr(fr, "bearings", None) or {}).items()):
        out.append(_clean({
            "bearing": int(b),
            "probe_angles_deg": list(getattr(detail, "probe_angles_deg", ())),
            "clearance_um": getattr(detail, "clearance_um", None),
            "features": dict(getattr(detail, "features", {}) or {}),
        }))
    return out
