"""The native API: topics as Arrow tables (read by pyarrow, Polars and DuckDB without a
copy) equal to pyulog's columns, the log's metadata, Parquet, the command-line tool, and
threads reading at once."""

import copy
import errno
import inspect
import io
import json
import os
import pickle
import re
import struct
import subprocess
import sys
import threading
import warnings

import numpy as np
import pytest
import pyulog

import ulog


def pyulog_instances(u):
    """pyulog's datasets of each instance with one subscription (resubscribed ones are
    one table in the native API)."""
    seen = {}
    for d in u.data_list:
        seen.setdefault((d.name, d.multi_id), []).append(d)
    return {k: v[0] for k, v in seen.items() if len(v) == 1}


def test_tables_hold_pyulogs_values(corpus_log, capsys):
    import pyarrow as pa

    u = pyulog.ULog(str(corpus_log))
    capsys.readouterr()
    log = ulog.open(str(corpus_log))
    topics = {(t["name"], t["multi_id"]): t for t in log.topics()}
    for (name, multi_id), d in pyulog_instances(u).items():
        t = log.table(name, multi_id)
        assert topics[(name, multi_id)]["rows"] == t.num_rows
        if u.file_corruption:
            # A damaged log: the native reader keeps intact rows pyulog's recovery cannot
            # see; every row pyulog has is among them, in order.
            ours = iter(t.numpy()["timestamp"].tolist())
            assert all(any(x == y for y in ours) for x in d.data["timestamp"].tolist()), name
            continue
        assert t.num_rows == len(d.data["timestamp"])
        arrow = pa.table(t)
        assert arrow.num_rows == t.num_rows
        for field in d.field_data:
            col = field.field_name
            if col not in arrow.column_names:
                # pyulog shows char arrays byte by byte (and nested padding); the table has
                # the text or leaves padding out.
                continue
            ours = arrow.column(col).to_numpy()
            theirs = d.data[col]
            if field.type_str == "bool":
                assert np.array_equal(ours, theirs != 0), (name, col)
            else:
                assert np.array_equal(ours.astype(theirs.dtype), theirs, equal_nan=True), (name, col)
        # numpy() gives the same values.
        arrays = t.numpy()
        assert list(arrays) == t.column_names
        assert np.array_equal(arrays["timestamp"], d.data["timestamp"])
    # tables(): every instance at once, each equal to its table().
    every = log.tables()
    assert sorted(every) == sorted(topics)
    for (name, multi_id), t in every.items():
        a, b = pa.table(t), pa.table(log.table(name, multi_id))
        assert a.schema == b.schema and a.num_rows == b.num_rows, (name, multi_id)
        for col in a.column_names:
            x, y = a.column(col).to_numpy(), b.column(col).to_numpy()
            nan = x.dtype.kind == "f"
            assert np.array_equal(x, y, equal_nan=nan), (name, multi_id, col)


def big_log(rows: int) -> bytes:
    """A log written byte by byte from the spec: one topic of `rows` rows (a timestamp, a
    float and an int16), its rows between those of a second topic."""
    import struct

    out = bytearray(b"ULog\x01\x12\x35" + bytes([1]) + struct.pack("<Q", 0))

    def message(kind: bytes, body: bytes):
        out.extend(struct.pack("<H", len(body)) + kind + body)

    message(b"F", b"t:uint64_t timestamp;float x;int16_t k;")
    message(b"F", b"u:uint64_t timestamp;uint8_t v;")
    message(b"A", b"\x00" + struct.pack("<H", 0) + b"t")
    message(b"A", b"\x00" + struct.pack("<H", 1) + b"u")
    for i in range(rows):
        message(b"D", struct.pack("<HQfh", 0, 1000 + i, i * 0.5, i % 30000 - 15000))
        if i % 3 == 0:
            message(b"D", struct.pack("<HQB", 1, 1000 + i, i % 256))
    return bytes(out)


