#!/usr/bin/env python3
"""Every value pyulog reads from one file, independently of this project's code.

Usage: dump_values.py FILE.ulg
Prints one JSON object: {"sha256": ..., "printed": what pyulog printed,
  "data": {"<topic>/<multi_id>": {"<column>": [every row's value, ...]}},
  "info": {key: value}, "info_multiple": {key: [[part, ...], ...]},
  "initial_parameters": {name: value}, "changed_parameters": [[timestamp, name, value], ...],
  "default_parameters": {"<bit>": {name: value}},
  "logged_messages": [[level, timestamp, text], ...],
  "logged_messages_tagged": {tag: [[level, timestamp, text], ...]},
  "dropouts": [duration_ms, ...]}
Floats are the exact double of the stored value; NaN and infinities are the strings
"NaN", "Infinity" and "-Infinity"; bool and char columns are pyulog's int8.
"""
import contextlib
import hashlib
import io
import json
import math
import sys

from pyulog.core import ULog


def plain(v):
    if hasattr(v, 'tolist'):
        v = v.tolist()
    if isinstance(v, float):
        if math.isnan(v):
            return "NaN"
        if math.isinf(v):
            return "Infinity" if v > 0 else "-Infinity"
    if isinstance(v, list):
        return [plain(x) for x in v]
    if isinstance(v, bytes):
        return {"hex": v.hex()}
    return v


def dump(path):
    printed = io.StringIO()
    with contextlib.redirect_stdout(printed):
        ulog = ULog(path)
    data = {}
    for d in ulog.data_list:
        data[f"{d.name}/{d.multi_id}"] = {k: plain(col) for k, col in d.data.items()}
    with open(path, 'rb') as f:
        sha = hashlib.sha256(f.read()).hexdigest()
    return {
        "sha256": sha,
        "printed": printed.getvalue(),
        "data": data,
        "info": {k: plain(v) for k, v in ulog.msg_info_dict.items()},
        "info_multiple": {k: plain(v) for k, v in ulog.msg_info_multiple_dict.items()},
        "initial_parameters": {k: plain(v) for k, v in ulog.initial_parameters.items()},
        "changed_parameters": [[t, n, plain(v)] for t, n, v in ulog.changed_parameters],
        "default_parameters": {str(bit): {n: plain(v)
                                          for n, v in ulog.get_default_parameters(bit).items()}
                               for bit in (0, 1)},
        "logged_messages": [[m.log_level, m.timestamp, m.message] for m in ulog.logged_messages],
        "logged_messages_tagged": {str(tag): [[m.log_level, m.timestamp, m.message] for m in ms]
                                   for tag, ms in ulog.logged_messages_tagged.items()},
        "dropouts": [d.duration for d in ulog.dropouts],
    }


if __name__ == '__main__':
    json.dump(dump(sys.argv[1]), sys.stdout, sort_keys=True)
    print()
