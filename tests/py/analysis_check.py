#!/usr/bin/env python3
"""The flight analysis of one log against the same statistics computed here from pyulog's
arrays with numpy, by the rules the analysis documents:

    analysis_check.py LOG ANALYSIS.json

ANALYSIS.json is `ulog analyze --json LOG`. Prints a JSON summary: the facts compared, the
ones that differ (with both values), and the topics left out because pyulog sees another
number of rows than the analysis counted (a damaged log, whose intact rows pyulog skips).
"""

import contextlib
import json
import sys

import numpy as np
from pyulog import ULog

REL = 1e-6  # float32 data summed in another order


def main():
    log_path, analysis_path = sys.argv[1], sys.argv[2]
    with open(analysis_path) as f:
        analysis = json.load(f)
    # pyulog says what it skips on stdout: that is not the summary.
    with contextlib.redirect_stdout(sys.stderr):
        ulog = ULog(log_path)
    checks = Checks()
    topics = {}
    for d in ulog.data_list:
        topics.setdefault((d.name, d.multi_id), []).append(d)

    # Rows per instance as the analysis counted them (the count of any field that is always
    # finite: the largest count among its fields).
    counted = {}
    for s in analysis["field_stats"]:
        key = (s["topic"], s["multi_id"])
        counted[key] = max(counted.get(key, 0), s["count"])

    def data(topic, multi_id=0):
        """The instance's fields (merged over pyulog's parts), if pyulog sees the rows the
        analysis saw."""
        parts = topics.get((topic, multi_id))
        if not parts:
            return None
        fields = {}
        for name in parts[0].data:
            if all(name in p.data for p in parts):
                fields[name] = np.concatenate([p.data[name] for p in parts])
        rows = len(fields["timestamp"])
        if (topic, multi_id) in counted and counted[(topic, multi_id)] > rows:
            checks.left_out.append(f"{topic}#{multi_id}: pyulog sees {rows} rows")
            return None
        return fields

    check_field_stats(analysis, topics, counted, checks)
    check_motion(analysis["stats"], data, checks)
    check_battery(analysis["battery"], data, checks)
    check_gps(analysis["gps_quality"], data, checks)
    check_vibration(analysis["vibration"], data, checks)
    check_modes(analysis["flight_modes"], data, checks)
    print(json.dumps({
        "compared": checks.compared,
        "mismatches": checks.mismatches,
        "left_out": checks.left_out,
    }))


class Checks:
    def __init__(self):
        self.compared = 0
        self.mismatches = []
        self.left_out = []

    def same(self, what, ours, theirs, rel=REL):
        """Compares a fact: both absent, or both present and equal within `rel`."""
        self.compared += 1
        if theirs is None or (isinstance(theirs, float) and not np.isfinite(theirs)):
            if ours is not None:
                self.mismatches.append({"fact": what, "ours": ours, "numpy": None})
            return
        theirs = float(theirs)
        if ours is None or abs(ours - theirs) > rel * max(1.0, abs(theirs)):
            self.mismatches.append({"fact": what, "ours": ours, "numpy": theirs})


def finite(a):
    a = np.asarray(a, dtype=np.float64)
    return a[np.isfinite(a)]


def check_field_stats(analysis, topics, counted, checks):
    """Every numeric field but `timestamp`, bool and char: min, max, mean, count of its
    finite values."""
    ours = {(s["topic"], s["multi_id"], s["field"]): s for s in analysis["field_stats"]}
    for (topic, multi_id), parts in sorted(topics.items()):
        rows = sum(len(p.data["timestamp"]) for p in parts)
        if counted.get((topic, multi_id), 0) > rows:
            continue
        kinds = {f.field_name: f.type_str for f in parts[0].field_data}
        for name, kind in kinds.items():
            padding = any(part.split("[")[0].startswith("_padding") for part in name.split("."))
            if name == "timestamp" or kind in ("bool", "char") or padding:
                continue
            if not all(name in p.data for p in parts):
                continue
            values = finite(np.concatenate([p.data[name] for p in parts]))
            key = (topic, multi_id, name)
            what = f"field_stats {topic}#{multi_id} {name}"
            if len(values) == 0:
                checks.compared += 1
                if key in ours:
                    checks.mismatches.append({"fact": what, "ours": ours[key], "numpy": None})
                continue
            s = ours.get(key)
            if s is None:
                checks.compared += 1
                checks.mismatches.append({"fact": what, "ours": None, "numpy": len(values)})
                continue
            checks.same(what + " count", s["count"], len(values), rel=0)
            checks.same(what + " min", s["min"], values.min(), rel=0)
            checks.same(what + " max", s["max"], values.max(), rel=0)
            checks.same(what + " mean", s["mean"], values.mean())


def rows_finite(*columns):
    """The rows where every column is finite."""
    stacked = np.vstack([np.asarray(c, dtype=np.float64) for c in columns])
    return stacked[:, np.all(np.isfinite(stacked), axis=0)]