def test_a_large_instances_table_is_gathered_on_every_core_in_order(tmp_path):
    # 100,000 rows: enough for a run of rows per core (each at least 32,768 rows).
    import pyarrow as pa

    path = tmp_path / "big.ulg"
    path.write_bytes(big_log(100_000))
    d = pyulog.ULog(str(path)).get_dataset("t")
    log = ulog.open(str(path))
    t = pa.table(log.table("t"))
    # One chunk: the cores wrote their runs in place.
    assert len(t.column("x").chunks) == 1
    for col in ("timestamp", "x", "k"):
        assert np.array_equal(t.column(col).to_numpy(), d.data[col]), col
    assert np.array_equal(log.table("t").numpy()["x"], d.data["x"])
    # Columns chosen, in the order asked for.
    t = pa.table(log.table("t", columns=["k", "timestamp"]))
    assert t.column_names == ["k", "timestamp"]
    assert np.array_equal(t.column("k").to_numpy(), d.data["k"])
    # A window (seconds): the rows from 0.05 s up to 0.08 s.
    t = pa.table(log.table("t", start=0.05, end=0.08))
    assert t.column("timestamp").to_pylist() == list(range(50_000, 80_000))


def test_polars_duckdb_and_pandas_take_a_table():
    import duckdb
    import pandas as pd
    import polars as pl

    path = str(pytest.importorskip("conftest").known_log("pyulog/sample_log_small.ulg"))
    log = ulog.open(path)
    t = log.table("vehicle_attitude", columns=["timestamp", "q[0]"])
    assert t.column_names == ["timestamp", "q[0]"]
    df = pl.DataFrame(t)
    assert df.shape == (t.num_rows, 2) and df.schema["q[0]"] == pl.Float32
    mean = duckdb.sql('select avg("q[0]") as m from t').fetchall()[0][0]
    assert abs(mean - float(df["q[0]"].mean())) < 1e-6
    pdf = t.to_pandas()
    assert isinstance(pdf, pd.DataFrame) and len(pdf) == t.num_rows
    assert t.to_polars().equals(df)
    # A window in seconds, as `ulog csv --start --end` takes it.
    ts = df["timestamp"].to_numpy()
    start, end = ts[10] / 1e6, ts[20] / 1e6
    w = log.table("vehicle_attitude", start=start, end=end)
    assert np.array_equal(pl.DataFrame(w)["timestamp"].to_numpy(), ts[10:20])
    # A window none of its rows lie in (microseconds given for seconds): no row, and a
    # warning that says where the rows lie, as `ulog csv` says it.
    with pytest.warns(UserWarning) as said:
        empty = log.table("vehicle_attitude", start=float(ts[10]))
    assert empty.num_rows == 0
    [message] = [str(w.message) for w in said]
    found = re.fullmatch(
        r"no row of `vehicle_attitude` #0 lies in the window from (\S+) s "
        r"\(its rows run from (\S+) s to (\S+) s\)",
        message,
    )
    assert found, message
    given, first, last = (float(x) for x in found.groups())
    assert given == pytest.approx(float(ts[10]), rel=1e-12)
    assert (first * 1e6, last * 1e6) == pytest.approx((ts.min(), ts.max()), abs=0.5)
    with pytest.raises(KeyError, match="did you mean `vehicle_attitude`"):
        log.table("vehicle_atitude")
    with pytest.raises(KeyError, match="no column `q\\[9\\]`"):
        log.table("vehicle_attitude", columns=["q[9]"])
    # One column name as a str is that column, not its characters.
    assert log.table("vehicle_attitude", columns="q[0]").column_names == ["q[0]"]
    # An instance number no instance can have is a KeyError listing the instances, as for
    # one the log lacks (and for a topic it lacks, the closest names).
    for bad in (5, -1, 300):
        with pytest.raises(KeyError, match=f"has no instance {bad} \\(instances: \\[0\\]\\)"):
            log.table("vehicle_attitude", bad)
    # A window no row could lie in is a ValueError, as `ulog csv --start --end` refuses it.
    for start, end, says in (
        (float("nan"), None, "start \\(NaN\\) is not a finite number"),
        (None, float("inf"), "end \\(inf\\) is not a finite number"),
        (end, start, "ends .* at or before its start"),
        (start, start, "ends .* at or before its start"),
    ):
        with pytest.raises(ValueError, match=says):
            log.table("vehicle_attitude", start=start, end=end)
    with pytest.raises(KeyError, match="did you mean `vehicle_attitude`"):
        log.table("vehicle_atitude", 300)


