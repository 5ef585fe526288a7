"""``ulog.ULog`` against pyulog 1.3.0, side by side on every corpus log: every attribute a
pyulog script uses, equal; arrays of the same dtype, bit for bit."""

import io
import pickle
import subprocess
import sys

import numpy as np
import pyulog
import pytest

import ulog
from conftest import known_log

ATTRIBUTES = [
    "_debug", "_file_corrupt", "_start_timestamp", "_last_timestamp", "_msg_info_dict",
    "_msg_info_dict_types", "_msg_info_multiple_dict", "_msg_info_multiple_dict_types",
    "_initial_parameters", "_default_parameters", "_changed_parameters", "_message_formats",
    "_logged_messages", "_logged_messages_tagged", "_dropouts", "_data_list", "_subscriptions",
    "_filtered_message_ids", "_missing_message_ids", "_file_version", "_compat_flags",
    "_incompat_flags", "_appended_offsets", "_has_sync", "_sync_seq_cnt",
]


def same_value(a, b):
    """Equal, and of the same Python type (an int is not a float, bytes not str)."""
    if type(a) is not type(b):
        return False
    if isinstance(a, dict):
        return list(a.keys()) == list(b.keys()) and all(same_value(a[k], b[k]) for k in a)
    if isinstance(a, (list, tuple)):
        return len(a) == len(b) and all(same_value(x, y) for x, y in zip(a, b))
    if isinstance(a, float) and np.isnan(a):
        return np.isnan(b)
    return a == b


def outcome(call):
    """What a call gives: its value, or the type and text of what it raised."""
    try:
        return ("returned", call())
    except Exception as e:
        return ("raised", type(e), str(e))


def check_pair(theirs, ours, capsys=None):
    assert list(ours.__dict__) == list(theirs.__dict__) == ATTRIBUTES
    for name in ATTRIBUTES:
        t, o = getattr(theirs, name), getattr(ours, name)
        if name == "_message_formats":
            assert list(o) == list(t)
            for k in t:
                assert (o[k].name, o[k].fields) == (t[k].name, t[k].fields), k
                assert all(type(f) is tuple for f in o[k].fields)
        elif name == "_logged_messages":
            assert [(m.log_level, m.timestamp, m.message, m.log_level_str()) for m in o] == [
                (m.log_level, m.timestamp, m.message, m.log_level_str()) for m in t
            ]
        elif name == "_logged_messages_tagged":
            assert list(o) == list(t)
            for k in t:
                assert [(m.log_level, m.tag, m.timestamp, m.message) for m in o[k]] == [
                    (m.log_level, m.tag, m.timestamp, m.message) for m in t[k]
                ]
        elif name == "_dropouts":
            assert [(d.duration, d.timestamp) for d in o] == [(d.duration, d.timestamp) for d in t]
        elif name == "_data_list":
            assert len(o) == len(t)
            for dt, do in zip(t, o):
                assert (do.name, do.multi_id, do.msg_id, do.timestamp_idx) == (
                    dt.name, dt.multi_id, dt.msg_id, dt.timestamp_idx)
                assert [(f.field_name, f.type_str) for f in do.field_data] == [
                    (f.field_name, f.type_str) for f in dt.field_data]
                assert list(do.data) == list(dt.data)
                for k in dt.data:
                    a, b = dt.data[k], do.data[k]
                    assert a.dtype == b.dtype and a.dtype.str == b.dtype.str, (dt.name, k)
                    assert a.dtype.byteorder == b.dtype.byteorder
                    assert a.tobytes() == b.tobytes(), (dt.name, k)
                    assert b.flags.writeable
        else:
            assert same_value(t, o), name
    # The properties and methods a script uses.
    for prop in ["start_timestamp", "last_timestamp", "has_data_appended", "file_corruption",
                 "has_default_parameters"]:
        assert same_value(getattr(theirs, prop), getattr(ours, prop)), prop
    assert type(ours.has_data_appended) is int
    for bank in (0, 1):
        assert same_value(theirs.get_default_parameters(bank), ours.get_default_parameters(bank))
    # Values, or the same exception (pyulog's raises when `ver_sw_release` is not an integer).
    for method in ("get_version_info", "get_version_info_str"):
        assert outcome(getattr(ours, method)) == outcome(getattr(theirs, method)), method
    for d in theirs.data_list:
        assert ours.get_dataset(d.name, d.multi_id).msg_id == theirs.get_dataset(d.name, d.multi_id).msg_id
    with pytest.raises(IndexError):
        ours.get_dataset("no such topic")
    assert ours == ours


