#!/usr/bin/env python3
"""Python readers side by side on one log, in one run, interleaved, each in a fresh
process (its peak resident memory its own): pyulog 1.3.0's ``ULog(path)``, ``ulog.ULog(path)``
(the same objects on the Rust reader), and ``ulog.open(path)`` with ``table()`` of every
topic instance. Prints the medians of wall time and peak RSS, and the ratios.

Each process imports numpy and the one library it measures, as a script using that library
does, so the peak holds that library's code and no other's. Both read their modules from
bytecode, as installed by pip: ``ulog``'s are compiled first (a ``maturin develop`` build
leaves none, and with ``PYTHONDONTWRITEBYTECODE`` set each import would compile them again).

    python bench.py LOG [--runs N] [--cache read|pages|keep]

How the page cache holds the log moves ``ulog``'s times (it maps the log; pyulog reads it),
so the log's cached pages are dropped and read back first, as ``versus`` does: from start to
end (``read``, the default: large folios), one 4 KiB page at a time without read-ahead
(``pages``: small folios, as a log cached for hours drifts to), or left as found (``keep``).

Build the package optimized first (``maturin develop`` in ``python/``, or ``pip install
./python``: both use the workspace's ``wheel`` profile): a debug build measures nothing.
"""

import argparse
import json
import platform
import statistics
import subprocess
import sys

# What is timed (after the imports), and the library it needs.
WORK = {
    "pyulog.ULog": (
        "pyulog", "u = pyulog.ULog(PATH); n = sum(len(d.data['timestamp']) for d in u.data_list)"
    ),
    "ulog.ULog": (
        "ulog", "u = ulog.ULog(PATH); n = sum(len(d.data['timestamp']) for d in u.data_list)"
    ),
    "ulog.open + table()": (
        "ulog",
        "log = ulog.open(PATH); "
        "n = sum(log.table(t['name'], t['multi_id']).num_rows for t in log.topics())",
    ),
    "ulog.open + tables()": (
        "ulog", "log = ulog.open(PATH); n = sum(t.num_rows for t in log.tables().values())"
    ),
}

# json is imported once the peak is taken: `ulog` imports it, pyulog does not. After it, the
# memory of the extension module's mappings (its code, read-only data and data, in KiB; Linux):
# how much of the peak is the module (`python/link/hot_symbols.py` says why it is small).
CHILD = """
import resource, sys, time
import numpy, {library}
PATH = sys.argv[1]
t = time.perf_counter()
{work}
wall = time.perf_counter() - t
rss_mib = resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 1024
import json
module_kib = 0
try:
    ours = False
    for line in open("/proc/self/smaps"):
        first = line.split() or [""]
        if "-" in first[0] and ":" not in first[0]:
            ours = line.rstrip().endswith(".so") and "/ulog/_ulog" in line
        elif ours and first[0] == "Rss:":
            module_kib += int(first[1])
except OSError:
    pass
print(json.dumps({{"wall": wall, "rss_mib": rss_mib, "rows": n, "module_kib": module_kib}}))
"""


def cpu_model() -> str:
    try:
        for line in open("/proc/cpuinfo"):
            if line.startswith("model name"):
                return line.split(":", 1)[1].strip()
    except OSError:
        pass
    return platform.processor() or "unknown"


def compile_ulog():
    """Writes the bytecode of the ``ulog`` package's modules, as ``pip install`` does."""
    import compileall
    import importlib.util
    import os

    spec = importlib.util.find_spec("ulog")
    if spec is None or spec.origin is None:
        sys.exit("the ulog package is not installed (maturin develop in python/, or pip install ./python)")
    compileall.compile_dir(os.path.dirname(spec.origin), quiet=1)


def prepare_cache(path: str, cache: str) -> str:
    """Puts the log in the page cache as ``cache`` says; returns how, for the report."""
    import os

    if cache == "keep":
        return "page cache as found"
    if not hasattr(os, "posix_fadvise"):
        sys.exit("--cache read and pages need posix_fadvise (Linux): use --cache keep")
    fd = os.open(path, os.O_RDONLY)
    try:
        os.fdatasync(fd)  # written pages not yet on disk cannot be dropped
        os.posix_fadvise(fd, 0, 0, os.POSIX_FADV_DONTNEED)
        at = 0
        if cache == "read":
            while chunk := os.pread(fd, 1 << 20, at):
                at += len(chunk)
            return "log read into the page cache once, start to end (large folios)"
        os.posix_fadvise(fd, 0, 0, os.POSIX_FADV_RANDOM)
        while chunk := os.pread(fd, 4096, at):
            at += len(chunk)
        return "log read into the page cache one 4 KiB page at a time (small folios)"
    finally:
        os.close(fd)


def main():
    parser = argparse.ArgumentParser(
        description="pyulog 1.3.0 and the ulog package side by side on one log "
        "(needs both, and numpy)")
    parser.add_argument("log")
    parser.add_argument("--runs", type=int, default=3, help="runs of each reader (3)")
    parser.add_argument("--cache", choices=("read", "pages", "keep"), default="read",
                        help="how the log is put in the page cache first (read)")
    args = parser.parse_args()
    if args.runs < 1:
        parser.error("--runs takes a number of runs, at least 1")
    runs, path = args.runs, args.log
    compile_ulog()
    how = prepare_cache(path, args.cache)
    results = {name: [] for name in WORK}
    names = list(WORK)
    for r in range(runs):
        order = names if r % 2 == 0 else names[::-1]
        for name in order:
            out = subprocess.run(
                [sys.executable, "-c", CHILD.format(library=WORK[name][0], work=WORK[name][1]),
                 path],
                capture_output=True, text=True)
            if out.returncode != 0:
                # The child's own error (a missing module, an unreadable log), not a traceback
                # of this script.
                sys.exit(f"{name} failed:\n{out.stderr.strip()}")
            results[name].append(json.loads(out.stdout.strip().splitlines()[-1]))
    print(f"CPU: {cpu_model()}; {runs} runs each, interleaved; log {path}; {how}")
    med = {n: (statistics.median(x["wall"] for x in v), statistics.median(x["rss_mib"] for x in v))
           for n, v in results.items()}
    rows = {n: v[0]["rows"] for n, v in results.items()}
    module = {n: statistics.median(x["module_kib"] for x in v) for n, v in results.items()}
    base = med["pyulog.ULog"]
    for n, (wall, rss) in med.items():
        print(f"  {n:<22} wall {wall:8.3f} s   peak RSS {rss:8.1f} MiB   rows {rows[n]:>10}"
              f"   pyulog/this: wall {base[0] / wall:6.1f}x, RSS {rss - base[1]:+7.1f} MiB"
              f" ({rss / base[1]:.3f} of pyulog's)"
              + (f", module mapped {module[n]:.0f} KiB" if module[n] else ""))


if __name__ == "__main__":
    main()