def test_tagged_strings_are_listed_when_asked_for():
    # A log made by hand (the spec's `L` and `C` messages): ulog_messages lists the logged
    # string only; `tagged=True` adds the tagged one, as `ulog messages --tagged` does.
    def msg(kind, body):
        return struct.pack("<HB", len(body), ord(kind)) + body

    data = b"ULog\x01\x12\x35\x01" + struct.pack("<Q", 0)
    data += msg("L", struct.pack("<BQ", ord("6"), 1000) + b"plain")
    data += msg("C", struct.pack("<BHQ", ord("4"), 3, 2000) + b"tagged")
    log = ulog.open(data)
    assert log.messages() == [(1000, "INFO", "plain")]
    assert log.messages(tagged=True) == [(1000, "INFO", "plain"), (2000, "WARNING", "[tag 3] tagged")]


def test_the_log_says_what_the_reader_read():
    from conftest import known_log

    path = known_log("pyulog/sample_px4_events.ulg")
    u = pyulog.ULog(str(path))
    log = ulog.open(path)
    assert log.header["start_timestamp"] == u.start_timestamp
    assert log.parameters == u.initial_parameters
    assert [(t, n, v) for t, n, v in log.parameter_changes] == u.changed_parameters
    assert log.info["sys_name"] == u.msg_info_dict["sys_name"]
    assert [m[3] for m in log.logged_messages] == [m.message for m in u.logged_messages]
    assert [(t, d) for t, d in log.dropouts] == [(d.timestamp, d.duration) for d in u.dropouts]
    events = log.events()
    assert events and all(e["name"] for e in events), "decoded with the embedded metadata"
    lines = log.messages()
    assert any("Takeoff detected" in text for _, _, text in lines)
    a = log.analysis()
    assert a["flight_modes"] and "field_stats" in a
    # Bytes work as a path does, and so do binary file objects (read from their position).
    assert ulog.open(path.read_bytes()).topics() == log.topics()
    with open(path, "rb") as f:
        assert ulog.open(f).topics() == log.topics()
    assert ulog.open(io.BytesIO(path.read_bytes())).topics() == log.topics()
    with pytest.raises(TypeError, match="binary file object"):
        with open(path, "r", encoding="latin-1") as f:
            ulog.open(f)
    # Refused before it is read: UTF-8 text mode would fail reading the log's bytes.
    with pytest.raises(TypeError, match="binary file object"):
        with open(path, "r", encoding="utf-8") as f:
            ulog.open(f)
    with pytest.raises(TypeError, match="not int"):
        ulog.open(3)


