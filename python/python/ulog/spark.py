"""Fleets on Apache Spark: logs read in the executors by the Rust reader, as Arrow batches.

From a DataFrame of binary files (``spark.read.format("binaryFile").load(glob)``):

- ``topics(spark, files)``: one DataFrame per topic, with the columns ``ulog parquet``
  writes (pyulog's names, the types Spark holds: unsigned integers widened as Spark reads
  them from Parquet, ``uint64`` as ``decimal(20,0)``), plus ``log`` (the log's name, unique
  as the hive layout makes it) and ``multi_id``; built with ``mapInArrow``, no pandas. The
  fields of a topic that differ between PX4 versions merge by name (missing columns null).
- ``metadata(spark, files)``: one row per log: what ``metadata.json`` holds as columns
  (``sys_name``, ``ver_sw``, ``ver_hw``, ``start_timestamp``, ``start_utc``, ``sha256``,
  ``duration_s``, ``dropouts``, ``dropout_ms``, ``rows``) and the flight analysis as JSON;
  a log that cannot be read is a row with its ``error``, never a failed job.
- ``convert(spark, input_glob, output_path, topics=None)``: the topics (all, or those
  named) written as the hive layout ``ulog parquet --layout hive`` makes
  (``topic=<t>/log=<l>/multi_id=<m>/``), and the metadata table at ``output_path/metadata``.

One task reads each log (its memory bounded by the log's bytes and one table); each topic's
DataFrame reads the logs again (reading is fast next to Spark's own work).
"""

from __future__ import annotations

import hashlib
import json
from typing import Dict, Iterator, List, Optional, Sequence, Tuple

import pyarrow as pa

from . import _ulog

__all__ = ["convert", "metadata", "topics"]


def __dir__() -> List[str]:
    # What `dir(ulog.spark)` and tab completion show: the three functions, not the typing
    # names and modules this file imports.
    return sorted(__all__)

# Spark holds no unsigned integers: each is widened as Spark widens it reading Parquet.
_WIDER = {
    pa.uint8(): pa.int16(),
    pa.uint16(): pa.int32(),
    pa.uint32(): pa.int64(),
    pa.uint64(): pa.decimal128(20, 0),
}


def _spark_type(t: pa.DataType) -> pa.DataType:
    return _WIDER.get(t, t)


def _logs(files) -> List[Tuple[str, str]]:
    """(path, log name) of every file of the DataFrame, names unique as the hive layout
    makes them (in path order)."""
    paths = sorted(r["path"] for r in files.select("path").collect())
    return list(zip(paths, _ulog.log_names([p.rsplit("/", 1)[-1] for p in paths])))


def _open(content: bytes):
    from . import _native

    return _native.Log(_ulog.Log.open(bytes(content)))


def _schemas(spark, files, names: Dict[str, str], wanted: Optional[Sequence[str]]):
    """Per topic, the union by name of its schemas in every log (types widened for Spark)."""
    schema = pa.schema([("topic", pa.string()), ("schema", pa.binary())])

    def per_log(batches: Iterator[pa.RecordBatch]) -> Iterator[pa.RecordBatch]:
        for batch in batches:
            rows = batch.to_pydict()
            topics, schemas = [], []
            for content in rows["content"]:
                try:
                    log = _open(content)
                except Exception:  # reported by metadata(); no topics
                    continue
                for t in log.topics():
                    if wanted is not None and t["name"] not in wanted:
                        continue
                    s = pa.schema(log.table(t["name"], t["multi_id"]).to_arrow().schema)
                    topics.append(t["name"])
                    schemas.append(s.serialize().to_pybytes())
            yield pa.RecordBatch.from_pydict({"topic": topics, "schema": schemas}, schema=schema)

    found: Dict[str, List[pa.Schema]] = {}
    for row in files.select("content").mapInArrow(per_log, "topic string, schema binary").collect():
        found.setdefault(row["topic"], []).append(pa.ipc.read_schema(pa.py_buffer(row["schema"])))
    unified = {}
    for topic, schemas in sorted(found.items()):
        merged = pa.unify_schemas(schemas, promote_options="permissive")
        fields = [pa.field(f.name, _spark_type(f.type)) for f in merged]
        fields += [pa.field("log", pa.string()), pa.field("multi_id", pa.int16())]
        unified[topic] = pa.schema(fields)
    return unified


def _to_spark_schema(schema: pa.Schema):
    from pyspark.sql.pandas.types import from_arrow_schema

    return from_arrow_schema(schema)


def topics(spark, files, names: Optional[Sequence[str]] = None):
    """One DataFrame per topic (only ``names`` if given) of the logs of ``files`` (a
    ``binaryFile`` DataFrame): a dict of topic to DataFrame."""
    logs = dict(_logs(files))
    if isinstance(names, str):
        names = [names]
    wanted = list(names) if names is not None else None
    unified = _schemas(spark, files, logs, wanted)
    out = {}
    for topic, schema in unified.items():
        out[topic] = files.select("path", "content").mapInArrow(
            _topic_rows(topic, schema, logs), _to_spark_schema(schema)
        )
    return out


