"""Small example recordings shipped with the package (offline quick-start, tests, the web page).

Made by ``examples/make_example_recordings.sh`` with ``rotordiag simulate --probes-out``: the
MODEL.md plant at 1800 r/min, generator unbalance A = 0.05, pin coupling, 40 dB SNR, 1 µm 1X
runout; 8 probes (b1@45 … b4@135) at 2560 Hz, 1.3 s, µm.

=========================  =====================================================================
``aligned.csv``            Δ = 0: ``time_s`` column (6 significant digits) + ``b2@45``-style header
``misaligned.csv``         Δ = 0.5 (severe), same layout
``misaligned_2560hz.npy``  the same waveforms, (8, n) float32; its sample rate in its sidecar
``misaligned_2560hz.json`` the sidecar of the NPY (``sample_rate_hz``), read by the CLI
``aligned.h5``             Δ = 0 as an HDF5 ``waveforms`` array with its ``channels`` table and attributes
``misaligned.h5``          Δ = 0.5, same
``misaligned.uff``         Δ = 0.5 as a universal file: one binary type-58b time record per probe,
                           ID line 1 ``b2@45``-style, ordinate unit label ``um``
=========================  =====================================================================
"""
from __future__ import annotations

from importlib.resources import files
from pathlib import Path

__all__ = ["example_options", "example_path", "list_examples", "describe_example", "copy_examples"]

_ENDINGS = (".csv", ".npy", ".h5", ".uff")
#: what each example recording is (by file stem) and how its format is written (by ending)
_TITLES = {
    "aligned": "aligned machine (Δ = 0)",
    "misaligned": "severely misaligned (Δ = 0.5)",
    "misaligned_2560hz": "severely misaligned (Δ = 0.5), bare array",
}
_FORMATS = {".csv": "CSV with a time column and b2@45-style header", ".h5": "HDF5 with its channel table",
            ".npy": "NPY, sample rate given separately", ".uff": "universal file (UFF 58b)"}


def list_examples() -> list[str]:
    """Names of the example recordings (sidecars left out)."""
    root = files(__name__)
    return sorted(p.name for p in root.iterdir() if p.name.endswith(_ENDINGS))


def example_path(name: str) -> Path:
    """Path of an example recording.

    Raises
    ------
    ValueError
        For a name that is not one of :func:`list_examples` (the message lists them).
    """
    if name not in list_examples() and name != "misaligned_2560hz.json":
        raise ValueError(f"no example recording {name!r}; the examples are {list_examples()}")
    return Path(str(files(__name__).joinpath(name)))


def example_options(name: str) -> dict[str, object]:
    """What an example needs beyond its file: the reader options of its sidecar ``<stem>.json``.

    The NPY example carries no sample rate; its sidecar says ``{"sample_rate_hz": 2560}`` (the
    CLI reads sidecars itself; the web page and API clients pass these as query parameters).

    Raises
    ------
    ValueError
        For a name that is not one of :func:`list_examples`.
    """
    import json

    path = example_path(name)
    sidecar = path.with_suffix(".json")
    if path.suffix == ".json" or not sidecar.is_file():
        return {}
    return dict(json.loads(sidecar.read_text()))


def describe_example(name: str) -> str:
    """One line on what an example recording is and how it is written (the CLI's and the web page's lists)."""
    path = Path(name)
    return f"{_TITLES.get(path.stem, path.stem)} — {_FORMATS.get(path.suffix, path.suffix)}"


def copy_examples(folder: Path, names: list[str] | None = None) -> list[Path]:
    """Copy example recordings (all, or ``names``) and their sidecars into ``folder`` (made if missing).

    Returns the files written. An existing file of the same name is not overwritten.

    Raises
    ------
    ValueError
        For a name that is not one of :func:`list_examples`, or a file already in ``folder``.
    """
    import shutil

    chosen = list_examples() if not names else list(names)
    for name in chosen:
        example_path(name)                              # names the choices when unknown
    sources = [example_path(n) for n in chosen]
    sources += [p.with_suffix(".json") for p in sources if p.with_suffix(".json").is_file()]
    folder = Path(folder)
    clash = [p.name for p in sources if (folder / p.name).exists()]
    if clash:
        raise ValueError(f"{folder}: {clash} already there; choose another folder or remove them")
    folder.mkdir(parents=True, exist_ok=True)
    return [Path(shutil.copyfile(p, folder / p.name)) for p in sources]
