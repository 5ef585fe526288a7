#!/usr/bin/env python3
"""Runs many pyulog tool invocations in one Python process, as their console scripts do.

Input (stdin): a JSON list of {"module": "params", "args": ["file.ulg", "-f", "qgc"]}.
Output (stdout): a JSON list, one {"status": N, "stdout": "...", "stderr": "..."} per
invocation. Each log is parsed once per (file, message filter, ignore flag): the ULog
object is reused, and what pyulog printed while parsing it is printed again, so every
invocation's output is what its console script alone would print.
"""
import contextlib
import importlib
import io
import json
import sys
import traceback

import pyulog.core
import pyulog.px4_events


def _offline(_already_has_default_parser):
    """For a PX4 log with events but no events metadata of its own, pyulog downloads PX4's
    current definitions: the tests never do, so that pyulog's output does not depend on the
    network (or on what PX4 publishes that day)."""
    raise OSError('offline: the tests do not download event definitions')


pyulog.px4_events.PX4Events._get_default_json_definitions = staticmethod(_offline)  # pylint: disable=protected-access

_REAL_ULOG = pyulog.core.ULog
_CACHE = {}


def _cached_ulog(log_file, message_name_filter_list=None, disable_str_exceptions=True,
                 *args, **kwargs):
    key = (log_file, None if message_name_filter_list is None
           else tuple(message_name_filter_list), bool(disable_str_exceptions), args,
           tuple(sorted(kwargs.items())))
    if key not in _CACHE:
        printed = io.StringIO()
        try:
            with contextlib.redirect_stdout(printed):
                ulog = _REAL_ULOG(log_file, message_name_filter_list, disable_str_exceptions,
                                  *args, **kwargs)
            _CACHE[key] = (ulog, printed.getvalue(), None)
        except Exception as e:  # replayed on every call, as a fresh parse would raise
            _CACHE[key] = (None, printed.getvalue(), e)
    ulog, printed, error = _CACHE[key]
    sys.stdout.write(printed)
    if error is not None:
        raise error
    return ulog


def run(module, args):
    mod = importlib.import_module('pyulog.' + module)
    if module == 'ulog2kml':
        # simplekml numbers its elements from a process-wide counter: start it as a fresh
        # process does.
        import simplekml.base  # pylint: disable=import-outside-toplevel
        simplekml.base.Kmlable._globalid = 0  # pylint: disable=protected-access
    mod.ULog = _cached_ulog
    out, err = io.StringIO(), io.StringIO()
    status = 0
    sys.argv = [module] + args
    with contextlib.redirect_stdout(out), contextlib.redirect_stderr(err):
        try:
            mod.main()
        except SystemExit as e:
            status = e.code if isinstance(e.code, int) else (0 if e.code is None else 1)
        except Exception:  # pylint: disable=broad-except
            traceback.print_exc()
            status = 1
    return {'status': status,
            'stdout': out.getvalue(),
            'stderr': err.getvalue()}


if __name__ == '__main__':
    runs = json.load(sys.stdin)
    print(json.dumps([run(r['module'], r['args']) for r in runs]))