def test_to_parquet_writes_what_ulog_parquet_writes(tmp_path):
    import pyarrow as pa
    import pyarrow.parquet as pq
    from conftest import known_log

    good = known_log("pyulog/sample_log_small.ulg")
    bad = tmp_path / "not_a_log.ulg"
    bad.write_bytes(b"not a log at all")
    results = ulog.to_parquet([good, bad], tmp_path / "out")
    assert [r["ok"] for r in results] == [True, False]
    assert "not a ULog file" in results[1]["error"]
    files = results[0]["files"]
    battery = next(f for f in files if f["topic"] == "battery_status")
    table = pq.read_table(battery["path"])
    assert table.num_rows == battery["rows"]
    meta = json.loads(open(results[0]["metadata"]).read())
    assert meta["analysis"]["battery"]["instances"]
    hive = ulog.to_parquet(str(good), tmp_path / "hive", layout="hive", topics=["battery_status"])
    assert all(f["topic"] == "battery_status" for f in hive[0]["files"])
    # One topic as a str is that topic.
    one = ulog.to_parquet(str(good), tmp_path / "one", topics="battery_status")
    assert {f["topic"] for f in one[0]["files"]} == {"battery_status"}
    # A topic no log defines: a KeyError naming the closest, before anything is written
    # (as `ulog parquet -m`); one that only some logs define: said of the others.
    with pytest.raises(KeyError, match="no topic `batery_status` in this log; did you mean `battery_status`"):
        ulog.to_parquet(str(good), tmp_path / "none", topics=["batery_status"])
    assert not (tmp_path / "none").exists()
    with pytest.raises(KeyError, match="no topic `zzzzzzzzzzzzzz` in this log \\(no topic the logs define has a close name\\)"):
        ulog.to_parquet(str(good), tmp_path / "none", topics="zzzzzzzzzzzzzz")
    with pytest.raises(KeyError, match="no topic `batery_status` in any of the logs that can be read; did you mean"):
        ulog.to_parquet([good, bad], tmp_path / "none", topics=["batery_status"])
    lacking = known_log("yule_log/short_list.ulg")
    assert "battery_status" not in ulog.ULog(str(lacking), parse_header_only=True).message_formats
    with pytest.warns(UserWarning) as said:
        some = ulog.to_parquet([good, lacking], tmp_path / "some", topics=["battery_status"])
    assert some[1]["ok"] and some[1]["said"][0] == "no topic `battery_status` in this log"
    assert f"{lacking}: no topic `battery_status` in this log" in [str(w.message) for w in said]
    assert "no topic" not in " ".join(some[0]["said"])
    for bad_args, what in [
        (dict(topics=[]), "topics=\\[\\] names no topic"),
        (dict(topics=iter([])), "topics=\\[\\] names no topic"),
        (dict(threads=0), "1 or more"),
        (dict(threads=-1), "1 or more"),
    ]:
        with pytest.raises(ValueError, match=what):
            ulog.to_parquet(str(good), tmp_path / "x", **bad_args)
    with pytest.raises(TypeError, match="threads must be an int, not str"):
        ulog.to_parquet(str(good), tmp_path / "x", threads="2")
    # Any iterable of names, and numpy's integers for threads.
    gen = ulog.to_parquet(str(good), tmp_path / "gen", topics=(t for t in ["battery_status"]), threads=np.int64(2))
    assert {f["topic"] for f in gen[0]["files"]} == {"battery_status"}
    # No log converted: the errors say why, and no topic is warned of.
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        failed = ulog.to_parquet([bad], tmp_path / "failed", topics=["battery_status"])
    assert not failed[0]["ok"]
    with pytest.raises(ValueError, match="layout"):
        ulog.to_parquet(str(good), tmp_path / "x", layout="flat")
    # A window: only its rows, as `table(start=, end=)` gives them; a topic with none in
    # it is a warning that names the window; a window no row could lie in, a ValueError
    # before anything is written.
    log = ulog.open(str(good))
    ts = pa.table(log.table("battery_status"))["timestamp"].to_numpy()
    start, end = ts[3] / 1e6, ts[9] / 1e6
    cut = ulog.to_parquet(str(good), tmp_path / "cut", topics="battery_status", start=start, end=end)
    written = pq.read_table(cut[0]["files"][0]["path"])["timestamp"].to_numpy()
    assert np.array_equal(written, ts[3:9])
    expected = pa.table(log.table("battery_status", start=start, end=end))["timestamp"].to_numpy()
    assert np.array_equal(written, expected)
    with pytest.warns(UserWarning) as said:
        early = ulog.to_parquet(str(good), tmp_path / "early", topics="battery_status", end=1.0)
    assert early[0]["ok"] and early[0]["files"] == []
    # The message gives the span of the topic's rows (every instance's, read by pyulog), as
    # Rust prints a float (no `.0` on a whole number).
    stamps = [d.data["timestamp"] for d in pyulog.ULog(str(good), ["battery_status"]).data_list]
    first, last = (float(min(t.min() for t in stamps)) / 1e6, float(max(t.max() for t in stamps)) / 1e6)

    def shown(x):
        return np.format_float_positional(x, trim="-")

    assert [str(w.message) for w in said] == [
        f"{good}: no Parquet file written: the topics asked for have no rows that can be read in the window before 1 s"
        f" (their rows run from {shown(first)} s to {shown(last)} s)",
        "no log has rows of topic `battery_status` in the window before 1 s",
    ]
    meta = json.loads(open(early[0]["metadata"]).read())
    assert meta["window"] == {"start_s": None, "end_s": 1.0}
    # What reading left out is in the result and said, as `ulog parquet` says it on stderr.
    assert results[0]["skipped"]["unreadable_topics"] == [] and results[0]["skipped"]["damaged_bytes"] == 0
    cut = tmp_path / "cut_short.ulg"
    cut.write_bytes(good.read_bytes()[:500_000])
    with pytest.warns(UserWarning, match="cut_short.ulg: 37 damaged bytes skipped \\(`ulog info -v` lists where\\)"):
        short = ulog.to_parquet(str(cut), tmp_path / "short")
    assert short[0]["ok"] and short[0]["skipped"]["damaged_bytes"] == 37
    assert short[0]["skipped"]["ignored_appended_offsets"] == []
    # A log with appended data, cut before it: the appended data that is not read is said.
    appended = known_log("pyulog/sample_appended_multiple.ulg").read_bytes()
    assert appended[16 + 2] == ord("B")
    offsets = [o for o in struct.unpack_from("<3Q", appended, 16 + 3 + 16) if o]
    cut_at = min(offsets) - 1000
    cut = tmp_path / "appended_cut.ulg"
    cut.write_bytes(appended[:cut_at])
    with pytest.warns(UserWarning, match=f"appended data at byte {offsets[0]} not read"):
        result = ulog.to_parquet(str(cut), tmp_path / "appended")
    assert result[0]["skipped"]["ignored_appended_offsets"] == offsets
    with pytest.raises(ValueError, match="at or before its start"):
        ulog.to_parquet(str(good), tmp_path / "never", start=end, end=start)
    assert not (tmp_path / "never").exists()


