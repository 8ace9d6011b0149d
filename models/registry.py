"""Model registry: versioned directories, atomic writes, an ``active`` pointer.

Layout of a registry root::

    ROOT/
      active                 text file: the active version name (e.g. "v0003")
      history.json           activation history, newest last (rollback walks it back)
      v0001/
        model.skops          the fitted MisalignmentModel (skops format, never pickle)
        card.json            version, created, data hash and spec, plant family, feature
                             names, bands, metrics, code version, ...
        report.json          evaluation report (models.evaluate)
        report.png           confusion matrices, reliability, Δ scatter
      v0002/ ...

A version is written into a temporary directory inside ROOT and moved into place with
``os.replace``, so a reader never sees a half-written version; the pointer and history
files are replaced the same way. Models are loaded with skops and the explicit
:data:`TRUSTED_TYPES` list: a file that contains any other type is refused.
"""
from __future__ import annotations

import builtins
import json
import os
import re
import shutil
import tempfile
import threading
import zipfile
from collections.abc import Mapping
from dataclasses import dataclass
from datetime import UTC, datetime
from pathlib import Path
from typing import TYPE_CHECKING, Any

from ._sklearn_private import PRIVATE_TRUSTED_TYPES

if TYPE_CHECKING:
    from .estimators import MisalignmentModel

MODEL_FILE = "model.skops"
CARD_FILE = "card.json"
ACTIVE_FILE = "active"
HISTORY_FILE = "history.json"
_VERSION_RE = re.compile(r"^v(\d{4,})$")

#: Every type a rotordiag model file may contain beyond skops' default-trusted ones.
#: Loading refuses files holding anything else (checked before any object is built).
TRUSTED_TYPES: tuple[str, ...] = (
    "rotordiag.core.bands.SeverityBands",
    "rotordiag.models.estimators.ConformalIntervalRegressor",
    "rotordiag.models.estimators.KNNDistanceOOD",
    "rotordiag.models.estimators.FeatureEnvelope",
    "rotordiag.models.estimators.MisalignmentModel",
    "rotordiag.models.estimators.SeverityClassifier",
    "rotordiag.models.ordinal.OrdinalSeverityClassifier",
    "numpy.dtype",
    *PRIVATE_TRUSTED_TYPES,
)


def _version_number(name: str) -> int:
    """The number of a version directory name (``"v0012"`` → 12)."""
    m = _VERSION_RE.match(name)
    if m is None:
        raise RegistryError(f"{name!r} is not a version name (v0001, v0002, ...)")
    return int(m.group(1))


def shipped_registry_dir() -> Path:
    """Directory of the default model registry shipped inside the package.

    Found through :mod:`importlib.resources`, so it works from a checkout (editable
    install) and from an installed wheel alike. The package is always installed
    unzipped, so the resource is a real directory.
    """
    from importlib.resources import files

    return Path(str(files("rotordiag.models") / "default_registry"))


class RegistryError(ValueError):
    """A registry operation that cannot be done (unknown version, untrusted file, ...)."""


class ActivationRefused(RegistryError):
    """Activating a version whose plant quality report says it is not better than the model it was compared
    with (or whose report is not written yet), without ``force`` (docs/models.md, "Activated only if better")."""


def activation_refusal(card: Mapping[str, Any]) -> str | None:
    """Why ``card``'s version may not be activated without force, or None: a plant-retrained version
    (card ``plant_report``) whose report is still pending or says it is not better."""
    rep = card.get("plant_report")
    if not isinstance(rep, dict):
        return None
    if rep.get("pending"):
        return "its plant quality report is not written yet (the retraining did not finish)"
    if rep.get("better") is False:
        failed = (rep.get("decision") or {}).get("failed") or []
        return (f"its quality report on {rep.get('plant', 'its plant')} says it is not better than "
                f"{rep.get('compared_with', 'the active model')}: " + "; ".join(failed))
    return None


@dataclass(frozen=True)
class ModelVersion:
    """One registered version: its name, directory and card."""

    name: str
    path: Path
    card: dict
    active: bool


def _atomic_write_text(path: Path, text: str) -> None:
    fd, tmp = tempfile.mkstemp(dir=path.parent, prefix=f".{path.name}.", suffix=".tmp")
    try:
        with os.fdopen(fd, "w", encoding="utf-8") as fh:
            fh.write(text)
            fh.flush()
            os.fsync(fh.fileno())
        os.chmod(tmp, 0o644)   # mkstemp makes 0600; registries are shared read-only data
        os.replace(tmp, path)
    except BaseException:
        Path(tmp).unlink(missing_ok=True)
        raise


