"""``ulog.ULog`` against pyulog 1.3.0, side by side on every corpus log: every attribute a
pyulog script uses, equal; arrays of the same dtype, bit for bit."""

import io

import numpy as np
import pyulog
import pytest

import ulog

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
    assert ours.get_version_info() == theirs.get_version_info()
    assert ours.get_version_info_str() == theirs.get_version_info_str()
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