def test_every_corpus_log_reads_as_pyulog_reads_it(corpus_log, capsys):
    path = str(corpus_log)
    theirs = pyulog.ULog(path)
    printed_theirs = capsys.readouterr().out
    ours = ulog.ULog(path)
    printed_ours = capsys.readouterr().out
    assert printed_ours == printed_theirs, "the same warnings"
    check_pair(theirs, ours)


def test_options_and_file_objects_as_pyulog_takes_them(corpus_log, capsys):
    path = str(corpus_log)
    with open(path, "rb") as f:
        data = f.read()
    # A file object read from its position (after some bytes before the log), then closed.
    for args in [
        dict(message_name_filter_list=["vehicle_attitude", "battery_status"]),
        dict(message_name_filter_list=[]),
        dict(message_name_filter_list="vehicle_attitude_setpoint"),
        dict(parse_header_only=True),
    ]:
        bufs = []
        for _ in range(2):
            buf = io.BytesIO(b"junk" + data)
            buf.seek(4)
            bufs.append(buf)
        theirs = pyulog.ULog(bufs[0], **args)
        ours = ulog.ULog(bufs[1], **args)
        assert bufs[1].closed
        capsys.readouterr()
        check_pair(theirs, ours)
    # Beyond pyulog: a pathlib.Path is its str; anything else is a TypeError that says what
    # is taken (pyulog fails on a missing attribute).
    import pathlib

    check_pair(pyulog.ULog(path), ulog.ULog(pathlib.Path(path)))
    capsys.readouterr()
    with pytest.raises(TypeError, match="ULog takes a path or a binary file object .* not bytes"):
        ulog.ULog(data)


def test_written_logs_are_pyulogs_bytes(corpus_log, tmp_path):
    theirs = pyulog.ULog(str(corpus_log))
    ours = ulog.ULog(str(corpus_log))
    a, b = io.BytesIO(), io.BytesIO()
    try:
        theirs.write_ulog(a)
    except Exception as e:  # pyulog cannot write some logs: neither can we, alike
        with pytest.raises(type(e)):
            ours.write_ulog(b)
        return
    ours.write_ulog(b)
    assert b.getvalue() == a.getvalue()


def test_strict_strings_raise_unicode_errors():
    def build(*messages):
        f = bytearray(ulog.ULog.HEADER_BYTES + b"\x01" + (0).to_bytes(8, "little"))
        for ty, body in messages:
            f += len(body).to_bytes(2, "little") + bytes([ord(ty)]) + body
        return bytes(f)

    data = build(("I", b"\x09char[2] s\xff\xfe"))
    with pytest.raises(UnicodeDecodeError):
        ulog.ULog(io.BytesIO(data), disable_str_exceptions=False)
    u = ulog.ULog(io.BytesIO(data))
    assert u.msg_info_dict == {"s": ""} and not u.file_corruption
    with pytest.raises(ulog.ULogException, match="Header too short"):
        ulog.ULog(io.BytesIO(b"ULog"))
    with pytest.raises(ulog.ULogException, match="Failed to parse header"):
        ulog.ULog(io.BytesIO(bytes(16)))
    flags = bytearray(40)
    flags[9] = 1
    with pytest.raises(ulog.ULogIncompatibleFlagException):
        ulog.ULog(io.BytesIO(build(("B", bytes(flags)))))
    # A program that imported pyulog (as this test did) catches them with pyulog's own
    # classes too: `except pyulog.ULogException` where it switched `ULog` alone.
    with pytest.raises(pyulog.ULogException, match="Header too short") as e:
        ulog.ULog(io.BytesIO(b"ULog"))
    assert isinstance(e.value, ulog.NotAULogError)
    with pytest.raises(pyulog.ULogIncompatibleFlagException) as e:
        ulog.ULog(io.BytesIO(build(("B", bytes(flags)))))
    assert isinstance(e.value, ulog.UnsupportedFlagError)
    # Pickled as the package's own class.
    again = pickle.loads(pickle.dumps(e.value))
    assert type(again) is ulog.UnsupportedFlagError and again.args == e.value.args


def run_python(code: str) -> str:
    """What a fresh interpreter prints running `code` (the package on its path)."""
    out = subprocess.run(
        [sys.executable, "-c", code], capture_output=True, text=True, timeout=120, check=False
    )
    assert out.returncode == 0, out.stdout + out.stderr
    return out.stdout


