#!/usr/bin/env python3
"""Writes ``hot-symbols.txt``: the functions of the extension module that a Python user's
common reads run, in the order the linker is to put them first in the module's code
(``python/build.rs`` hands the file to the linker, LLD's ``--symbol-ordering-file``).

Why: the kernel maps an extension's code into a process 64 to 128 KiB at a time around each
page it runs. Spread over 5.6 MB of code, the 140 KB that ``import ulog`` and
``ulog.ULog(path)`` run mapped 1.7 MiB of it into the process, which counted in its peak
memory; packed together they map about 0.25 MiB.

How: the module built as maturin builds the package, but not stripped (the names are those
of the stripped one), run under valgrind's callgrind, which lists every function that ran.
A name carries a hash of its crate's build settings (for a generic function, of the crate
that instantiates it: a `cargo build` of the module names those otherwise than maturin's
build), not of its code, so the list stays right while the code changes; a function missing
from it is only placed elsewhere. Run this again when the functions a read runs have changed
much (new dependency versions rename theirs):

    python python/link/hot_symbols.py [--so UNSTRIPPED.so] [--corpus DIR]

Without `--so` it builds the wheel itself (`maturin build --strip false`). It needs
valgrind, and maturin and numpy in the Python that runs it.
"""

import argparse
import os
import re
import shutil
import subprocess
import sys
import tempfile
import zipfile
from pathlib import Path

HERE = Path(__file__).resolve().parent
ROOT = HERE.parent.parent

# What is run, in this order: the names a workload adds come after those of the ones before
# it, so what `ulog.ULog` runs (the drop-in for pyulog, the most used) is packed first.
WORKLOADS = [
    (
        "import ulog; ulog.ULog(path) and pyulog's use of it",
        ["pyulog/sample_log_small.ulg"],
        """
u = ulog.ULog(p)
n = sum(len(d.data['timestamp']) for d in u.data_list)
u.get_dataset('vehicle_attitude').data['q[0]']
u.msg_info_dict, u.initial_parameters, u.logged_messages, u.get_version_info_str()
""",
    ),
    (
        "ulog.ULog on logs of other shapes (appended data, damage, events, old PX4)",
        [
            "pyulog/sample_appended_multiple.ulg",
            "pyulog/sample_2016.ulg",
            "pyulog/sample_px4_events.ulg",
            "px4-ulog-rs/corrupt_unregistered_msg_id.ulg",
        ],
        """
u = ulog.ULog(p)
n = sum(len(d.data['timestamp']) for d in u.data_list)
""",
    ),
    (
        "ulog.open with table(), tables() and numpy()",
        ["pyulog/sample_log_small.ulg"],
        """
log = ulog.open(p)
n = sum(log.table(t['name'], t['multi_id']).num_rows for t in log.topics())
log.tables()
log.table('vehicle_attitude').numpy()
""",
    ),
]

# Run when the module is loaded, from the C runtime's startup code (`crtbegin.o`), where
# callgrind does not name it.
AT_LOAD = ["frame_dummy"]

CHILD = """
import sys, numpy, ulog
for p in sys.argv[1:]:
{body}
"""


