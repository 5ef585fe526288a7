"""PX4 ULog flight logs on the Rust reader.

- ``ulog.ULog``: pyulog 1.3.0's ``ULog``, the same attributes and answers, many times faster
  (``from ulog import ULog`` instead of ``from pyulog import ULog``).
- ``ulog.open(path_or_bytes)`` (or a binary file object): a ``Log`` with everything the
  reader recovers, its topics as Arrow tables (``log.table("vehicle_attitude")``) that
  pyarrow, Polars and DuckDB take without a copy.
- ``ulog.to_parquet(paths, out_dir)``: per-topic Parquet files and a ``metadata.json`` per
  log, as ``ulog parquet`` writes them.
- ``ulog.spark``: the same on Apache Spark (needs pyspark; imported on first use).
- The ``ulog`` command-line tool (``python -m ulog``).
"""

from ._native import Log, Table, open, to_parquet
from ._pyulog import ULog
from ._ulog import NotAULogError, ULogError, ULogIOError, UnsupportedFlagError, __version__

# pyulog's names for its exceptions, so that `except ULogException` keeps working.
ULogException = ULogError
ULogIncompatibleFlagException = UnsupportedFlagError

__all__ = [
    "Log",
    "NotAULogError",
    "Table",
    "ULog",
    "ULogError",
    "ULogException",
    "ULogIOError",
    "ULogIncompatibleFlagException",
    "UnsupportedFlagError",
    "__version__",
    "to_parquet",
]
# Not `open`: `from ulog import *` in place of `from pyulog import *` (as Flight Review
# imports pyulog) must not hide the built-in `open`. It is `ulog.open`.


def __getattr__(name: str):
    # `ulog.spark` at hand after `import ulog`, as the other names are: imported on first use
    # (it needs pyarrow, and pyspark to run).
    if name == "spark":
        import importlib

        return importlib.import_module(".spark", __name__)
    raise AttributeError(f"module 'ulog' has no attribute {name!r}")
