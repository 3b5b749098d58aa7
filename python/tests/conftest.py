"""Shared test set-up: where the shared corpus and the `sinew` binary are."""

import os
import pathlib
import shutil

import pytest

ROOT = pathlib.Path(__file__).resolve().parents[2]


def corpus() -> pathlib.Path:
    path = pathlib.Path(os.environ.get("SINEW_CORPUS", ROOT.parent / "shared" / "corpus"))
    if not (path / "MANIFEST.tsv").is_file():
        if os.environ.get("CI"):
            raise RuntimeError(f"corpus not found at {path} and CI is set")
        pytest.skip(f"corpus not found at {path}")
    return path


def sinew_binary() -> pathlib.Path:
    """The command-line binary the Python results are compared with (built by `cargo build --release
    -p sinew-cli`, or named by SINEW_BIN)."""
    path = pathlib.Path(os.environ.get("SINEW_BIN", ROOT / "target" / "release" / "sinew"))
    if not path.is_file():
        found = shutil.which("sinew")
        if found is None:
            raise RuntimeError(f"no sinew binary at {path}: run `cargo build --release -p sinew-cli`")
        path = pathlib.Path(found)
    return path


@pytest.fixture
def corpus_dir() -> pathlib.Path:
    return corpus()


@pytest.fixture
def sinew_bin() -> pathlib.Path:
    return sinew_binary()
