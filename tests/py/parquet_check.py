#!/usr/bin/env python3
"""Checks a `ulog parquet` conversion of one log against pyulog, read with pyarrow.

Usage: parquet_check.py LOG DIR HIDDEN.json
  DIR          the log's folder of the conversion (<topic>_<multi_id>.parquet, metadata.json)
  HIDDEN.json  {"<topic>/<multi_id>": [indices of rows of ours that pyulog cannot see]}
               (pyulog resumes after damage only at a sync magic; those rows are set aside)

Independently of the converter's code, from pyulog's reading of LOG:
- the files: one per topic instance pyulog has, named <topic>_<multi_id>.parquet;
- the columns: pyulog's fields in order with `timestamp` first, padding left out, each
  char[N] array one text column; their Arrow types from the ULog types;
- every value: floats bit for bit, bool as pyulog's byte != 0, text as ulog2csv shows it;
- each file's key-value metadata: sha256 of LOG, its file name, sys_name/ver_sw/ver_hw,
  header start, topic, multi_id, format string;
- metadata.json: info, initial and changed parameters, logged messages, dropouts, row counts.
Prints one JSON summary line; exits 1 naming the log, file, column and row of a difference.
"""
import contextlib
import hashlib
import io
import json
import os
import re
import sys

import numpy as np
import pyarrow.parquet as pq
from pyulog.core import ULog

ARROW = {
    'int8_t': 'int8', 'uint8_t': 'uint8', 'int16_t': 'int16', 'uint16_t': 'uint16',
    'int32_t': 'int32', 'uint32_t': 'uint32', 'int64_t': 'int64', 'uint64_t': 'uint64',
    'float': 'float', 'double': 'double', 'bool': 'bool', 'char': 'int8',
}


def component(name):
    """A name as a file name part: A-Z a-z 0-9 _ - kept, / as _, other bytes as %XX."""
    out = []
    for b in name.encode('utf-8'):
        c = chr(b)
        if c.isascii() and (c.isalnum() or c in '_-'):
            out.append(c)
        elif c == '/':
            out.append('_')
        else:
            out.append('%%%02X' % b)
    return ''.join(out)


def fail(msg):
    print(msg, file=sys.stderr)
    sys.exit(1)


def expected_columns(d):
    """(name, arrow type, [pyulog fields]) in our order: timestamp, then the fields."""
    cols = []
    fields = [f for f in d.field_data
              if not any(p.startswith('_padding') for p in f.field_name.split('.'))]
    i = 0
    while i < len(fields):
        f = fields[i]
        m = re.match(r'^(.*)\[0\]$', f.field_name)
        if f.type_str == 'char' and m:
            base = m.group(1)
            group = [f.field_name]
            k = 1
            while i + k < len(fields) and fields[i + k].field_name == f'{base}[{k}]':
                group.append(fields[i + k].field_name)
                k += 1
            cols.append((base, 'string', group))
            i += k
            continue
        t = 'uint64' if f.field_name == 'timestamp' else ARROW[f.type_str]
        cols.append((f.field_name, t, [f.field_name]))
        i += 1
    ts = [c for c in cols if c[0] == 'timestamp']
    return ts + [c for c in cols if c[0] != 'timestamp']


def text_of(d, group, rows):
    out = []
    arrays = [d.data[g] for g in group]
    for r in rows:
        s = ''
        for a in arrays:
            c = int(a[r]) & 0xff
            if c == 0:
                break
            s += chr(c)
        out.append(s)
    return out


def format_string(ulog, name):
    f = ulog.message_formats[name]
    parts = []
    for type_str, array_size, field in f.fields:
        t = f'{type_str}[{array_size}]' if array_size > 1 else type_str
        parts.append(f'{t} {field};')
    return f'{name}:' + ''.join(parts)


