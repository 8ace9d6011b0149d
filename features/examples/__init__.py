"""Small example recordings shipped with the package (offline quick-start, tests, the web page).

Made by ``examples/make_example_recordings.sh`` with ``rotordiag simulate --probes-out`` (seed 1): the MODEL.md
plant at 1800 r/min, generator unbalance A = 0.05, 40 dB SNR, 1 µm 1X runout; 8 probes (b1@45 … b4@135) at
2560 Hz, 1.3 s, µm. One clean, steady (period-1) recording of each state the verdict names — its sidecar
``<name>.json`` gives the bearing clearance (350 µm), and the shipped model answers each with its band (the
misaligned ones confident; the aligned one uncertain with v0002, its Δ interval reaching moderate) — and one
oil-whirl recording, labelled as such, in every reader format.

=========================  =====================================================================
``aligned.csv`` / ``.h5``  Δ = 0 (rigid coupling), CSV with a ``time_s`` column and ``b2@45``-style header /
                           HDF5 ``waveforms`` array with its ``channels`` table
``slight.csv``             Δ = 0.10
``moderate.csv``           Δ = 0.25
``severe.csv``             Δ = 0.45
``whirl.csv`` / ``.h5``    oil whirl: a pin coupling at Δ = 0.5 runs quasi-periodic, a 0.38X whirl dominating the
                           orbit — the verdict says to investigate the whirl first, not to realign
``whirl.uff``              the same as a universal file: one binary type-58b record per probe
``whirl_2560hz.npy``       the same waveforms, (8, n) float32; its sample rate in its sidecar ``.json``
=========================  =====================================================================
"""
from __future__ import annotations

from importlib.resources import files
from pathlib import Path

__all__ = ["example_options", "example_path", "list_examples", "describe_example", "copy_examples"]

_ENDINGS = (".csv", ".npy", ".h5", ".uff")
#: what each example recording is (by file stem) and how its format is written (by ending)
_TITLES = {
    "aligned": "aligned (Δ = 0), steady",
    "slight": "slight misalignment (Δ = 0.10), steady",
    "moderate": "moderate misalignment (Δ = 0.25), steady",
    "severe": "severe misalignment (Δ = 0.45), steady",
    "whirl": "oil whirl (0.38X, quasi-periodic) on a misaligned train: investigate the whirl first",
    "whirl_2560hz": "oil whirl, bare array",
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
    if name not in list_examples() and not (name.endswith(".json") and files(__name__).joinpath(name).is_file()):
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