def check_motion(stats, data, checks):
    lp = data("vehicle_local_position")
    if lp is not None:
        rows = rows_finite(lp["timestamp"], lp["x"], lp["y"], lp["z"])
        t, pos = rows[0], rows[1:]
        if pos.shape[1] > 0:
            steps = np.sqrt((np.diff(pos, axis=1) ** 2).sum(axis=0))
            # No step across time that runs back (logs joined, a damaged log).
            steps = steps[np.diff(t) >= 0]
            checks.same("total_distance_m", stats["total_distance_m"], steps.sum())
            alt = -pos[2]
            checks.same("max_altitude_diff_m", stats["max_altitude_diff_m"], alt.max() - alt.min())
        if all(k in lp for k in ("vx", "vy", "vz")):
            v = rows_finite(lp["vx"], lp["vy"], lp["vz"])
            if v.shape[1] > 0:
                h = np.hypot(v[0], v[1])
                s = np.sqrt(h ** 2 + v[2] ** 2)
                checks.same("max_speed_m_s", stats["max_speed_m_s"], s.max())
                checks.same("max_horizontal_speed_m_s", stats["max_horizontal_speed_m_s"], h.max())
                checks.same("max_speed_up_m_s", stats["max_speed_up_m_s"], max(0.0, (-v[2]).max()))
                checks.same("max_speed_down_m_s", stats["max_speed_down_m_s"], max(0.0, v[2].max()))
                checks.same("avg_speed_m_s", stats["avg_speed_m_s"], s.mean())
    att = data("vehicle_attitude")
    if att is not None and "q[1]" in att:
        # Rows with a finite, non-zero quaternion, each normalised by its length.
        q = rows_finite(att["q[0]"], att["q[1]"], att["q[2]"], att["q[3]"])
        q = q[:, (q ** 2).sum(axis=0) > 0]
        if q.shape[1] > 0:
            tilt = np.degrees(np.arccos(np.clip(1 - 2 * (q[1] ** 2 + q[2] ** 2) / (q ** 2).sum(axis=0), -1, 1)))
            checks.same("max_tilt_deg", stats["max_tilt_deg"], tilt.max())
    rates = data("vehicle_angular_velocity")
    if rates is not None and "xyz[0]" in rates:
        r = rows_finite(rates["xyz[0]"], rates["xyz[1]"], rates["xyz[2]"])
        if r.shape[1] > 0:
            checks.same("max_rotation_speed_deg_s", stats["max_rotation_speed_deg_s"],
                        np.degrees(np.sqrt((r ** 2).sum(axis=0)).max()))


def check_battery(battery, data, checks):
    for inst in battery["instances"]:
        b = data("battery_status", inst["multi_id"])
        if b is None:
            continue
        name = "voltage_v" if "voltage_v" in b else "voltage_filtered_v"
        v = finite(b[name])
        v = v[v > 0]
        what = f"battery#{inst['multi_id']}"
        checks.same(what + " min_voltage_v", inst["min_voltage_v"], v.min() if len(v) else None)
        cname = "current_a" if "current_a" in b else "current_filtered_a"
        currents = 0
        if cname in b:
            c = finite(b[cname])
            c = c[c >= 0]
            currents = len(c)
            checks.same(what + " max_current_a", inst["max_current_a"], c.max() if len(c) else None)
            checks.same(what + " avg_current_a", inst["avg_current_a"], c.mean() if len(c) else None)
        if "discharged_mah" in b:
            d = finite(b["discharged_mah"])
            d = d[d >= 0]
            # PX4 integrates the charge from the current: without a valid current reading
            # a charge of 0 is unknown (a charge above 0 is a battery's own count).
            expected = d[-1] if len(d) and (currents or d[-1] > 0) else None
            checks.same(what + " discharged_mah", inst["discharged_mah"], expected)


def check_gps(quality, data, checks):
    g = data("vehicle_gps_position")
    if g is None:
        g = data("sensor_gps")
    if g is None:
        return
    if "satellites_used" in g:
        s = finite(g["satellites_used"])
        checks.same("min_satellites", quality["min_satellites"], s.min() if len(s) else None)
        checks.same("max_satellites", quality["max_satellites"], s.max() if len(s) else None)
    fixed = np.ones(len(g["timestamp"]), dtype=bool)
    if "fix_type" in g:
        fixed = g["fix_type"] >= 3
        seen = sorted(set(int(f) for f in g["fix_type"]))
        checks.compared += 1
        if seen != quality["fix_types_seen"]:
            checks.mismatches.append({"fact": "fix_types_seen", "ours": quality["fix_types_seen"], "numpy": seen})
    for field, key in (("eph", "max_eph_m"), ("epv", "max_epv_m"), ("hdop", "max_hdop")):
        if field in g:
            v = np.asarray(g[field], dtype=np.float64)[fixed]
            v = v[np.isfinite(v)]
            checks.same(key, quality[key], v.max() if len(v) else None)


def check_vibration(vibration, data, checks):
    for imu in vibration["imus"]:
        d = data("vehicle_imu_status", imu["multi_id"])
        if d is None:
            continue
        v = finite(d["accel_vibration_metric"])
        v = v[v >= 0]
        checks.same(f"vibration#{imu['multi_id']} mean", imu["mean"], v.mean())
        checks.same(f"vibration#{imu['multi_id']} max", imu["max"], v.max())


def check_modes(modes, data, checks):
    """Segments of nav_state: each starts at the row whose mode differs from the row
    before, or whose time is before that row's; by start time."""
    s = data("vehicle_status")
    if s is None or "nav_state" not in s:
        return
    t, nav = s["timestamp"], s["nav_state"]
    starts = [0] + [i for i in range(1, len(nav)) if nav[i] != nav[i - 1] or t[i] < t[i - 1]]
    ours = [(m["mode_id"], m["start_us"]) for m in modes]
    theirs = sorted(((int(nav[i]), int(t[i])) for i in starts), key=lambda m: m[1])
    checks.compared += 1
    if ours != theirs:
        checks.mismatches.append({"fact": "flight_modes", "ours": ours[:20], "numpy": theirs[:20]})


if __name__ == "__main__":
    main()
