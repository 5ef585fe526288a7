#!/usr/bin/env python3
"""Queries a fleet converted by `ulog parquet --layout hive` with DuckDB, and checks the
answers against pyulog.

Usage: fleet_check.py DIR LOG...

1. One SQL statement over all logs (hive partitions `log` and `multi_id` as columns): per
   log and instance of vehicle_attitude, rows, first and last timestamp and mean q[0]; the
   same computed from pyulog's reading of each log.
2. A topic whose fields differ between the logs (PX4 versions) reads as one table with
   union_by_name: its columns are the union of every log's (and the partition columns
   topic, log, multi_id), and each log's row count is pyulog's.
Prints one JSON summary line; exits 1 with the first difference.
"""
import contextlib
import io
import json
import os
import re
import sys

import duckdb
import numpy as np
from pyulog.core import ULog


def fail(msg):
    print(msg, file=sys.stderr)
    sys.exit(1)


def stem(path):
    name = os.path.basename(path)
    return name[:-4] if name.lower().endswith('.ulg') else name


def columns_of(d):
    """Our column names for a pyulog dataset: padding out, char arrays as one column."""
    out = []
    for f in d.field_data:
        if any(p.startswith('_padding') for p in f.field_name.split('.')):
            continue
        m = re.match(r'^(.*)\[(\d+)\]$', f.field_name)
        if f.type_str == 'char' and m:
            if m.group(2) == '0':
                out.append(m.group(1))
            continue
        out.append(f.field_name)
    return out


def main(root, logs):
    con = duckdb.connect()
    with contextlib.redirect_stdout(io.StringIO()):  # pyulog's warnings
        ulogs = {stem(p): ULog(p) for p in logs}
    glob = lambda topic: os.path.join(root, f'topic={topic}', '*', '*', '*.parquet')

    # 1. A per-log aggregate over one topic, in one statement.
    got = con.execute(f"""
        SELECT log, multi_id, count(*), min(timestamp), max(timestamp), avg("q[0]")
        FROM read_parquet('{glob('vehicle_attitude')}', hive_partitioning = true,
                          union_by_name = true)
        GROUP BY log, multi_id ORDER BY log, multi_id""").fetchall()
    want = []
    for name in sorted(ulogs):
        for d in sorted(ulogs[name].data_list, key=lambda d: d.multi_id):
            if d.name != 'vehicle_attitude':
                continue
            ts = d.data['timestamp']
            q0 = d.data['q[0]'].astype(np.float64)
            want.append((name, d.multi_id, len(ts), int(ts.min()), int(ts.max()),
                         float(np.mean(q0))))
    if len(got) != len(want) or len(want) < 2:
        fail(f'vehicle_attitude: duckdb has {len(got)} instances, pyulog {len(want)} (need 2+)')
    for g, w in zip(sorted(got), sorted(want)):
        same = (g[0] == w[0] and g[1] == w[1] and g[2:5] == w[2:5]
                and (abs(g[5] - w[5]) <= 1e-9 * max(1.0, abs(w[5]))
                     or (np.isnan(g[5]) and np.isnan(w[5]))))
        if not same:
            fail(f'vehicle_attitude: duckdb {g}, pyulog {w}')

    # 2. A topic whose fields differ between logs reads as one table.
    shapes = {}
    for name, u in ulogs.items():
        for d in u.data_list:
            shapes.setdefault(d.name, {})[name] = columns_of(d)
    differing = sorted(t for t, per_log in shapes.items()
                       if len({tuple(c) for c in per_log.values()}) > 1 and len(per_log) > 1)
    if not differing:
        fail('no topic whose fields differ between these logs')
    checked = 0
    for topic in differing:
        # DuckDB's names are case-insensitive: voltage5V_v and voltage5v_v are one column.
        union = {'topic', 'log', 'multi_id'}
        for cols in shapes[topic].values():
            union.update(c.lower() for c in cols)
        rel = f"read_parquet('{glob(topic)}', hive_partitioning = true, union_by_name = true)"
        names = {c[0].lower() for c in con.execute(f'DESCRIBE SELECT * FROM {rel}').fetchall()}
        if names != union:
            fail(f'{topic}: union_by_name columns {sorted(names ^ union)} differ')
        counts = dict(((l, m), n) for l, m, n in con.execute(
            f'SELECT log, multi_id, count(*) FROM {rel} GROUP BY ALL').fetchall())
        for name, u in ulogs.items():
            for d in u.data_list:
                if d.name == topic and counts.get((name, d.multi_id)) != len(d.data['timestamp']):
                    fail(f'{topic} {name} #{d.multi_id}: duckdb {counts.get((name, d.multi_id))} '
                         f'rows, pyulog {len(d.data["timestamp"])}')
        checked += 1
    print(json.dumps({'logs': len(ulogs), 'attitude_instances': len(got),
                      'topics_with_differing_fields': checked}))


if __name__ == '__main__':
    main(sys.argv[1], sys.argv[2:])
