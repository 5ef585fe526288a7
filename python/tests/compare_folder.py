"""pyulog 1.3.0 and ``ulog.ULog`` on every file of some folders (a fuzzer's corpus, a folder
of odd logs): the same attributes and printed warnings (``test_compat.check_pair``), or the
same exception. Where pyulog does not finish within a time limit (its recovery loops forever
on many damaged inputs), ``ulog.ULog`` must return, or raise a ``ulog.ULogError``.

    python python/tests/compare_folder.py [--limit SECONDS] FOLDER...

A folder with ``.ulg`` files is read for those (a corpus folder, its oracles and notes left
out); one without, for every file (a fuzzer's corpus, whose files have no extension). The
time limit is ``--limit`` (0.3 s) plus a second per MB of the file, pyulog's own pace on a
damaged log.

Prints a progress line every 200 files, then the counts and every difference; exits 1 if
there was one. Needs pyulog==1.3.0 and the ulog package installed."""

import argparse
import os
import sys

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))

from test_compat import compare_with_pyulog  # noqa: E402


def main():
    parser = argparse.ArgumentParser(
        description=__doc__.split("\n\n")[0], formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("folders", nargs="+", metavar="FOLDER")
    parser.add_argument("--limit", type=float, default=0.3,
                        help="seconds pyulog is given, plus one per MB of the file (0.3)")
    args = parser.parse_args()
    limit = args.limit
    for folder in args.folders:
        if not os.path.isdir(folder):
            parser.error(f"{folder} is not a folder")
    counts = {"same": 0, "refused": 0, "looped": 0}
    differences = []
    n = 0
    for folder in args.folders:
        names = sorted(f for f in os.listdir(folder) if os.path.isfile(os.path.join(folder, f)))
        if any(f.endswith(".ulg") for f in names):
            names = [f for f in names if f.endswith(".ulg")]
        for name in names:
            path = os.path.join(folder, name)
            with open(path, "rb") as f:
                data = f.read()
            outcome = compare_with_pyulog(data, limit + len(data) / 1e6)
            outcome = {"looped, raised": "looped"}.get(outcome, outcome)
            if outcome in counts:
                counts[outcome] += 1
            else:
                differences.append((path, outcome))
            n += 1
            if n % 200 == 0:
                print(f"{n} files, {len(differences)} differences", flush=True)
    print(f"files {n}: the same {counts['same']}, refused alike {counts['refused']}, "
          f"pyulog not finished in time {counts['looped']}, "
          f"differences {len(differences)}")
    for path, why in differences:
        print(f"{path}: {why}")
    sys.exit(1 if differences else 0)


if __name__ == "__main__":
    main()
