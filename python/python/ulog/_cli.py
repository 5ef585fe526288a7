"""The ``ulog`` command-line tool, as the package installs it."""

import signal
import sys
import threading


def main() -> None:
    """Runs ``ulog`` with the process's arguments and exits with its code."""
    from . import _ulog

    # As the native `ulog`: Ctrl-C ends the tool (`ulog parquet` sets its own handler, and
    # finishes the logs under way). Python's handler would run only when the Rust tool
    # returned, after every log of a long run.
    if threading.current_thread() is threading.main_thread():
        signal.signal(signal.SIGINT, signal.SIG_DFL)
    sys.stdout.flush()
    sys.exit(_ulog.cli_main(["ulog"] + sys.argv[1:]))