def test_pyarrow_reads_the_float_columns_statistics(tmp_path):
    # Every float column chunk's bounds, as pyarrow reads them (it ignores the IEEE 754
    # total order parquet-rs 60 would declare): those of its values, NaN left out.
    import pyarrow as pa
    import pyarrow.parquet as pq
    from conftest import corpus_files

    checked = 0
    for path in corpus_files():
        result = ulog.to_parquet(str(path), tmp_path / path.stem)[0]
        for f in result.get("files", []):
            pf = pq.ParquetFile(f["path"])
            for g in range(pf.metadata.num_row_groups):
                group = pf.read_row_group(g)
                for c in range(pf.metadata.num_columns):
                    chunk = pf.metadata.row_group(g).column(c)
                    if chunk.physical_type not in ("FLOAT", "DOUBLE"):
                        continue
                    values = group.column(chunk.path_in_schema).to_numpy().astype(np.float64)
                    numbers = values[~np.isnan(values)]
                    stats = chunk.statistics
                    assert stats.has_min_max == (numbers.size > 0), (f["path"], chunk.path_in_schema)
                    if numbers.size:
                        assert stats.min == numbers.min() and stats.max == numbers.max()
                        checked += 1
    if corpus_files():
        assert checked > 1000


def test_the_command_line_tool_ships_with_the_package():
    from conftest import known_log

    path = str(known_log("pyulog/sample.ulg"))
    run = subprocess.run([sys.executable, "-m", "ulog", "info", path], capture_output=True, text=True)
    assert run.returncode == 0 and "sys_name" in run.stdout, run.stderr
    run = subprocess.run([sys.executable, "-m", "ulog", "info", "/no/such.ulg"], capture_output=True, text=True)
    assert run.returncode == 1 and "no such file" in run.stderr
    run = subprocess.run([sys.executable, "-m", "ulog", "--bogus"], capture_output=True, text=True)
    assert run.returncode == 2


def many_links(tmp_path, n: int):
    """`n` logs of distinct names (links to one corpus log of 0.9 MB): two at a time, their
    conversion lasts long enough to be interrupted once the first is converted."""
    from conftest import known_log

    src = known_log("pyulog/sample_log_small.ulg")
    logs = tmp_path / "logs"
    logs.mkdir()
    for i in range(n):
        (logs / f"log{i:03}.ulg").symlink_to(src)
    return sorted(logs.glob("*.ulg"))


def converted_whole(out, n: int):
    """The logs converted under `out`: each folder complete (its metadata.json written last),
    none half-written, and fewer than `n`."""
    done = {p.parent.name for p in out.glob("*/metadata.json")}
    assert not list(out.rglob("*.partial")), "a file left half-written"
    assert {p.name for p in out.iterdir()} == done, "a folder of a log not converted"
    assert 0 < len(done) < n, len(done)
    return done


# Sends SIGINT to its own process once `out` holds a converted log (a Ctrl-C in the middle
# of the conversion), and prints `interrupted` if the call raised KeyboardInterrupt.
INTERRUPTED_CONVERSION = """
import os, signal, sys, threading, time
import ulog
from pathlib import Path

logs, out = sorted(Path(sys.argv[1]).glob("*.ulg")), Path(sys.argv[2])

def interrupt():
    while not any(out.glob("*/metadata.json")):
        time.sleep(0.001)
    os.kill(os.getpid(), signal.SIGINT)

threading.Thread(target=interrupt, daemon=True).start()
try:
    ulog.to_parquet(logs, out, threads=2)
except KeyboardInterrupt:
    print("interrupted")
"""


