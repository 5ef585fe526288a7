"""``ulog.spark`` in PySpark's local mode (``local[2]``): the corpus converted on Spark, one
Spark SQL query per topic (rows, first and last timestamp, a mean per log) equal to
pyulog's figures, and the Spark-written hive layout read by DuckDB equal to the one
``ulog parquet --layout hive`` writes. Needs pyspark and Java (``.ci/run`` installs both)."""

import math
import os
import shutil
import sys

import pytest
import pyulog

import ulog
import ulog.spark
from conftest import corpus_files, pyulog_start_utc, under_ci

TOPICS = ["vehicle_attitude", "battery_status", "sensor_combined", "vehicle_local_position"]
# A numeric field each topic has in every PX4 version of the corpus.
MEAN_OF = {
    "vehicle_attitude": "q[0]",
    "battery_status": "voltage_v",
    "sensor_combined": "gyro_rad[0]",
    "vehicle_local_position": "z",
}


@pytest.fixture(scope="module")
def spark():
    try:
        from pyspark.sql import SparkSession
    except ImportError:
        if under_ci():
            pytest.fail("under CI pyspark must be installed (.ci/run installs it)")
        pytest.skip("no pyspark")
    if shutil.which("java") is None:
        if under_ci():
            pytest.fail("under CI Java must be installed (.ci/run installs openjdk-17)")
        pytest.skip("no java")
    # The workers run this interpreter (pyarrow and the package beside it), not the first
    # `python3` on the PATH, which outside `.ci/run` has neither.
    before = os.environ.get("PYSPARK_PYTHON")
    os.environ["PYSPARK_PYTHON"] = sys.executable
    s = (
        SparkSession.builder.master("local[2]")
        .appName("ulog-spark-test")
        .config("spark.ui.enabled", "false")
        .config("spark.sql.shuffle.partitions", "2")
        .config("spark.driver.memory", "1g")
        .getOrCreate()
    )
    s.sparkContext.setLogLevel("ERROR")
    yield s
    s.stop()
    if before is None:
        del os.environ["PYSPARK_PYTHON"]
    else:
        os.environ["PYSPARK_PYTHON"] = before


def test_the_corpus_on_spark_equals_pyulog_and_ulog_parquet(spark, tmp_path, capsys):
    import duckdb

    logs = corpus_files()
    if not logs:
        pytest.skip("no corpus")
    inputs = tmp_path / "in"
    inputs.mkdir()
    for p in logs:
        # Two logs of one stem would take `~2`: the corpus's names are unique.
        (inputs / p.name).symlink_to(p)
    # A file that is no log at all: a metadata row with its error, not a failed job.
    (inputs / "broken.ulg").write_bytes(b"this is not a ULog file")
    out = tmp_path / "spark"
    written = ulog.spark.convert(spark, str(inputs / "*.ulg"), str(out), topics=TOPICS)
    assert set(written) <= set(TOPICS) and written

    # The metadata table: one row per log, the unreadable ones with their error.
    meta = {r["log"]: r for r in spark.read.parquet(str(out / "metadata")).collect()}
    assert set(meta) == {p.stem for p in logs} | {"broken"}
    assert "not a ULog file" in meta["broken"]["error"]
    import hashlib
    import json

    for p in logs:
        r = meta[p.stem]
        assert r["error"] is None, r["error"]
        assert r["sha256"] == hashlib.sha256(p.read_bytes()).hexdigest()
        u = pyulog.ULog(str(p), [])
        capsys.readouterr()
        assert r["start_timestamp"] == u.start_timestamp
        assert r["start_utc"] == pyulog_start_utc(p), p.name
        assert r["sys_name"] == (u.msg_info_dict.get("sys_name") if isinstance(u.msg_info_dict.get("sys_name"), str) else None)
        assert "flight_modes" in json.loads(r["analysis"])

    # One query per topic against pyulog's figures (logs pyulog reads whole).
    for topic in written:
        df = spark.read.parquet(str(out / f"topic={topic}"))
        df.createOrReplaceTempView("t")
        col = MEAN_OF[topic]
        got = {
            (r["log"], r["multi_id"]): r
            for r in spark.sql(
                f"select log, multi_id, count(*) as n, min(timestamp) as t0, max(timestamp) as t1, "
                f"avg(`{col}`) as m from t group by log, multi_id"
            ).collect()
        }
        checked = 0
        for p in logs:
            u = pyulog.ULog(str(p), [topic])
            capsys.readouterr()
            if u.file_corruption:
                continue
            for d in u.data_list:
                key = (p.stem, d.multi_id)
                if sum(1 for x in u.data_list if x.multi_id == d.multi_id) > 1:
                    continue  # resubscribed: one table of several datasets
                r = got[key]
                ts = d.data["timestamp"]
                assert r["n"] == len(ts), (topic, key)
                assert int(r["t0"]) == int(ts.min()) and int(r["t1"]) == int(ts.max()), (topic, key)
                values = d.data[col].astype(float)
                finite = values[[math.isfinite(v) for v in values]]
                if len(finite) == len(values):
                    assert math.isclose(r["m"], values.mean(), rel_tol=1e-9, abs_tol=1e-12), (topic, key)
                checked += 1
        assert checked > 0, topic

    # The same logs through ulog parquet's hive layout: DuckDB sees the same tables.
    hive = tmp_path / "hive"
    real = sorted(p for p in inputs.glob("*.ulg") if p.name != "broken.ulg")
    # (Damaged logs and logs without these topics are said as warnings, a line of `said` each.)
    with pytest.warns(UserWarning) as said:
        results = ulog.to_parquet(real, hive, layout="hive", topics=TOPICS, analysis=False)
    assert all(r["ok"] for r in results)
    assert len(said) == sum(len(r["said"]) for r in results)
    for topic in written:
        col = MEAN_OF[topic]
        q = (
            "select log, cast(multi_id as integer) as m, count(*) as n, "
            "cast(min(timestamp) as bigint) as t0, cast(max(timestamp) as bigint) as t1, "
            f'avg("{col}") as mean from read_parquet(\'{{}}/topic={topic}/**/*.parquet\', '
            "hive_partitioning = true, union_by_name = true) group by all order by all"
        )
        ours = duckdb.sql(q.format(hive)).fetchall()
        theirs = duckdb.sql(q.format(out)).fetchall()
        assert len(ours) == len(theirs) > 0, topic
        for a, b in zip(ours, theirs):
            assert a[:5] == b[:5], (topic, a, b)
            same_nan = a[5] is not None and b[5] is not None and math.isnan(a[5]) and math.isnan(b[5])
            assert (a[5] is None and b[5] is None) or same_nan or math.isclose(a[5], b[5], rel_tol=1e-12), (topic, a, b)