def test_without_pyulog_imported_the_errors_are_the_packages_alone():
    printed = run_python(
        "import io, sys, ulog\n"
        "try:\n"
        "    ulog.ULog(io.BytesIO(b'ULog'))\n"
        "except ulog.NotAULogError as e:\n"
        "    print([c.__name__ for c in type(e).__mro__], 'pyulog' in sys.modules)\n"
    )
    assert printed.split("]")[0] == "['NotAULogError', 'ULogError', 'Exception', 'BaseException', 'object'"
    assert printed.strip().endswith("False")


def test_star_import_leaves_the_builtin_open():
    # `from ulog import *` in place of `from pyulog import *` (Flight Review's import).
    printed = run_python(
        "import builtins\nfrom ulog import *\nprint(open is builtins.open, ULog.__name__)"
    )
    assert printed.split() == ["True", "ULog"]


def test_a_timeout_signal_during_the_first_read_raises_the_handlers_exception():
    # Flight Review bounds a log's load with SIGALRM and a handler that raises. In a fresh
    # process the first read used to load numpy's C API, running Python code there: the
    # handler's exception made the numpy crate panic (a PanicException, which
    # `except Exception` does not catch). Alarms from 0.2 ms to 30 ms into the read.
    log = known_log("pyulog/sample.ulg")
    for delay in (0.0002, 0.001, 0.003, 0.01, 0.03):
        printed = run_python(
            "import signal, ulog\n"
            "class Timeout(Exception): pass\n"
            "def handler(signum, frame): raise Timeout()\n"
            "signal.signal(signal.SIGALRM, handler)\n"
            f"signal.setitimer(signal.ITIMER_REAL, {delay})\n"
            "try:\n"
            f"    ulog.ULog({str(log)!r})\n"
            # Stopped before anything is printed: an alarm after the read is a timeout too.
            "    signal.setitimer(signal.ITIMER_REAL, 0)\n"
            "    print('read')\n"
            "except Timeout:\n"
            "    print('timeout')\n"
        )
        assert printed.strip() in ("read", "timeout"), (delay, printed)


def damaged_copies(data: bytes, seed: str, count: int):
    """Damaged copies of a log: bytes overwritten, the log cut short, a run of bytes cut
    out, in turn; the same copies on every run (seeded by the log's name)."""
    import random

    rng = random.Random(seed)
    for k in range(count):
        d = bytearray(data)
        if k % 3 == 0:
            for _ in range(rng.randrange(1, 30)):
                d[rng.randrange(len(d))] = rng.randrange(256)
        elif k % 3 == 1:
            d = d[: rng.randrange(len(d))]
        else:
            a = rng.randrange(len(d))
            del d[a: a + rng.randrange(1, 5000)]
        yield bytes(d)


def ours_of(exception: type) -> type:
    """The exception ``ulog.ULog`` raises where pyulog raises ``exception``: the class of
    the same name in ``ulog`` for pyulog's own (``ULogException``...), else the same."""
    if exception.__module__.startswith("pyulog"):
        return getattr(ulog, exception.__name__)
    return exception


class PyulogTooLong(BaseException):
    """pyulog ran past its time (a BaseException: nothing in pyulog catches it)."""