def _json_default(o: Any):
    import numpy as np

    if isinstance(o, np.generic):
        return o.item()
    if isinstance(o, np.ndarray):
        return o.tolist()
    if isinstance(o, Path):
        return str(o)
    raise TypeError(f"not JSON-serialisable: {type(o).__name__}")


def dumps_json(obj: Any) -> str:
    """JSON text used for cards and reports (NumPy scalars/arrays converted)."""
    return json.dumps(obj, indent=2, default=_json_default, allow_nan=True) + "\n"


_SKOPS_LOAD_LOCK = threading.Lock()


def load_model_bytes(data: bytes, name: str = "<bytes>") -> MisalignmentModel:
    """Load a skops model from bytes with the explicit trusted-types list.

    A file written before the ``rotordiag.*`` rename (type names ``models.*``) is mapped
    to the current names first (:mod:`rotordiag.models.legacy`, a fixed table of this
    package's own classes); the trusted-types list is never widened.

    Raises
    ------
    RegistryError
        If the data is not a readable skops file or contains a type outside :data:`TRUSTED_TYPES`.
    """
    import skops.io as sio
    from skops.io.exceptions import UntrustedTypesFoundException

    from .legacy import renamed_skops_bytes

    try:
        data, _ = renamed_skops_bytes(data)
    except Exception as exc:  # noqa: BLE001 - any parse failure is a bad file
        raise RegistryError(f"model file {name} is not a readable skops file ({exc})") from None
    try:
        # skops audits the whole tree against ``trusted`` before constructing anything, so one
        # parse does (checking with get_untrusted_types first parsed the schema twice: ~0.3 s).
        # One load at a time: skops reads its arrays with np.load, whose header parse (ast.literal_eval) is not
        # thread-safe on CPython 3.11.7 — two threads loading at once can fail with "AST constructor recursion
        # depth mismatch" (seen when the service's warm-up and a request loaded the model together).
        with _SKOPS_LOAD_LOCK:
            return sio.loads(data, trusted=list(TRUSTED_TYPES))
    except UntrustedTypesFoundException:
        extra = sorted(set(sio.get_untrusted_types(data=data)) - set(TRUSTED_TYPES))
        raise RegistryError(
            f"model file {name} contains types outside the trusted list: {extra}; refusing to load it"
        ) from None
    except Exception as exc:  # noqa: BLE001 - any parse failure is a bad file
        raise RegistryError(f"model file {name} is not a readable skops file ({exc})") from None


def load_model_file(path: str | Path) -> MisalignmentModel:
    """Load a model file with the explicit trusted-types list (see :func:`load_model_bytes`).

    Raises
    ------
    RegistryError
        If the file is missing, unreadable, or contains a type outside :data:`TRUSTED_TYPES`.
    """
    path = Path(path)
    if not path.is_file():
        raise RegistryError(f"model file {path} does not exist")
    return load_model_bytes(path.read_bytes(), str(path))


