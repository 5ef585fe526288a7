"""The native API: a ``Log`` over the Rust reader and its topics as Arrow tables."""

from __future__ import annotations

import io
import json
import operator
import os
import warnings
from typing import Any, BinaryIO, Dict, List, Optional, Sequence, Union

from . import _ulog

__all__ = ["Log", "Table", "open", "to_parquet"]


class Table:
    """One topic instance's columns, as the ``arrow`` feature types them, handed over
    through the Arrow PyCapsule interface: ``pyarrow.table(t)``, ``polars.DataFrame(t)`` and
    DuckDB (``duckdb.sql("select * from t")``) take them without a copy."""

    def __init__(self, native: "_ulog.Table"):
        self._native = native

    def __arrow_c_stream__(self, requested_schema: Any = None) -> Any:
        return self._native.__arrow_c_stream__(requested_schema)

    def __arrow_c_schema__(self) -> Any:
        return self._native.__arrow_c_schema__()

    @property
    def num_rows(self) -> int:
        """Rows."""
        return self._native.num_rows

    @property
    def column_names(self) -> List[str]:
        """Column names, in order (pyulog's: ``timestamp``, ``q[0]``, ``esc[3].esc_rpm``)."""
        return self._native.column_names

    @property
    def topic(self) -> str:
        """The topic."""
        return self._native.topic

    @property
    def multi_id(self) -> int:
        """The instance."""
        return self._native.multi_id

    def __len__(self) -> int:
        return self._native.num_rows

    def __repr__(self) -> str:
        return repr(self._native)

    def numpy(self) -> Dict[str, Any]:
        """The columns as numpy arrays (text columns as lists of str)."""
        return self._native.numpy()

    def to_arrow(self) -> Any:
        """A ``pyarrow.Table`` (needs pyarrow)."""
        import pyarrow

        return pyarrow.table(self)

    def to_pandas(self) -> Any:
        """A ``pandas.DataFrame`` (needs pandas and pyarrow)."""
        return self.to_arrow().to_pandas()

    def to_polars(self) -> Any:
        """A ``polars.DataFrame`` (needs polars)."""
        import polars

        return polars.DataFrame(self)


class _Closed:
    """What a closed ``Log`` holds instead of its reader: any use is a ``ValueError``."""

    def __getattr__(self, name: str) -> Any:
        raise ValueError("the log is closed")

    def __repr__(self) -> str:
        return "<ulog.Log (closed)>"


_CLOSED = _Closed()


