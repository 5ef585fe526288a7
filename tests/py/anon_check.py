#!/usr/bin/env python3
"""Checks an anonymized log against its original, independently of the rewriter's code.

Usage: anon_check.py ORIGINAL OUTPUT

From pyulog on both:
- no original latitude or longitude (as the file stores it: int32 1e-7 degrees, float or
  double degrees, in every field named lat/lon, latitude/longitude, latitude_deg/longitude_deg,
  ref_lat/ref_lon of every topic) nor any UTC time (time_utc_usec, and with an absolute clock
  the header's start) remains in OUTPUT (zero and non-finite values, which stay, aside): an
  8-byte value's pattern nowhere in its bytes; a 4-byte value's pattern nowhere outside its
  data rows (definitions, info, parameters, strings), and in the rows as no value of any
  field of the same type of any topic. (Within the rows a 4-byte pattern is looked for field
  by field, not at every byte: in a 23 MB log with thousands of distinct int32 latitudes,
  four bytes straddling two fields matched one by chance.)
- the distances between consecutive points of every track (vehicle_global_position,
  vehicle_gps_position, sensor_gps, estimator_global_position) equal the original's: to
  1 mm for double fields, to the resolution of the stored values for int32 1e-7° ones;
- pyulog reads OUTPUT whole, with the same topics and row counts, and no corruption.
Prints a JSON summary line; exits 1 naming the first problem.
"""
import contextlib
import io
import json
import math
import struct
import sys

import numpy as np
from pyulog.core import ULog

POSITION_NAMES = {'lat', 'lon', 'latitude', 'longitude', 'latitude_deg', 'longitude_deg',
                  'ref_lat', 'ref_lon'}
TRACKS = ['vehicle_global_position', 'vehicle_gps_position', 'sensor_gps',
          'estimator_global_position']
R = 6371000.0


def fail(msg):
    print(msg, file=sys.stderr)
    sys.exit(1)


def read(path):
    with contextlib.redirect_stdout(io.StringIO()):
        return ULog(path)


def not_data(blob):
    """The bytes of every message but the data rows (`D`), the header and definitions
    included, each message's bytes after the other's."""
    parts = [blob[:16]]
    pos = 16
    while pos + 3 <= len(blob):
        size, kind = struct.unpack_from('<HB', blob, pos)
        end = pos + 3 + size
        if kind != ord('D'):
            parts.append(blob[pos:end])
        pos = end
    return b''.join(parts)


def haversine(a, b):
    (la1, lo1), (la2, lo2) = a, b
    p1, p2 = math.radians(la1), math.radians(la2)
    h = math.sin((p2 - p1) / 2) ** 2 + math.cos(p1) * math.cos(p2) * math.sin(math.radians(lo2 - lo1) / 2) ** 2
    return 2 * R * math.asin(math.sqrt(min(1.0, h)))


def track(d):
    for lat, lon, scale in (('lat', 'lon', None), ('latitude_deg', 'longitude_deg', None)):
        if lat in d.data and lon in d.data:
            a, b = d.data[lat], d.data[lon]
            scaled = a.dtype.kind == 'i'
            k = 1e-7 if scaled else 1.0
            pts = [(float(x) * k, float(y) * k) for x, y in zip(a, b)
                   if (x != 0 or y != 0) and np.isfinite(x) and np.isfinite(y)]
            return pts, scaled
    return None, False


def main():
    original, output = sys.argv[1:3]
    u0, u1 = read(original), read(output)
    if u1.file_corruption:
        fail('pyulog finds the output corrupt')
    blob = open(output, 'rb').read()
    patterns = set()
    # The original values of 4 bytes, by type.
    short = {}
    for d in u0.data_list:
        for field, values in d.data.items():
            base = field.split('.')[-1]
            if base in POSITION_NAMES or base == 'time_utc_usec':
                for v in np.unique(values):
                    if v == 0 or (values.dtype.kind == 'f' and not np.isfinite(v)):
                        continue
                    patterns.add(np.array([v], dtype=values.dtype).tobytes())
                if values.dtype.itemsize == 4:
                    short.setdefault(values.dtype.str, set()).update(
                        v for v in np.unique(values)
                        if v != 0 and not (values.dtype.kind == 'f' and not np.isfinite(v)))
    if u0.start_timestamp >= 946684800000000:
        patterns.add(struct.pack('<Q', u0.start_timestamp))
    outside_rows = not_data(blob)
    for p in patterns:
        at = blob.find(p) if len(p) > 4 else outside_rows.find(p)
        if at >= 0:
            where = 'at byte' if len(p) > 4 else 'outside the data rows, at byte'
            fail(f'an original value {p.hex()} is still in the output {where} {at}')
    for d in u1.data_list:
        for field, values in d.data.items():
            originals = short.get(values.dtype.str)
            if originals:
                kept = np.isin(values, np.array(sorted(originals), dtype=values.dtype))
                if kept.any():
                    i = int(np.argmax(kept))
                    fail(f'{d.name}.{field}: row {i} holds the original value {values[i]}')
    ours = {(d.name, d.multi_id): d for d in u1.data_list}
    if sorted(ours) != sorted((d.name, d.multi_id) for d in u0.data_list
                              if d.name not in ('gps_dump', 'gps_inject_data', 'satellite_info',
                                                'cellular_status', 'ulog_stream')):
        fail(f'topics differ: {sorted(ours)}')
    worst = {'double': 0.0, 'int32': 0.0}
    points = 0
    for d in u0.data_list:
        if d.name not in TRACKS:
            continue
        a, scaled = track(d)
        b, _ = track(ours[(d.name, d.multi_id)])
        if a is None:
            continue
        if len(a) != len(b):
            fail(f'{d.name}: {len(a)} valid points, {len(b)} after')
        kind = 'int32' if scaled else 'double'
        for i in range(1, len(a)):
            err = abs(haversine(a[i - 1], a[i]) - haversine(b[i - 1], b[i]))
            worst[kind] = max(worst[kind], err)
        points += len(a)
    # The resolution of int32 1e-7° values: each coordinate moves by at most half a step
    # when stored, so a distance by at most two half-steps of each.
    step = 1e-7 * math.pi / 180 * R
    if worst['double'] > 1e-3:
        fail(f'double tracks: a distance changed by {worst["double"]} m')
    if worst['int32'] > 2 * math.hypot(step / 2, step / 2) + 1e-6:
        fail(f'int32 tracks: a distance changed by {worst["int32"]} m')
    print(json.dumps({'patterns': len(patterns), 'points': points,
                      'max_error_double_m': worst['double'], 'max_error_int32_m': worst['int32']}))


if __name__ == '__main__':
    main()