def check(log, folder, hidden):
    with contextlib.redirect_stdout(io.StringIO()):  # pyulog's warnings
        ulog = ULog(log)
    label = os.path.basename(log)
    with open(log, 'rb') as f:
        sha = hashlib.sha256(f.read()).hexdigest()
    ours = {n for n in os.listdir(folder) if n.endswith('.parquet')}
    if any(n.endswith('.partial') for n in os.listdir(folder)):
        fail(f'{label}: a .partial file was left behind')
    theirs = {}
    for d in ulog.data_list:
        name = f'{component(d.name)}_{d.multi_id}.parquet'
        if name in theirs:
            fail(f'{label}: pyulog has two datasets of {d.name} #{d.multi_id}')
        theirs[name] = d
    missing = set(theirs) - ours
    if missing:
        fail(f'{label}: no Parquet file for {sorted(missing)}')
    cells = rows_total = 0
    for name in sorted(ours):
        path = os.path.join(folder, name)
        pf = pq.ParquetFile(path)
        kv = {k.decode(): v.decode() for k, v in pf.metadata.metadata.items()}
        table = pf.read()
        d = theirs.get(name)
        key = None
        if d is None:
            # An instance pyulog does not have: every row of it must be one pyulog cannot see.
            key = f"{kv['ulog.topic']}/{kv['ulog.multi_id']}"
            if len(hidden.get(key, [])) != table.num_rows:
                fail(f'{label}: {name}: {table.num_rows} rows pyulog does not have')
            continue
        key = f'{d.name}/{d.multi_id}'
        where = f'{label}: {name}'
        want_kv = {
            'ulog.file_name': os.path.basename(log),
            'ulog.sha256': sha,
            'ulog.topic': d.name,
            'ulog.multi_id': str(d.multi_id),
            'ulog.start_timestamp': str(ulog.start_timestamp),
            'ulog.format': format_string(ulog, d.name),
        }
        for info in ('sys_name', 'ver_sw', 'ver_hw'):
            if isinstance(ulog.msg_info_dict.get(info), str):
                want_kv[f'ulog.{info}'] = ulog.msg_info_dict[info]
        # pyulog keeps no difference between `uint8_t[1] x` and `uint8_t x`.
        got_format = re.sub(r'\[1\] ', ' ', kv.get('ulog.format', ''))
        for k, v in want_kv.items():
            if (got_format if k == 'ulog.format' else kv.get(k)) != v:
                fail(f'{where}: key-value metadata {k} is {kv.get(k)!r}, expected {v!r}')
        cols = expected_columns(d)
        names = [c[0] for c in cols]
        if table.column_names != names:
            fail(f'{where}: columns {table.column_names}, pyulog has {names}')
        drop = set(hidden.get(key, []))
        keep = np.array([i for i in range(table.num_rows) if i not in drop], dtype=np.int64)
        n = len(d.data['timestamp'])
        if len(keep) != n:
            fail(f'{where}: {len(keep)} rows, pyulog has {n}')
        rows_total += n
        for (col, arrow_type, group), field in zip(cols, table.schema):
            if str(field.type) != arrow_type:
                fail(f'{where}: column {col} is {field.type}, expected {arrow_type}')
            mine = table.column(col).to_numpy(zero_copy_only=False)[keep]
            if arrow_type == 'string':
                want = text_of(d, group, range(n))
                for i, (a, b) in enumerate(zip(mine, want)):
                    if a != b:
                        fail(f'{where}: column {col} row {i}: {a!r}, pyulog {b!r}')
                cells += n
                continue
            want = d.data[group[0]]
            if arrow_type == 'bool':
                same = mine == (want != 0)
            elif arrow_type in ('float', 'double'):
                bits = np.uint32 if arrow_type == 'float' else np.uint64
                same = mine.view(bits) == want.astype(mine.dtype).view(bits)
            else:
                same = mine.astype(np.int64 if arrow_type != 'uint64' else np.uint64) == \
                    want.astype(np.int64 if arrow_type != 'uint64' else np.uint64)
            if not np.all(same):
                i = int(np.argmin(same))
                fail(f'{where}: column {col} row {i}: {mine[i]!r}, pyulog {want[i]!r}')
            cells += n
    check_metadata(ulog, label, os.path.join(folder, 'metadata.json'), theirs, hidden, sha)
    return {'files': len(ours), 'rows': rows_total, 'cells': cells}


def same_number(a, b):
    if isinstance(b, float) or isinstance(a, float):
        if a is None:
            return np.isnan(b)
        return np.float32(a) == np.float32(b) or (np.isnan(a) and np.isnan(b))
    return a == b


def check_metadata(ulog, label, path, theirs, hidden, sha):
    with open(path) as f:
        meta = json.load(f)
    where = f'{label}: metadata.json'
    if meta['log']['sha256'] != sha:
        fail(f'{where}: sha256')
    if meta['start_timestamp'] != ulog.start_timestamp:
        fail(f'{where}: start_timestamp {meta["start_timestamp"]}, pyulog {ulog.start_timestamp}')
    for k, v in ulog.msg_info_dict.items():
        if isinstance(v, (str, int)) and meta['info'].get(k) != v:
            fail(f'{where}: info {k} is {meta["info"].get(k)!r}, pyulog {v!r}')
    for k, v in ulog.initial_parameters.items():
        if k not in meta['parameters'] or not same_number(meta['parameters'][k], v):
            fail(f'{where}: parameter {k} is {meta["parameters"].get(k)!r}, pyulog {v!r}')
    changes = [(c['timestamp'], c['name'], c['value']) for c in meta['parameter_changes']]
    if len(changes) != len(ulog.changed_parameters):
        fail(f'{where}: {len(changes)} parameter changes, pyulog {len(ulog.changed_parameters)}')
    for (t, n, v), (pt, pn, pv) in zip(changes, ulog.changed_parameters):
        if t != pt or n != pn or not same_number(v, pv):
            fail(f'{where}: parameter change {(t, n, v)}, pyulog {(pt, pn, pv)}')
    texts = [m['text'] for m in meta['logged_messages'] if m['tag'] is None]
    want = [m.message for m in ulog.logged_messages]
    # Equal, or (where pyulog could not see part of a damaged file) pyulog's in ours in order.
    rest = iter(texts)
    if (texts != want and not hidden) or not all(w in rest for w in want):
        fail(f'{where}: logged messages {texts[:5]}..., pyulog {want[:5]}...')
    drops = [d['duration_ms'] for d in meta['dropouts']]
    if drops != [d.duration for d in ulog.dropouts]:
        fail(f'{where}: dropouts {drops}, pyulog {[d.duration for d in ulog.dropouts]}')
    rows = {f"{t['topic']}/{t['multi_id']}": t['rows'] for t in meta['topics']}
    for d in theirs.values():
        key = f'{d.name}/{d.multi_id}'
        n = len(d.data['timestamp']) + len(hidden.get(key, []))
        if rows.get(key) != n:
            fail(f'{where}: topic {key} has {rows.get(key)} rows, pyulog {n} (+ hidden)')


if __name__ == '__main__':
    log, folder, hidden_path = sys.argv[1:4]
    with open(hidden_path) as f:
        hidden = json.load(f)
    print(json.dumps(check(log, folder, hidden)))
