"""Model files written before the ``rotordiag.*`` rename.

Until commit ``bcdd415`` the packages were installed as top-level ``models``, ``service``
etc., so a skops file names its own classes ``models.estimators.MisalignmentModel`` and
``models.bands.SeverityBands``. :func:`renamed_skops_bytes` rewrites exactly those names
(the table :data:`LEGACY_TYPE_NAMES`, nothing by pattern) in the file's ``schema.json``,
in memory, to their current names; the result is then checked against the unchanged
trusted-types list like any other file. ``models.registry.migrate_registry`` rewrites a registry's
files on disk (``rotordiag models migrate``), verifying each rewritten model predicts
exactly what the in-memory mapping does before it replaces the old file.
"""
from __future__ import annotations

import io
import json
import zipfile
from typing import Any

from ._sklearn_private import SKLEARN_RENAMED_TYPES

#: every type name a pre-rename rotordiag model file can hold → the current name
LEGACY_TYPE_NAMES: dict[str, str] = {
    "models.bands.SeverityBands": "rotordiag.core.bands.SeverityBands",
    "models.estimators.ConformalIntervalRegressor": "rotordiag.models.estimators.ConformalIntervalRegressor",
    "models.estimators.KNNDistanceOOD": "rotordiag.models.estimators.KNNDistanceOOD",
    "models.estimators.MisalignmentModel": "rotordiag.models.estimators.MisalignmentModel",
    "models.estimators.SeverityClassifier": "rotordiag.models.estimators.SeverityClassifier",
}
SCHEMA_FILE = "schema.json"
#: every name rewritten on load: the rename's table and scikit-learn 1.8's loss module names
_RENAMES: dict[str, str] = {**LEGACY_TYPE_NAMES, **SKLEARN_RENAMED_TYPES}
#: the old modules as they appear in a schema (``"models.bands"``): a file holding none is left as it is
_OLD_MODULES: tuple[bytes, ...] = tuple(sorted({f'"{name.rsplit(".", 1)[0]}"'.encode() for name in _RENAMES}))


def _rename_nodes(node: Any) -> int:
    """Rewrite ``__module__``/``__class__`` pairs in a skops schema tree in place; count them."""
    n = 0
    if isinstance(node, dict):
        module, cls = node.get("__module__"), node.get("__class__")
        if isinstance(module, str) and isinstance(cls, str):
            new = _RENAMES.get(f"{module}.{cls}")
            if new is not None:
                node["__module__"], node["__class__"] = new.rsplit(".", 1)
                n += 1
        for v in node.values():
            n += _rename_nodes(v)
    elif isinstance(node, list):
        for v in node:
            n += _rename_nodes(v)
    return n


def renamed_skops_bytes(data: bytes) -> tuple[bytes, int]:
    """A skops file's bytes with the pre-rename type names (and scikit-learn 1.8's ``_loss.*``) replaced.

    Parameters
    ----------
    data : bytes
        The skops (zip) file.

    Returns
    -------
    (bytes, int)
        The rewritten file and how many type references were renamed (0: ``data`` unchanged).

    Raises
    ------
    ValueError
        If ``data`` is not a zip archive with a JSON ``schema.json``.
    """
    try:
        with zipfile.ZipFile(io.BytesIO(data)) as zin:
            raw = zin.read(SCHEMA_FILE)
            if not any(module in raw for module in _OLD_MODULES):   # a current file: no parse, no rewrite
                return data, 0
            schema = json.loads(raw)
            n = _rename_nodes(schema)
            if n == 0:
                return data, 0
            out = io.BytesIO()
            with zipfile.ZipFile(out, "w", compression=zipfile.ZIP_DEFLATED) as zout:
                for info in zin.infolist():
                    payload = json.dumps(schema, indent=2).encode() if info.filename == SCHEMA_FILE \
                        else zin.read(info.filename)
                    zout.writestr(info, payload)
    except (zipfile.BadZipFile, KeyError, json.JSONDecodeError) as exc:
        raise ValueError(f"not a skops model file ({exc})") from None
    return out.getvalue(), n