class Registry:
    """A directory of model versions with an ``active`` pointer.

    Parameters
    ----------
    root : path
        Registry directory (created on the first :meth:`register`).
    """

    def __init__(self, root: str | Path) -> None:
        self.root = Path(root)

    # ------------------------------------------------------------------ reading
    def versions(self) -> builtins.list[str]:
        """Version names, oldest first."""
        if not self.root.is_dir():
            return []
        names = [p.name for p in self.root.iterdir() if p.is_dir() and _VERSION_RE.match(p.name)]
        return sorted(names, key=_version_number)

    def active_version(self) -> str | None:
        """Name of the active version, or ``None`` when nothing is active."""
        p = self.root / ACTIVE_FILE
        if not p.is_file():
            return None
        name = p.read_text(encoding="utf-8").strip()
        return name or None

    def card(self, version: str) -> dict:
        """The card of ``version``."""
        d = self._version_dir(version)
        try:
            return json.loads((d / CARD_FILE).read_text(encoding="utf-8"))
        except (OSError, json.JSONDecodeError) as exc:
            raise RegistryError(f"version {version}: card.json unreadable ({exc})") from None

    def list(self) -> list[ModelVersion]:
        """All versions with their cards, oldest first."""
        active = self.active_version()
        return [ModelVersion(v, self.root / v, self.card(v), v == active) for v in self.versions()]

    def load(self, version: str | None = None):
        """Load ``version`` (default: the active one); returns ``(model, card)``.

        Raises
        ------
        RegistryError
            No active version, unknown version, or an untrusted/corrupt model file.
        """
        if version is None:
            version = self.active_version()
            if version is None:
                raise RegistryError(
                    f"registry {self.root}: no active model; train one (rotordiag train) or activate a version"
                )
        d = self._version_dir(version)
        return load_model_file(d / MODEL_FILE), self.card(version)

    def _version_dir(self, version: str) -> Path:
        if not _VERSION_RE.match(str(version)):
            raise RegistryError(f"version: {version!r} is not a version name like 'v0001'")
        d = self.root / version
        if not d.is_dir():
            have = ", ".join(self.versions()) or "none"
            raise RegistryError(f"version: {version} is not in registry {self.root} (have: {have})")
        return d

    # ------------------------------------------------------------------ writing
    def register(
        self,
        model,
        card: Mapping[str, Any],
        *,
        extra_files: Mapping[str, bytes | str] | None = None,
        activate: bool = True,
    ) -> str:
        """Store a fitted model as a new version, atomically.

        Parameters
        ----------
        model : fitted MisalignmentModel
        card : mapping
            Card fields; ``version`` and ``created`` (UTC ISO-8601) and
            ``code_version`` (when absent) are filled in here.
        extra_files : mapping name -> content, optional
            More files for the version directory (e.g. ``report.json``, ``report.png``).
        activate : bool, default=True
            Point ``active`` at the new version.

        Returns
        -------
        str
            The new version name.
        """
        import skops.io as sio

        from rotordiag.core.version import code_version

        self.root.mkdir(parents=True, exist_ok=True)
        tmp = Path(tempfile.mkdtemp(dir=self.root, prefix=".incoming-"))
        os.chmod(tmp, 0o755)       # mkdtemp makes 0700
        try:
            # Deflate: a boosted model is thousands of small arrays plus a large JSON schema,
            # which compress ~5-10x.
            sio.dump(model, tmp / MODEL_FILE, compression=zipfile.ZIP_DEFLATED, compresslevel=9)
            untrusted = set(sio.get_untrusted_types(file=tmp / MODEL_FILE)) - set(TRUSTED_TYPES)
            if untrusted:
                raise RegistryError(
                    f"model contains types outside the trusted list {sorted(untrusted)}; "
                    "add them to models.registry.TRUSTED_TYPES only if they are safe to load"
                )
            for name, content in (extra_files or {}).items():
                if "/" in name or name in (MODEL_FILE, CARD_FILE) or name.startswith("."):
                    raise RegistryError(f"extra_files: invalid file name {name!r}")
                mode = "wb" if isinstance(content, bytes) else "w"
                with open(tmp / name, mode) as fh:
                    fh.write(content)
            # Pick the next free name and move in; os.replace refuses a non-empty target,
            # so two writers racing for one name cannot overwrite each other.
            for _ in range(100):
                version = self.next_version()
                full = dict(card)
                full["version"] = version
                full.setdefault("created", datetime.now(UTC).isoformat(timespec="seconds"))
                full.setdefault("code_version", code_version())
                (tmp / CARD_FILE).write_text(dumps_json(full), encoding="utf-8")
                try:
                    os.replace(tmp, self.root / version)
                    break
                except OSError:
                    if (self.root / version).exists():
                        continue
                    raise
            else:  # pragma: no cover - 100 concurrent writers
                raise RegistryError(f"registry {self.root}: could not find a free version name")
        except BaseException:
            shutil.rmtree(tmp, ignore_errors=True)
            raise
        if activate:
            self.activate(version)
        return version

    def next_version(self) -> str:
        """The name the next registered model takes: one above every number this registry has used, in its
        directories and in its activation history, so a name is never given to a second model after its directory
        was deleted (an asset's stored verdicts name the version that answered them)."""
        used = [_version_number(v) for v in self.versions()]
        used += [_version_number(v) for v in self._history() if _VERSION_RE.fullmatch(v)]
        return f"v{max(used, default=0) + 1:04d}"

    def _history(self) -> builtins.list[str]:
        p = self.root / HISTORY_FILE
        if not p.is_file():
            return []
        try:
            h = json.loads(p.read_text(encoding="utf-8"))
        except json.JSONDecodeError as exc:
            raise RegistryError(f"registry {self.root}: {HISTORY_FILE} is corrupt ({exc})") from None
        return [str(v) for v in h]

    def write_file(self, version: str, name: str, content: str | bytes) -> None:
        """Add or replace one extra file of ``version`` (atomically; not the model nor the card)."""
        d = self._version_dir(version)
        if "/" in name or name in (MODEL_FILE, CARD_FILE) or name.startswith("."):
            raise RegistryError(f"write_file: invalid file name {name!r}")
        _atomic_write_text(d / name, content.decode("utf-8") if isinstance(content, bytes) else content)

    def update_card(self, version: str, fields: Mapping[str, Any]) -> dict:
        """Set ``fields`` in ``version``'s card (atomic replace); returns the new card."""
        card = self.card(version)
        card.update(fields)
        _atomic_write_text(self._version_dir(version) / CARD_FILE, dumps_json(card))
        return card

    def activate(self, version: str, *, force: bool = False) -> None:
        """Make ``version`` the active one (recorded in the history for rollback).

        A plant-retrained version whose quality report says it is not better (:func:`activation_refusal`) is
        refused unless ``force``; its card then records ``activated_by: "forced"``.

        Raises
        ------
        ActivationRefused
            Not better on its report and not forced (the message says why).
        """
        self._version_dir(version)
        if self.active_version() == version:
            return
        card = self.card(version)
        why = activation_refusal(card)
        if why is not None and not force:
            raise ActivationRefused(f"version {version} not activated: {why}; activate it anyway with force")
        if "plant_report" in card:
            self.update_card(version, {"activated_by": "forced" if why is not None else "report",
                                       "activated_at": datetime.now(UTC).isoformat(timespec="seconds")})
        history = self._history() + [version]
        _atomic_write_text(self.root / HISTORY_FILE, json.dumps(history) + "\n")
        _atomic_write_text(self.root / ACTIVE_FILE, version + "\n")

    def rollback(self) -> str:
        """Re-activate the version that was active before the current one.

        Returns
        -------
        str
            The version now active.

        Raises
        ------
        RegistryError
            If there is no earlier activation to return to.
        """
        history = self._history()
        current = self.active_version()
        if current is not None and history and history[-1] == current:
            history = history[:-1]
        # Skip versions that were deleted by hand since.
        while history and not (self.root / history[-1]).is_dir():
            history.pop()
        if not history:
            raise RegistryError(f"registry {self.root}: nothing to roll back to (no earlier activation)")
        target = history[-1]
        _atomic_write_text(self.root / HISTORY_FILE, json.dumps(history) + "\n")
        _atomic_write_text(self.root / ACTIVE_FILE, target + "\n")
        return target