def test_ctrl_c_stops_to_parquet_after_the_logs_being_converted(tmp_path):
    # The GIL is released while converting, and the signal is seen while it runs: the
    # logs not started yet are left alone (they were all converted before Python's handler
    # ran), and the exception comes out of the call.
    n = 300
    logs = many_links(tmp_path, n)
    out = tmp_path / "out"
    run = subprocess.run(
        [sys.executable, "-c", INTERRUPTED_CONVERSION, str(logs[0].parent), str(out)],
        capture_output=True,
        text=True,
        timeout=600,
    )
    assert run.stdout.strip() == "interrupted", run.stderr
    converted_whole(out, n)


def test_ctrl_c_stops_the_command_line_tool_as_it_stops_the_rust_binary(tmp_path):
    # `ulog parquet` finishes the logs under way and exits 130 (Python's handler would have
    # run only after every log was converted, then ended the process with a traceback).
    import signal
    import time

    n = 300
    logs = many_links(tmp_path, n)
    out = tmp_path / "out"
    tool = subprocess.Popen(
        [sys.executable, "-m", "ulog", "parquet", *map(str, logs), "-j", "2", "-o", str(out)],
        stdout=subprocess.DEVNULL,
        stderr=subprocess.PIPE,
        text=True,
    )
    try:
        while not any(out.glob("*/metadata.json")) and tool.poll() is None:
            time.sleep(0.001)
        tool.send_signal(signal.SIGINT)
        _, stderr = tool.communicate(timeout=600)
    finally:
        tool.kill()
    assert tool.returncode == 130, stderr
    done = converted_whole(out, n)
    assert f"stopped (signal 2): {n - len(done)} of {n} logs not converted" in stderr


def test_threads_read_logs_at_once(corpus_log):
    # The GIL is released while reading: threads finish, with the same answers.
    results = [None] * 4

    def read(i):
        u = ulog.ULog(str(corpus_log))
        results[i] = [(d.name, d.multi_id, len(d.data["timestamp"])) for d in u.data_list]

    threads = [threading.Thread(target=read, args=(i,)) for i in range(4)]
    for t in threads:
        t.start()
    for t in threads:
        t.join(timeout=120)
    assert all(r == results[0] for r in results)


def test_the_package_shows_only_its_public_names():
    # What `dir(ulog)` and tab completion show is what `__all__` promises (submodules
    # aside), and `ulog.open`, which `__all__` leaves out so that `from ulog import *`
    # does not hide the built-in `open`; and every name of `__all__` is there.
    public = {n for n in dir(ulog) if not n.startswith("_") and not inspect.ismodule(getattr(ulog, n))}
    assert public == {n for n in ulog.__all__ if not n.startswith("_")} | {"open"}
    assert "open" not in ulog.__all__
    assert all(hasattr(ulog, n) for n in ulog.__all__)
    # The same of `ulog.spark` (importable without pyspark), which imports typing names.
    from ulog import spark

    assert [n for n in dir(spark) if not n.startswith("_")] == ["convert", "metadata", "topics"]
    assert all(callable(getattr(spark, n)) for n in spark.__all__)


def test_ulog_spark_is_at_hand_after_import_ulog():
    # In a fresh interpreter, so that no earlier test has imported the submodule.
    code = "import ulog, sys; assert 'ulog.spark' not in sys.modules; print(sorted(ulog.spark.__all__))"
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, check=True)
    assert out.stdout.strip() == "['convert', 'metadata', 'topics']"
    with pytest.raises(AttributeError, match="no attribute 'sparks'"):
        ulog.sparks


