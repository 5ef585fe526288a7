"""The ``ulog`` command-line tool, as the package installs it."""

import sys


def main() -> None:
    """Runs ``ulog`` with the process's arguments and exits with its code."""
    from . import _ulog

    sys.stdout.flush()
    sys.exit(_ulog.cli_main(["ulog"] + sys.argv[1:]))