# `convert` takes a parameter named `topics`.
_topic_frames = topics


def _topic_rows(topic: str, schema: pa.Schema, logs: Dict[str, str]):
    def rows(batches: Iterator[pa.RecordBatch]) -> Iterator[pa.RecordBatch]:
        for batch in batches:
            d = batch.to_pydict()
            for path, content in zip(d["path"], d["content"]):
                try:
                    log = _open(content)
                except Exception:
                    continue
                for t in log.topics():
                    if t["name"] != topic:
                        continue
                    table = log.table(topic, t["multi_id"]).to_arrow()
                    n = table.num_rows
                    arrays = []
                    for field in schema:
                        if field.name == "log":
                            arrays.append(pa.array([logs[path]] * n, pa.string()))
                        elif field.name == "multi_id":
                            arrays.append(pa.array([t["multi_id"]] * n, pa.int16()))
                        elif field.name in table.column_names:
                            arrays.append(table.column(field.name).combine_chunks().cast(field.type))
                        else:
                            arrays.append(pa.nulls(n, field.type))
                    for b in pa.Table.from_arrays(arrays, schema=schema).to_batches(max_chunksize=1 << 16):
                        yield b

    return rows


_METADATA = pa.schema(
    [
        ("path", pa.string()),
        ("log", pa.string()),
        ("error", pa.string()),
        ("sys_name", pa.string()),
        ("ver_sw", pa.string()),
        ("ver_hw", pa.string()),
        ("start_timestamp", pa.int64()),
        ("start_utc", pa.string()),
        ("sha256", pa.string()),
        ("duration_s", pa.float64()),
        ("rows", pa.int64()),
        ("dropouts", pa.int64()),
        ("dropout_ms", pa.int64()),
        ("analysis", pa.string()),
    ]
)


def metadata(spark, files):
    """One row per log of ``files`` (see the module docs)."""
    logs = dict(_logs(files))

    def per_log(batches: Iterator[pa.RecordBatch]) -> Iterator[pa.RecordBatch]:
        for batch in batches:
            d = batch.to_pydict()
            rows: Dict[str, list] = {f.name: [] for f in _METADATA}
            for path, content in zip(d["path"], d["content"]):
                row = dict.fromkeys(rows)
                row["path"], row["log"] = path, logs[path]
                row["sha256"] = hashlib.sha256(content).hexdigest()
                try:
                    log = _open(content)
                    info = log.info
                    text = lambda k: info[k] if isinstance(info.get(k), str) else None  # noqa: E731
                    row["sys_name"], row["ver_sw"], row["ver_hw"] = text("sys_name"), text("ver_sw"), text("ver_hw")
                    row["start_timestamp"] = log.header["start_timestamp"]
                    row["start_utc"] = log.start_utc
                    ts = [t for t in log.topics()]
                    first = [t["first_timestamp"] for t in ts if t["first_timestamp"] is not None]
                    last = [t["last_timestamp"] for t in ts if t["last_timestamp"] is not None]
                    row["duration_s"] = (max(last) - min(first)) / 1e6 if first else None
                    row["rows"] = sum(t["rows"] for t in ts)
                    row["dropouts"] = len(log.dropouts)
                    row["dropout_ms"] = sum(ms for _, ms in log.dropouts)
                    row["analysis"] = json.dumps(log.analysis())
                except Exception as e:  # a log that cannot be read: its error, not a failure
                    row["error"] = str(e)
                for k in rows:
                    rows[k].append(row[k])
            yield pa.RecordBatch.from_pydict(rows, schema=_METADATA)

    return files.select("path", "content").mapInArrow(per_log, _to_spark_schema(_METADATA))


def convert(spark, input_glob: str, output_path: str, topics: Optional[Sequence[str]] = None) -> Dict[str, int]:
    """Converts the logs of ``input_glob`` to the hive layout at ``output_path``:
    ``topic=<t>/log=<l>/multi_id=<m>/`` per topic (only ``topics`` if given), and the
    metadata table at ``output_path/metadata``. Returns the rows written per topic."""
    files = spark.read.format("binaryFile").load(input_glob)
    written = {}
    for topic, df in _topic_frames(spark, files, topics).items():
        df.write.mode("overwrite").partitionBy("log", "multi_id").parquet(
            f"{output_path.rstrip('/')}/topic={topic}"
        )
        written[topic] = spark.read.parquet(f"{output_path.rstrip('/')}/topic={topic}").count()
    metadata(spark, files).write.mode("overwrite").parquet(f"{output_path.rstrip('/')}/metadata")
    return written