def test_a_log_closes_at_the_end_of_a_with_block():
    from conftest import corpus_files

    files = corpus_files()
    if not files:
        pytest.skip("no corpus")
    with ulog.open(files[0]) as log:
        assert not log.closed
        first = next(t for t in log.topics() if t["rows"] > 0)
        table = log.table(first["name"], first["multi_id"])
    assert log.closed
    with pytest.raises(ValueError, match="the log is closed"):
        log.topics()
    with pytest.raises(ValueError, match="the log is closed"):
        log.name
    # A table made before keeps its columns.
    import pyarrow

    assert pyarrow.table(table).num_rows == first["rows"] > 0
    log.close()  # closing again is harmless
    assert log.closed
    assert repr(log) == "<ulog.Log (closed)>"
    with pytest.raises(ValueError, match="the log is closed"):
        with log:
            pass


def test_misused_arguments_are_clear_errors(tmp_path):
    from conftest import known_log

    path = known_log("pyulog/sample_log_small.ulg")
    log = ulog.open(path)
    for wrong in ["0", None, 0.0, True]:
        with pytest.raises(TypeError, match=f"multi_id must be an int, not {type(wrong).__name__}"):
            log.table("vehicle_attitude", wrong)
    # numpy's integers are ints here, as they are to Python's own indexing.
    assert log.table("vehicle_attitude", np.uint8(0)).num_rows == log.table("vehicle_attitude").num_rows
    with pytest.raises(ValueError, match=r"columns named more than once: \['q\[0\]'\]"):
        log.table("vehicle_attitude", columns=["q[0]", "timestamp", "q[0]"])
    assert log.table("vehicle_attitude", columns=["q[1]", "q[0]"]).column_names == ["q[1]", "q[0]"]
    # A path that is not a regular file: refused by name, as the CLI does, not mapped.
    with pytest.raises(ulog.ULogIOError, match="is not a regular file"):
        ulog.open("/dev/null")
    # A folder is an IsADirectoryError too (errno EISDIR), as Python's own open() says.
    with pytest.raises(IsADirectoryError, match="is a folder, not a log file") as raised:
        ulog.open(tmp_path)
    assert isinstance(raised.value, ulog.ULogIOError) and raised.value.errno == errno.EISDIR
    pipe = tmp_path / "pipe.ulg"
    os.mkfifo(pipe)
    with pytest.raises(ulog.ULogIOError, match="is not a regular file"):
        ulog.open(pipe)  # refused, not waited on for a writer
    # An I/O error is an OSError too, with its errno and file name, and of the OSError
    # subclass of its errno, as Python's own are: `except FileNotFoundError` catches it.
    missing = tmp_path / "missing.ulg"
    with pytest.raises(FileNotFoundError) as raised:
        ulog.open(missing)
    assert isinstance(raised.value, ulog.ULogError) and isinstance(raised.value, ulog.ULogIOError)
    assert raised.value.errno == errno.ENOENT and raised.value.filename == str(missing)
    assert str(raised.value) == f"{missing}: I/O error: No such file or directory (os error 2)"
    assert not isinstance(raised.value, PermissionError)
    # What pickle and copy give back is the same error: type, message, errno, file name.
    for again in (pickle.loads(pickle.dumps(raised.value)), copy.copy(raised.value)):
        assert type(again) is type(raised.value)
        assert (str(again), again.errno, again.filename) == (str(raised.value), errno.ENOENT, str(missing))
    # Without an errno, a ULogIOError of no OSError subclass, pickled whole as well.
    with pytest.raises(ulog.ULogIOError) as raised:
        ulog.open("/dev/null")
    assert type(raised.value) is ulog.ULogIOError and raised.value.errno is None
    again = pickle.loads(pickle.dumps(raised.value))
    assert (type(again), str(again), again.filename) == (ulog.ULogIOError, str(raised.value), "/dev/null")
    assert "(70 topic instances, 14604 rows)" in repr(log)
    one = known_log("yule_log/short_list.ulg")
    assert repr(ulog.open(one)).endswith("(1 topic instance, 10 rows)>")
    assert repr(ulog.open(one).table("list_data", columns="timestamp")) == "<ulog.Table list_data #0: 10 rows, 1 column>"


def test_the_start_date_is_the_headers_or_the_first_gps_fixs(capsys):
    from conftest import corpus_files, pyulog_start_utc

    dated = 0
    for path in corpus_files():
        log = ulog.open(str(path))
        expected = pyulog_start_utc(path)
        capsys.readouterr()
        assert log.start_utc == expected, path.name
        if log.header["start_utc"] is None and expected is not None:
            dated += 1
    if corpus_files():
        assert dated > 0, "some corpus log is dated by its GPS alone"