class Log:
    """A log read by the Rust reader: every intact message of a damaged file, with what
    recovery skipped in ``diagnostics``. Open one with ``ulog.open``; ``with ulog.open(path)
    as log:`` closes it at the end of the block."""

    def __init__(self, native: "_ulog.Log"):
        self._native: Union["_ulog.Log", _Closed] = native

    def close(self) -> None:
        """Lets the log go: its memory map (or its bytes) is released once nothing else
        holds it, and tables already made keep their columns. Using the log afterwards
        raises ``ValueError``, as a closed file does."""
        self._native = _CLOSED

    @property
    def closed(self) -> bool:
        """Whether ``close`` was called."""
        return self._native is _CLOSED

    def __enter__(self) -> "Log":
        if self.closed:
            raise ValueError("the log is closed")
        return self

    def __exit__(self, *exc: Any) -> None:
        self.close()

    @property
    def name(self) -> str:
        """The file's name (empty for bytes)."""
        return self._native.name

    @property
    def header(self) -> Dict[str, Any]:
        """``version``, ``start_timestamp`` (µs), ``start_utc`` (text when the header holds a
        date, else None; ``Log.start_utc`` falls back to the first GPS fix)."""
        return self._native.header

    @property
    def start_utc(self) -> Optional[str]:
        """The log's start as UTC text (``2021-04-21 06:30:58.437779 UTC``): the header's date
        when it holds one (``header["start_utc"]``), else from the first GPS fix, as
        ``metadata.json``'s ``start_utc`` and the Parquet files' ``ulog.start_utc``; else
        None."""
        return self._native.start_utc

    @property
    def info(self) -> Dict[str, Any]:
        """Info values by key (whole keys, spaces included)."""
        return self._native.info

    @property
    def multi_info(self) -> Dict[str, List[List[Any]]]:
        """Multi info values by key: a list of values, each the list of its parts."""
        return self._native.multi_info

    @property
    def parameters(self) -> Dict[str, Union[int, float]]:
        """Parameters as logging started."""
        return self._native.parameters

    @property
    def parameter_changes(self) -> List[tuple]:
        """Parameter changes: ``(timestamp µs, name, value)``."""
        return self._native.parameter_changes

    @property
    def default_parameters(self) -> List[tuple]:
        """Default parameters: ``(default_types bits, name, value)``."""
        return self._native.default_parameters

    @property
    def logged_messages(self) -> List[tuple]:
        """Logged strings: ``(timestamp µs, level byte, tag or None, text)``."""
        return self._native.logged_messages

    @property
    def dropouts(self) -> List[tuple]:
        """Dropouts: ``(timestamp µs, duration ms)``."""
        return self._native.dropouts

    @property
    def diagnostics(self) -> List[tuple]:
        """What recovery skipped or found odd: ``(byte offset, what)``."""
        return self._native.diagnostics

    def messages(self, tagged: bool = False) -> List[tuple]:
        """Logged strings and PX4 events as ``ulog messages`` lists them:
        ``(timestamp µs, level, text)``; with ``tagged``, also the tagged strings (``C``
        messages, which pyulog's ``ulog_messages`` leaves out), their text as
        ``[tag N] text``, as ``ulog messages --tagged`` lists them."""
        return self._native.messages(tagged)

    def events(self) -> List[Dict[str, Any]]:
        """PX4 events decoded with the metadata the log embeds."""
        return self._native.events()

    def topics(self) -> List[Dict[str, Any]]:
        """Topic instances with rows: ``name``, ``multi_id``, ``rows``, ``first_timestamp``
        and ``last_timestamp`` (µs: the first and the last row's in file order, so on a log
        whose timestamps jump back the first may be the later)."""
        return self._native.topics()

    def table(
        self,
        topic: str,
        multi_id: int = 0,
        columns: Optional[Sequence[str]] = None,
        start: Optional[float] = None,
        end: Optional[float] = None,
    ) -> Table:
        """A topic instance's columns (only ``columns`` if given, in that order: names, or
        one name as a str; an empty list gives the rows with no column), the rows from
        ``start`` to ``end`` seconds (of the log's clock, as ``ulog csv --start --end``
        takes them). The window is positional, as pyulog's ``ulog2csv`` makes it: from the
        first row whose timestamp is at or after ``start`` up to (not including) the first
        row at or after ``end``, so on a log whose timestamps jump back (a damaged one) it
        is not a filter on each row's time. KeyError (naming the closest) for a topic,
        instance or column the log lacks; TypeError for a ``multi_id`` that is not an int;
        ValueError for a column named twice, a bound that is NaN or infinite, or an ``end``
        at or before ``start``; a UserWarning, saying where the rows lie, when the window
        holds none of the instance's rows."""
        if isinstance(columns, str):
            columns = [columns]
        if columns is not None:
            columns = list(columns)
            repeated = sorted({c for c in columns if columns.count(c) > 1})
            if repeated:
                raise ValueError(f"columns named more than once: {repeated}")
        multi_id = _count("multi_id", multi_id)
        if not 0 <= multi_id <= 255:
            # Beyond what an instance number can be: the log's instances of the topic, as
            # for any instance it lacks (or the native error if it lacks the topic).
            have = sorted(t["multi_id"] for t in self.topics() if t["name"] == topic)
            if have:
                raise KeyError(f"`{topic}` has no instance {multi_id} (instances: {have})")
            multi_id = 0
        table = Table(self._native.table(topic, multi_id, columns, start, end))
        if table.num_rows == 0 and (start is not None or end is not None):
            # As `ulog csv` says it: a window none of the instance's rows lie in (seconds
            # where microseconds were meant, say) is said, with where the rows lie.
            span = next(
                (
                    (t["first_timestamp"], t["last_timestamp"])
                    for t in self.topics()
                    if t["name"] == topic and t["multi_id"] == multi_id
                ),
                None,
            )
            if span is not None:
                first, last = min(span), max(span)
                warnings.warn(
                    f"no row of `{topic}` #{multi_id} lies{_ulog.window_words(start, end)} "
                    f"(its rows run from {_seconds(first)} s to {_seconds(last)} s)",
                    stacklevel=2,
                )
        return table

    def tables(self) -> Dict[tuple, Table]:
        """Every topic instance's table, by ``(topic, multi_id)``, made in one pass over the
        file on every core: for all of a log's topics, faster than ``table()`` for each."""
        return {(t.topic, t.multi_id): Table(t) for t in self._native.tables()}

    def analysis(self) -> Dict[str, Any]:
        """The flight analysis (what ``ulog analyze --json`` prints)."""
        return json.loads(self._native.analysis_json())

    def __repr__(self) -> str:
        return repr(self._native)


def _seconds(us: int) -> str:
    """Microseconds as seconds, in the shortest digits that give them back and never with an
    exponent (as the ``ulog`` command prints times: ``20.33``, ``5``, ``0.00005``)."""
    import numpy

    return numpy.format_float_positional(us / 1e6, trim="-")


def _count(name: str, value: Any) -> int:
    """``value`` as an int (numpy's integers too, as ``operator.index`` takes them; not a
    bool), else a TypeError naming the argument."""
    if isinstance(value, bool):
        raise TypeError(f"{name} must be an int, not bool")
    try:
        return operator.index(value)
    except TypeError:
        raise TypeError(f"{name} must be an int, not {type(value).__name__}") from None


