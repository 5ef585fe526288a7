"""The ``ulog`` command-line tool, as the package installs it."""

import signal
import sys
import threading


def main() -> None:
    """Runs ``ulog`` with the process's arguments and exits with its code."""
    from . import _ulog

    # The process is the tool: Ctrl-C and SIGTERM stop it as they stop the Rust binary
    # (`ulog parquet` finishes the logs under way and exits 130; the other verbs end at
    # once). Python's own handler would run only once the tool returned, after every log of
    # a long run, and then end it with a traceback.
    main_thread = threading.current_thread() is threading.main_thread()
    if main_thread:
        signal.signal(signal.SIGINT, signal.SIG_DFL)
    sys.stdout.flush()
    sys.exit(_ulog.cli_main(["ulog"] + sys.argv[1:], as_process=main_thread))
