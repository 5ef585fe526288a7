#!/usr/bin/env python3
"""pyulog's figures for the `scan` example, computed independently of this project's code.

Usage: scan_reference.py FILE.ulg [FILE.ulg ...]
Prints one JSON object per file:
  {"file": ..., "sha256": ..., "msgs": N, "leaves": L, "sum": S,
   "topics": [[name, multi_id, rows, sum], ...]}
N counts rows, L the non-padding leaf values (every array element, nested fields included),
S the sum of the finite leaf values as float64, with bool as 0/1 and char as int8.
"""
import contextlib
import hashlib
import json
import sys

import numpy as np
from pyulog.core import ULog


def is_padding(field_name):
    return any(part.split('[')[0].startswith('_padding') for part in field_name.split('.'))


def figures(path):
    with contextlib.redirect_stdout(sys.stderr):  # pyulog prints warnings
        ulog = ULog(path)
    msgs = leaves = 0
    total = 0.0
    topics = []
    for d in ulog.data_list:
        n = len(d.data['timestamp'])
        topic_sum = 0.0
        for f in d.field_data:
            if is_padding(f.field_name):
                continue
            col = d.data[f.field_name]
            if f.type_str == 'bool':
                col = (col != 0).astype(np.float64)
            else:
                col = col.astype(np.float64)
            leaves += n
            topic_sum += float(np.sum(col[np.isfinite(col)], dtype=np.float64))
        msgs += n
        total += topic_sum
        topics.append([d.name, int(d.multi_id), n, topic_sum])
    with open(path, 'rb') as fh:
        sha = hashlib.sha256(fh.read()).hexdigest()
    return {"file": path, "sha256": sha, "msgs": msgs, "leaves": leaves, "sum": total,
            "topics": topics}


def main():
    for p in sys.argv[1:]:
        print(json.dumps(figures(p)))


if __name__ == '__main__':
    main()