def compare_with_pyulog(data: bytes, limit: float) -> str:
    """pyulog 1.3.0 and ``ulog.ULog`` on the same bytes: ``"same"`` (every attribute
    ``check_pair`` compares, the warnings printed), ``"refused"`` (the same exception),
    ``"looped"`` (pyulog did not finish within ``limit`` seconds, ours gave a log),
    ``"looped, raised"`` (ours raised a ``ulog.ULogError``, as pyulog may further on), or
    what differs."""
    import contextlib
    import signal

    def too_long(*_):
        raise PyulogTooLong

    previous = signal.signal(signal.SIGALRM, too_long)
    printed_theirs, raised = io.StringIO(), None
    signal.setitimer(signal.ITIMER_REAL, limit)
    try:
        with contextlib.redirect_stdout(printed_theirs):
            theirs = pyulog.ULog(io.BytesIO(data))
    except PyulogTooLong:
        signal.setitimer(signal.ITIMER_REAL, 0)
        try:
            with contextlib.redirect_stdout(io.StringIO()):
                ulog.ULog(io.BytesIO(data))
        except ulog.ULogError:
            return "looped, raised"
        except Exception as e:
            return f"pyulog does not finish; ulog.ULog raised {e!r}"
        return "looped"
    except Exception as e:
        raised = e
    finally:
        signal.setitimer(signal.ITIMER_REAL, 0)
        signal.signal(signal.SIGALRM, previous)
    printed_ours = io.StringIO()
    try:
        with contextlib.redirect_stdout(printed_ours):
            ours = ulog.ULog(io.BytesIO(data))
    except Exception as e:
        if raised is not None and isinstance(e, ours_of(type(raised))):
            return "refused"
        return f"ulog.ULog raised {e!r}, pyulog {raised!r}"
    if raised is not None:
        return f"pyulog raised {raised!r}, ulog.ULog read it"
    if printed_ours.getvalue() != printed_theirs.getvalue():
        return f"printed {printed_ours.getvalue()[:300]!r}, pyulog {printed_theirs.getvalue()[:300]!r}"
    try:
        check_pair(theirs, ours)
    except Exception as e:
        return f"differs: {type(e).__name__} {e}"[:500]
    return "same"


def test_damaged_logs_read_as_pyulog_reads_them(corpus_log):
    """What pyulog's recovery makes of a damaged log, `ulog.ULog` makes too (every
    attribute, the warnings printed), or the same exception type; where pyulog's recovery
    does not finish within 10 s (it can loop), ours must still give a log."""
    data = corpus_log.read_bytes()[: 512 << 10]
    for k, d in enumerate(damaged_copies(data, corpus_log.name, 6)):
        outcome = compare_with_pyulog(d, 10)
        assert outcome in ("same", "refused", "looped"), f"copy {k}: {outcome}"


def log_bytes(*messages) -> bytearray:
    """A log's bytes: the header, then each (type, body) as a message."""
    f = bytearray(ulog.ULog.HEADER_BYTES + b"\x01" + (0).to_bytes(8, "little"))
    for ty, body in messages:
        f += len(body).to_bytes(2, "little") + ty + body
    return f


def carried_subscription_log(last_type: bytes, back: int) -> bytes:
    """Definitions that end, at the end of the file, with the header of a message longer
    than what is left: pyulog seeks back by the size it asked for (and `back` more bytes),
    into the body of an earlier message of an unknown type, which holds a subscription;
    the data section starts there, and the rows after it are read."""
    fmt = b"t:uint64_t timestamp;uint8_t x;"
    body = b"\x00" + (0).to_bytes(2, "little") + b"t"
    subscription = len(body).to_bytes(2, "little") + b"A" + body
    rows = [(b"D", (0).to_bytes(2, "little") + (1000 * i).to_bytes(8, "little") + bytes([i]))
            for i in range(1, 6)]
    f = log_bytes((b"F", fmt), (b"Z", subscription), *rows)
    at = len(f) - len(subscription) - sum(3 + len(r[1]) for r in rows)
    end = len(f) + 3
    f += (end - back - at).to_bytes(2, "little") + last_type
    return bytes(f)


def test_a_short_read_ending_the_definitions_seeks_back_as_pyulog_does(capsys):
    # The last header a subscription (pyulog seeks back 3 more: to the message, it thinks)
    # or a corrupt one (2 more: the next byte, it thinks).
    for last_type, back in [(b"A", 3), (b"\x00", 2)]:
        data = carried_subscription_log(last_type, back)
        theirs = pyulog.ULog(io.BytesIO(data))
        printed = capsys.readouterr().out
        ours = ulog.ULog(io.BytesIO(data))
        assert capsys.readouterr().out == printed
        check_pair(theirs, ours)
        assert [d.data["x"].tolist() for d in ours.data_list] == [[1, 2, 3, 4, 5]], last_type


def test_a_short_read_pyulog_would_repeat_forever_ends(capsys):
    # A corrupt header at the end that seeks back to the first row: pyulog reads the same
    # rows and the same header again, forever; we go on from the next byte, once.
    fmt = b"t:uint64_t timestamp;uint8_t x;"
    rows = [(b"D", (0).to_bytes(2, "little") + (1000 * i).to_bytes(8, "little") + bytes([i]))
            for i in range(1, 4)]
    f = log_bytes((b"F", fmt), *rows)
    first_row = len(f) - sum(3 + len(r[1]) for r in rows)
    f += (len(f) + 3 - 2 - first_row).to_bytes(2, "little") + b"\x00"
    u = ulog.ULog(io.BytesIO(bytes(f)))
    assert u.file_corruption and u.data_list == []
    capsys.readouterr()