def functions_run(callgrind_out: Path, obj: str) -> list:
    """The functions of the object whose path ends with `obj` that ran, once each, in the
    file's order (callgrind names an object or function once in full, later by its number)."""
    names = {"ob": {}, "fn": {}}
    current = None
    seen, out = set(), []

    def name(kind, text):
        m = re.match(r"\((\d+)\)(?: (.*))?$", text)
        if not m:
            return text
        if m.group(2) is not None:
            names[kind][m.group(1)] = m.group(2)
        return names[kind].get(m.group(1))

    for line in callgrind_out.read_text().splitlines():
        key, _, value = line.partition("=")
        if key in ("ob", "cob"):
            ob = name("ob", value.strip())
            if key == "ob":
                current = ob
        elif key in ("fn", "cfn"):
            fn = name("fn", value.strip())
            if key == "fn" and current and current.endswith(obj) and fn:
                # Unnamed code (PLT stubs) shows as an address; a recursion as `name'2`.
                fn = re.sub(r"'\d+$", "", fn)
                if not fn.startswith("0x") and fn not in seen:
                    seen.add(fn)
                    out.append(fn)
    return out


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--so", help="an unstripped module of maturin's build (default: build one)")
    ap.add_argument(
        "--corpus",
        default=os.environ.get("ULOG_CORPUS", str(ROOT.parent / "shared/testdata/ulog")),
    )
    ap.add_argument("--out", default=str(HERE / "hot-symbols.txt"))
    args = ap.parse_args()
    # Absolute: the children run in another folder.
    corpus = Path(args.corpus).resolve()
    if not shutil.which("valgrind"):
        sys.exit("hot_symbols.py needs valgrind")
    listed, seen = [], set()
    with tempfile.TemporaryDirectory() as tmp:
        if args.so:
            so = Path(args.so)
        else:
            wheels = Path(tmp) / "wheels"
            subprocess.run(
                [sys.executable, "-m", "maturin", "build", "--strip", "false", "-o", str(wheels)],
                cwd=ROOT / "python", check=True,
            )
            (wheel,) = wheels.glob("*.whl")
            with zipfile.ZipFile(wheel) as z:
                (member,) = [n for n in z.namelist() if re.fullmatch(r"ulog/_ulog[^/]*\.so", n)]
                so = Path(z.extract(member, Path(tmp) / "unpacked"))
        if b".symtab" not in so.read_bytes():
            sys.exit(f"{so} has no symbols: build it with `maturin build --strip false`")
        pkg = Path(tmp) / "ulog"
        shutil.copytree(ROOT / "python/python/ulog", pkg)
        shutil.copy(so, pkg / "_ulog.abi3.so")
        # Bytecode first, as an installed package has it: compiling is not a read.
        subprocess.run([sys.executable, "-m", "compileall", "-q", str(pkg)], check=True)
        env = dict(os.environ, PYTHONPATH=tmp)
        for _, logs, _ in WORKLOADS:
            for log in logs:
                if not (corpus / log).is_file():
                    sys.exit(f"{corpus / log} not found: --corpus (or ULOG_CORPUS) "
                             "names the corpus folder")
        for k, (what, logs, body) in enumerate(WORKLOADS):
            out = Path(tmp) / f"callgrind.{k}"
            indented = "\n".join("    " + l for l in body.strip().splitlines())
            run = subprocess.run(
                [
                    "valgrind", "--tool=callgrind", "--demangle=no",
                    f"--callgrind-out-file={out}",
                    sys.executable, "-c", CHILD.format(body=indented),
                    *(str(corpus / log) for log in logs),
                ],
                # Run from the copy's folder: a `-c` script's first import path is the
                # current folder, which could hold another `ulog`.
                env=env, cwd=tmp, stdout=subprocess.DEVNULL, stderr=subprocess.PIPE, text=True,
            )
            if run.returncode != 0:
                sys.exit(f"{what}: failed under callgrind:\n{run.stderr[-3000:]}")
            # Sorted within a workload (callgrind's order varies from run to run; the
            # workload's functions are packed together either way).
            new = sorted(f for f in functions_run(out, "_ulog.abi3.so") if f not in seen)
            seen.update(new)
            listed.append((what, new))
            print(f"{what}: {len(new)} more functions", file=sys.stderr)

    rustc = subprocess.run(["rustc", "-V"], capture_output=True, text=True).stdout.strip()
    with open(args.out, "w") as f:
        f.write(
            "# The extension's functions that common reads run, placed first in its code by\n"
            "# the linker (python/build.rs). Written by python/link/hot_symbols.py: run it\n"
            "# again rather than edit this. The names are those of this rustc's build:\n"
            f"# {rustc}\n"
        )
        f.write("# run at load by the C runtime\n")
        f.writelines(n + "\n" for n in AT_LOAD if n not in seen)
        for what, names in listed:
            f.write(f"# {what}\n")
            f.writelines(n + "\n" for n in names)


if __name__ == "__main__":
    main()