def migrate_registry(root: str | Path) -> list[str]:
    """Rewrite every pre-rename model file of a registry to the current type names.

    Each ``vNNNN/model.skops`` holding old names is rewritten, loaded back with the
    trusted-types list, checked to give bit-identical predictions to the in-memory
    mapping on a fixed probe table, and only then put in place with ``os.replace``
    (the old file is kept as ``model.skops.pre-rename``); ``card.json``'s ``model_class``
    is updated likewise. Files already current are left alone.

    Returns
    -------
    list of str
        The versions rewritten.
    """
    import numpy as np

    from .legacy import LEGACY_TYPE_NAMES, renamed_skops_bytes

    migrated = []
    for vdir in sorted(p for p in Path(root).iterdir() if p.is_dir() and (p / MODEL_FILE).is_file()):
        path = vdir / MODEL_FILE
        old = path.read_bytes()
        new, n = renamed_skops_bytes(old)
        if n == 0:
            continue
        reference, rewritten = load_model_bytes(old, str(path)), load_model_bytes(new, str(path))
        probe = np.random.default_rng(0).normal(size=(64, reference.feature_median_.size))
        probe[::7, ::3] = np.nan
        for method in ("predict_proba", "ood_ratio"):
            if not np.array_equal(getattr(reference, method)(probe), getattr(rewritten, method)(probe), equal_nan=True):
                raise ValueError(f"{path}: the rewritten model's {method} differs; left unchanged")
        fd, tmp = tempfile.mkstemp(dir=vdir, prefix=".model.", suffix=".tmp")
        with os.fdopen(fd, "wb") as fh:
            fh.write(new)
            fh.flush()
            os.fsync(fh.fileno())
        os.chmod(tmp, 0o644)
        os.replace(path, vdir / f"{MODEL_FILE}.pre-rename")
        os.replace(tmp, path)
        card_path = vdir / CARD_FILE
        if card_path.is_file():
            card = json.loads(card_path.read_text())
            if card.get("model_class") in LEGACY_TYPE_NAMES:
                card["model_class"] = LEGACY_TYPE_NAMES[card["model_class"]]
                card_path.write_text(json.dumps(card, indent=2) + "\n")
        migrated.append(vdir.name)
    return migrated