@pytest.mark.parametrize("name", ["filtered-damaged-log", "row-without-timestamp-ends-the-read"])
def test_a_filtered_read_is_pyulogs_where_pyulog_reads_more_rows_filtered(name, fuzz_regressions, capsys):
    """Two logs where pyulog's read filtered to one topic (`message_name_filter_list`) holds
    rows of it that its unfiltered read lacks; `ulog.ULog` with the same filter gives what
    pyulog gives, not the unfiltered read's rows (inputs the `pyulog_compat` fuzz target
    found). On the damaged log, pyulog's recovery goes another way when other topics are
    filtered out; on the other, a row of a format without `timestamp` raises a
    `struct.error` that ends pyulog's unfiltered read silently, a row its filtered read
    never parses."""
    path = str(fuzz_regressions / "pyulog_compat" / name)
    full = pyulog.ULog(path)
    check_pair(full, ulog.ULog(path))
    names = sorted({d.name for d in full.data_list})
    differs = []
    for topic in names:
        theirs = pyulog.ULog(path, [topic])
        ours = ulog.ULog(path, [topic])
        capsys.readouterr()
        check_pair(theirs, ours)
        rows = lambda u: [(d.multi_id, len(next(iter(d.data.values())))) for d in u.data_list if d.name == topic]
        if rows(theirs) != rows(full):
            differs.append(topic)
    # The case this test is for: pyulog's filtered read is not a subset of its full one.
    assert differs, f"pyulog reads {name} alike with and without a filter"


def test_recover_keeps_the_rows_after_a_row_pyulog_stops_at(capsys):
    """A row of a format without `timestamp` ends pyulog's reading (its `struct.error`
    taken for the end of the file): `ulog.ULog` stops there too, and `recover=True` keeps
    the rows after it, as written."""
    import struct

    def row(msg_id, t, x):
        return (b"D", struct.pack("<HQB", msg_id, t, x))

    data = bytes(log_bytes(
        (b"F", b"t:uint64_t timestamp;uint8_t x;"),
        (b"F", b"e:uint64_t time;uint8_t x;"),
        (b"A", struct.pack("<BH", 0, 1) + b"t"),
        (b"A", struct.pack("<BH", 0, 2) + b"e"),
        row(1, 2000, 1), row(2, 2500, 9), row(1, 3000, 2), row(1, 4000, 3),
    ))
    xs = lambda u: {d.name: d.data["x"].tolist() for d in u.data_list}
    theirs = pyulog.ULog(io.BytesIO(data))
    ours = ulog.ULog(io.BytesIO(data))
    check_pair(theirs, ours)
    assert xs(ours) == {"t": [1], "e": [9]} and not ours.file_corruption
    kept = ulog.ULog(io.BytesIO(data), recover=True)
    assert xs(kept) == {"t": [1, 2, 3], "e": [9]}
    assert kept.get_dataset("t").data["timestamp"].tolist() == [2000, 3000, 4000]
    capsys.readouterr()


def test_array_sizes_in_any_characters_read_as_pyulog_reads_them(capsys):
    """pyulog slices a field's type by characters (`type_str[a+1:-1]` without a `]`) and
    `int()` takes any Unicode decimal digit: so do we (a multi-byte last character once
    made the Rust reader panic; a fuzzer's input)."""
    import struct

    def msg(t, body):
        return struct.pack("<HB", len(body), ord(t)) + body

    head = b"ULog\x01\x12\x35\x01" + struct.pack("<Q", 0) + msg("B", bytes(40))
    for ty in ["float[2\u02db", "float[\u02db", "uint8_t[\u00e93]", "float[3]\u00e9", "float[\u0663]", "float[\u0967\u0966]"]:
        data = (
            head
            + msg("F", f"t:uint64_t timestamp;{ty} x;".encode())
            + msg("A", struct.pack("<BH", 0, 1) + b"t")
            + msg("D", struct.pack("<HQ", 1, 5) + bytes(8))
        )
        theirs = pyulog.ULog(io.BytesIO(data))
        printed = capsys.readouterr().out
        ours = ulog.ULog(io.BytesIO(data))
        assert capsys.readouterr().out == printed, ty
        check_pair(theirs, ours)
