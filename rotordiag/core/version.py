"""The code version recorded in datasets, model cards and service answers."""
from __future__ import annotations

import functools
import hashlib
import subprocess
from importlib import metadata
from pathlib import Path

try:
    __version__: str = metadata.version("rotordiag")
except metadata.PackageNotFoundError:  # running from a checkout that is not installed
    __version__ = "0.1.0"


def _checkout_root() -> Path | None:
    """The repository root when this code runs from a source checkout, else ``None``.

    An installed wheel lives in ``site-packages/rotordiag``; its parent is no checkout
    even when the virtual environment itself sits inside some git repository.
    """
    root = Path(__file__).resolve().parents[2]
    markers = ("pyproject.toml", "simulator", "features", "models", "service")
    return root if all((root / m).exists() for m in markers) else None


@functools.cache
def code_version() -> str:
    """Package version plus the git commit when run from a checkout.

    Returns
    -------
    str
        ``"0.1.0"`` or ``"0.1.0+g<short-sha>"`` (``".dirty"`` appended when the
        work tree has uncommitted changes). Recorded in datasets and model cards.
    """
    root = _checkout_root()
    if root is None:
        return __version__
    try:
        sha = subprocess.run(
            ["git", "-C", str(root), "rev-parse", "--short=10", "HEAD"],
            capture_output=True, text=True, timeout=5, check=True,
        ).stdout.strip()
        dirty = subprocess.run(
            ["git", "-C", str(root), "status", "--porcelain", "--untracked-files=no"],
            capture_output=True, text=True, timeout=5, check=True,
        ).stdout.strip()
    except (OSError, subprocess.SubprocessError):
        return __version__
    return f"{__version__}+g{sha}" + (".dirty" if dirty else "")


def source_hash(package_dir: Path) -> str:
    """SHA-256 of every ``*.py`` file under ``package_dir`` (names and contents, sorted): what a cache of a
    package's results depends on, so that a changed simulator or extractor never serves results of the old code."""
    h = hashlib.sha256()
    for p in sorted(Path(package_dir).rglob("*.py")):
        h.update(p.relative_to(package_dir).as_posix().encode())
        h.update(p.read_bytes())
    return h.hexdigest()
