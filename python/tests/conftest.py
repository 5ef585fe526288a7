"""Shared by the package's tests: the corpus (``ULOG_CORPUS``, default
``../shared/testdata/ulog`` beside the repository), and what CI requires."""

import os
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[2]


PROJECT_CORPUS = ROOT.parent / "shared" / "testdata" / "ulog"


def corpus_dir() -> Path:
    return Path(os.environ.get("ULOG_CORPUS", PROJECT_CORPUS))


def known_log(name: str) -> Path:
    """A file of the project's corpus whose known facts a test checks
    (``pyulog/sample_log_small.ulg``): from ``ULOG_CORPUS`` when it holds the file, else
    from the project's corpus, so that a folder of other logs named by ``ULOG_CORPUS``
    leaves these tests checking what they check. Neither: a failure under CI, else the
    test is skipped, saying why."""
    for d in (corpus_dir(), PROJECT_CORPUS):
        if (d / name).exists():
            return d / name
    why = f"{name} is in neither {corpus_dir()} nor {PROJECT_CORPUS} (set ULOG_CORPUS)"
    if under_ci():
        raise RuntimeError(why)
    pytest.skip(why)


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


def pyulog_start_utc(path):
    """A log's start as UTC text, from pyulog's reading of it (an independent reference for
    ``ulog``'s ``start_utc``): the header's time when it is a date (2000 or later); else the
    earliest row of a GPS dataset (``vehicle_gps_position``/``sensor_gps``) whose
    ``time_utc_usec`` is from 2000 to 2100, less that row's time since the log's start;
    else None."""
    import datetime

    import pyulog

    y2000, y2100 = 946_684_800_000_000, 4_102_444_800_000_000

    def text(us):
        d = datetime.datetime(1970, 1, 1) + datetime.timedelta(microseconds=int(us))
        return d.strftime("%Y-%m-%d %H:%M:%S.%f") + " UTC"

    u = pyulog.ULog(str(path), ["vehicle_gps_position", "sensor_gps"])
    if u.start_timestamp >= y2000:
        return text(u.start_timestamp)
    fixes = []  # each dataset's first fix: (row time, start)
    for d in u.data_list:
        utc = d.data.get("time_utc_usec")
        if utc is None or str(utc.dtype) != "uint64":
            continue
        for ts, t in zip(d.data["timestamp"], utc):
            if y2000 <= int(t) < y2100:
                fixes.append((int(ts), int(t) - max(int(ts) - u.start_timestamp, 0)))
                break
    # The first in the file: rows are written in time order.
    return text(min(fixes)[1]) if fixes else None