def open(  # noqa: A001
    source: Union[str, "os.PathLike[str]", bytes, bytearray, memoryview, BinaryIO],
) -> Log:
    """Opens a log: a path (memory-mapped, not read into memory), the file's bytes, or a
    binary file object (read from its position to its end, into memory).

    A path must name a regular file (a folder, device or pipe is a ``ULogIOError``). Like
    every memory-mapped reader, a ``Log`` opened from a path needs the file not to be
    truncated or rewritten in place while it is open: the operating system ends the
    process (``SIGBUS``) when a page the file no longer has is read. For a file that may
    change meanwhile (a log being downloaded again, rotated), open its bytes:
    ``ulog.open(pathlib.Path(path).read_bytes())``."""
    if isinstance(source, (bytearray, memoryview)):
        source = bytes(source)
    elif not isinstance(source, (str, bytes, os.PathLike)):
        read = getattr(source, "read", None)
        if read is None:
            raise TypeError(
                "ulog.open takes a path, the file's bytes or a binary file object, not "
                f"{type(source).__name__}"
            )
        # A text file object is refused before it is read (its read() would decode the log
        # as text and fail on the first invalid byte).
        if isinstance(source, io.TextIOBase):
            raise TypeError("ulog.open needs a binary file object (opened with 'rb')")
        source = read()
        if not isinstance(source, (bytes, bytearray, memoryview)):
            raise TypeError("ulog.open needs a binary file object (opened with 'rb')")
        source = bytes(source)
    return Log(_ulog.Log.open(source))


def to_parquet(
    paths: Union[str, "os.PathLike[str]", Sequence[Union[str, "os.PathLike[str]"]]],
    out_dir: Union[str, "os.PathLike[str]"],
    layout: str = "per-log",
    topics: Optional[Sequence[str]] = None,
    threads: Optional[int] = None,
    analysis: bool = True,
    start: Optional[float] = None,
    end: Optional[float] = None,
) -> List[Dict[str, Any]]:
    """Converts logs to Parquet as ``ulog parquet`` does (``layout`` ``"per-log"`` or
    ``"hive"``, only ``topics`` if given, ``threads`` logs at once, the flight analysis in
    each ``metadata.json`` unless ``analysis=False``, only the rows from ``start`` to
    ``end`` seconds as ``ulog parquet --start --end`` takes them; ``topics`` names, or one
    name as a str, never an empty list; ``threads`` None for one per core). One dict per log, in order: ``ok`` and what it wrote (``files``,
    ``metadata``, ``log_dir``, ``notes``, and ``skipped``: what reading left out, as
    ``unreadable_topics`` of (topic, msg_id, why), ``misfit_rows`` of (topic, multi_id,
    rows), ``orphan_rows``, ``unusable_messages``, ``damaged_bytes`` and
    ``ignored_appended_offsets`` (appended data not read); and ``said``, the
    lines ``ulog parquet`` prints of the log on stderr), or ``error``; a log that fails does
    not stop the others. What ``ulog parquet`` says on stderr is a ``UserWarning``: each
    log's ``said`` (a topic of ``topics`` the log does not define, its notes, what reading
    left out, no file written), and a topic of ``topics`` that no converted log has rows of
    (in the window). Before any log is converted, as ``ulog parquet -m``: KeyError for a
    topic of ``topics`` that no log defines (naming the closest topics the logs have);
    ValueError for a bound that is NaN, infinite or beyond any time a log can hold (2^64 µs;
    a window after a log's rows is a warning, not an error), an ``end`` at or
    before ``start``, an empty ``topics`` or a ``threads`` below 1 (TypeError for one that
    is not an integer). The GIL is released while converting; called from the main thread
    (where Python runs signal handlers), Ctrl-C (any signal whose handler raises) stops the
    conversion after the logs under way, whose files are whole, leaves the logs not started
    alone, and raises the handler's exception (``KeyboardInterrupt``) once they are done."""
    if isinstance(paths, (str, os.PathLike)):
        paths = [paths]
    if isinstance(topics, str):
        topics = [topics]
    if topics is not None:
        topics = list(topics)
        if not topics:
            raise ValueError("topics=[] names no topic; topics=None converts every topic")
    if threads is not None:
        threads = _count("threads", threads)
        if threads < 1:
            raise ValueError(
                f"threads is how many logs are converted at once: 1 or more (None: one per core), not {threads}"
            )
    results = _ulog.to_parquet(
        [os.fspath(p) for p in paths],
        os.fspath(out_dir),
        layout,
        topics,
        threads,
        analysis,
        start,
        end,
    )
    for r in results:
        for line in r.get("said", []):
            warnings.warn(f"{r['log']}: {line}", stacklevel=2)
    if topics is not None and any(r["ok"] for r in results):
        # (When every log failed, their errors say why; no topic is to blame.)
        written = {f["topic"] for r in results if r["ok"] for f in r["files"]}
        for topic in topics:
            if topic not in written:
                warnings.warn(f"no log has rows of topic `{topic}`{_ulog.window_words(start, end)}", stacklevel=2)
    return results
