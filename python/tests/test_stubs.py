"""The package's types: mypy's stubtest holds the native module's stub (``_ulog.pyi``) and
the typed Python modules to what the package has at run time (every public name typed,
each signature as it is), and mypy finds no error in the package itself."""

import subprocess
import sys
from pathlib import Path

HERE = Path(__file__).resolve().parent


def test_the_stubs_type_everything_the_package_has(tmp_path):
    out = subprocess.run(
        [
            sys.executable,
            "-m",
            "mypy.stubtest",
            "ulog",
            "--mypy-config-file",
            str(HERE.parent / "pyproject.toml"),
            "--allowlist",
            str(HERE / "stubtest_allowlist.txt"),
        ],
        # mypy's cache goes to the working folder, not the sources.
        cwd=tmp_path,
        capture_output=True,
        text=True,
        timeout=600,
    )
    assert out.returncode == 0, out.stdout[-6000:] + out.stderr[-2000:]
