"""Shared by the package's tests: the corpus (``ULOG_CORPUS``, default
``../shared/testdata/ulog`` beside the repository), and what CI requires."""

import os
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[2]


def corpus_dir() -> Path:
    return Path(os.environ.get("ULOG_CORPUS", ROOT.parent / "shared" / "testdata" / "ulog"))


def under_ci() -> bool:
    return os.environ.get("CI") in ("true", "1")


def corpus_files():
    files = sorted(p for p in corpus_dir().rglob("*.ulg"))
    if not files:
        if under_ci():
            raise RuntimeError(f"no .ulg files under {corpus_dir()} (set ULOG_CORPUS)")
    return files


def log_id(path: Path) -> str:
    return f"{path.parent.name}/{path.name}"


def pytest_generate_tests(metafunc):
    if "corpus_log" in metafunc.fixturenames:
        files = corpus_files()
        metafunc.parametrize("corpus_log", files, ids=[log_id(f) for f in files])


@pytest.fixture
def fuzz_regressions() -> Path:
    return ROOT / "tests" / "fuzz_regressions"
