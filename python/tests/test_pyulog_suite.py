"""pyulog's own test suite (its 1.3.0 source distribution, downloaded from PyPI, never kept
in this repository) run with every ``ULog`` of pyulog's modules replaced by ``ulog.ULog``:
pyulog's tools (info, messages, params, ulog2csv, extract_message, gps dump, PX4ULog,
PX4Events, the database) must give pyulog's expected outputs on our objects. The corpus
supplies its sample logs; the tests of the two samples the corpus lacks are left out (and
listed)."""

import os
import subprocess
import sys
import tarfile
from pathlib import Path

import pytest

from conftest import PROJECT_CORPUS, corpus_dir, under_ci

# Installs ulog.ULog in pyulog before any test module (or pyulog.db) is imported; the
# original constructor fails loudly, so an unpatched call site cannot pass unnoticed.
PATCH = '''
import importlib
import sys

import pyulog
import pyulog.core
import pyulog.exceptions
import ulog

assert "pyulog.db" not in sys.modules
ORIGINAL = pyulog.core.ULog
for module in (pyulog, pyulog.core):
    module.ULog = ulog.ULog
for module in (pyulog, pyulog.core, pyulog.exceptions):
    module.ULogException = ulog.ULogException
    module.ULogIncompatibleFlagException = ulog.ULogIncompatibleFlagException
for name in ("info", "messages", "params", "ulog2csv", "extract_message",
             "extract_gps_dump", "px4_events"):
    importlib.import_module("pyulog." + name).ULog = ulog.ULog
import pyulog.db
assert pyulog.db.DatabaseULog.__mro__[1] is ulog.ULog


def _unpatched(self, *args, **kwargs):
    raise AssertionError("pyulog's own ULog was constructed")


ORIGINAL.__init__ = _unpatched
'''

SAMPLES = ["sample", "sample_appended", "sample_appended_multiple", "sample_log_small",
           "sample_px4_events", "sample_logging_tagged_and_default_params"]


def sdist(work: Path) -> Path:
    cache = Path(os.environ.get("ULOG_PYULOG_SDIST", work))
    found = sorted(cache.glob("pyulog-1.3.0.tar.gz"))
    if not found:
        run = subprocess.run(
            [sys.executable, "-m", "pip", "download", "--quiet", "--no-deps",
             "--no-binary", ":all:", "pyulog==1.3.0", "-d", str(work)],
            capture_output=True, text=True)
        if run.returncode != 0:
            if under_ci():
                pytest.fail(f"pyulog's sdist could not be downloaded: {run.stderr}")
            pytest.skip("pyulog's sdist could not be downloaded (offline?)")
        found = sorted(work.glob("pyulog-1.3.0.tar.gz"))
    return found[0]


def test_pyulogs_suite_passes_on_ulog_ULog(tmp_path):
    archive = sdist(tmp_path)
    with tarfile.open(archive) as tar:
        members = [m for m in tar.getmembers() if "/test/" in m.name + "/"]
        tar.extractall(tmp_path, members=members, filter="data")
    test_dir = next(tmp_path.glob("pyulog-1.3.0/test"))
    # pyulog's sample logs: the project corpus's (which lacks two of them), and those it
    # lacks from ULOG_CORPUS when that folder has them.
    logs = {p.stem: p for d in (corpus_dir(), PROJECT_CORPUS) if d.exists() for p in d.rglob("*.ulg")}
    missing = [s for s in SAMPLES if s not in logs]
    for s in SAMPLES:
        if s in logs:
            (test_dir / f"{s}.ulg").symlink_to(logs[s])
    (test_dir / "conftest.py").write_text(PATCH)
    env = dict(os.environ, TMPDIR=str(tmp_path), PATH=os.path.dirname(sys.executable) + os.pathsep + os.environ["PATH"])
    collect = subprocess.run(
        [sys.executable, "-m", "pytest", "--collect-only", "-q", "-p", "no:cacheprovider", "test"],
        cwd=test_dir.parent, capture_output=True, text=True, env=env)
    ids = [l for l in collect.stdout.splitlines() if "::" in l]
    assert len(ids) >= 58, collect.stdout + collect.stderr
    # ddt names end with the sample's name.
    left_out = [i for i in ids if any(i.endswith("_" + m) for m in missing)]
    args = [sys.executable, "-m", "pytest", "-q", "-p", "no:cacheprovider", "test"]
    for i in left_out:
        args += ["--deselect", i]
    run = subprocess.run(args, cwd=test_dir.parent, capture_output=True, text=True, env=env)
    summary = run.stdout.strip().splitlines()[-1] if run.stdout.strip() else run.stderr
    print(f"pyulog's suite on ulog.ULog: {summary}; left out (samples the corpus lacks: "
          f"{', '.join(missing) or 'none'}): {len(left_out)}")
    assert run.returncode == 0, run.stdout[-6000:] + run.stderr[-2000:]
    assert "failed" not in summary and "error" not in summary, summary
    passed = int(summary.split(" passed")[0].split()[-1])
    assert passed + len(left_out) + 1 >= len(ids), summary
