#!/usr/bin/env python3
"""Checks a log cut to a time window and filtered by topic against pyulog's reading of the
original, independently of the rewriter's code.

Usage: cut_check.py ORIGINAL OUTPUT START_US END_US KEEP EXCLUDE
  START_US, END_US  the window in µs of log time ("-" for none)
  KEEP, EXCLUDE     comma-separated topics ("-" for none)

From pyulog on ORIGINAL, what OUTPUT must hold, as pyulog reads it:
- every kept topic instance's rows of the window (per instance: from its first row at or
  after the start, up to its first row at or after the end), every field bit for bit;
  no other topic instance, and none of a dropped topic;
- the logged and tagged strings whose time is in [start, end);
- the parameter changes in the window (names and values, in order), and as initial
  parameters the original's with every change before the start applied;
- the same info values and the same default parameters.
Prints a JSON summary line; exits 1 naming the first difference.
"""
import contextlib
import io
import json
import sys

import numpy as np
from pyulog.core import ULog


def fail(msg):
    print(msg, file=sys.stderr)
    sys.exit(1)


def read(path):
    with contextlib.redirect_stdout(io.StringIO()):
        return ULog(path)


def window_rows(ts, start, end):
    """Indices of the rows Window::admit takes, in pyulog's terms."""
    out, started = [], False
    for i, t in enumerate(ts):
        t = int(t)
        if not started and start is not None and t < start:
            continue
        if end is not None and t >= end:
            break
        started = True
        out.append(i)
    return out


def same(a, b):
    """Arrays equal bit for bit (NaN equals NaN)."""
    return a.dtype == b.dtype and a.shape == b.shape and a.tobytes() == b.tobytes()


def main():
    original, output, s, e, keep, exclude = sys.argv[1:7]
    start = None if s == '-' else int(s)
    end = None if e == '-' else int(e)
    keep = [] if keep == '-' else keep.split(',')
    exclude = [] if exclude == '-' else exclude.split(',')
    kept = lambda name: (not keep or name in keep) and name not in exclude
    u0, u1 = read(original), read(output)
    if u1.file_corruption:
        fail(f'{output}: pyulog finds it corrupt')
    ours = {(d.name, d.multi_id): d for d in u1.data_list}
    rows = 0
    for d in u0.data_list:
        key = (d.name, d.multi_id)
        take = window_rows(d.data['timestamp'], start, end) if kept(d.name) else []
        if not take:
            if key in ours:
                fail(f'{key}: in the output, but no row of it should be')
            continue
        if key not in ours:
            fail(f'{key}: {len(take)} rows of the window missing')
        got = ours.pop(key)
        for field, values in d.data.items():
            want = values[take]
            if field not in got.data or not same(got.data[field], want):
                fail(f'{key} {field}: differs')
        rows += len(take)
    if ours:
        fail(f'unexpected topic instances: {sorted(ours)}')

    def in_window(t):
        return (start is None or t >= start) and (end is None or t < end)

    logged = lambda u: [(m.log_level, m.timestamp, m.message) for m in u.logged_messages]
    want = [m for m in logged(u0) if in_window(m[1])]
    if logged(u1) != want:
        fail(f'logged strings differ: {logged(u1)[:3]} vs {want[:3]}')
    tagged = lambda u: {tag: [(m.log_level, m.timestamp, m.message) for m in ms]
                        for tag, ms in u.logged_messages_tagged.items()}
    want_tagged = {tag: [m for m in ms if in_window(m[1])] for tag, ms in tagged(u0).items()}
    want_tagged = {k: v for k, v in want_tagged.items() if v}
    if tagged(u1) != want_tagged:
        fail('tagged strings differ')
    changes = [(n, v) for (t, n, v) in u0.changed_parameters if in_window(t)]
    if [(n, v) for (_, n, v) in u1.changed_parameters] != changes:
        fail(f'parameter changes differ: {u1.changed_parameters[:3]} vs {changes[:3]}')
    initial = dict(u0.initial_parameters)
    for (t, n, v) in u0.changed_parameters:
        if start is not None and t < start:
            initial[n] = v
    if u1.initial_parameters != initial:
        diff = {k for k in set(initial) | set(u1.initial_parameters)
                if initial.get(k) != u1.initial_parameters.get(k)}
        fail(f'initial parameters differ: {sorted(diff)[:5]}')
    if u1.msg_info_dict != u0.msg_info_dict:
        fail('info differs')
    for bank in (0, 1):
        if u1.get_default_parameters(bank) != u0.get_default_parameters(bank):
            fail(f'default parameters ({bank}) differ')
    print(json.dumps({'rows': rows, 'logged': len(want), 'changes': len(changes),
                      'instances': sum(1 for d in u1.data_list)}))


if __name__ == '__main__':
    main()
