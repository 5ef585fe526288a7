"""``ulog.ULog``: pyulog 1.3.0's ``ULog``, attribute for attribute, read by the Rust reader.

The file is read by ``ulog_runtime::compat::pyulog`` (pyulog's rules: what it keeps, skips
and cuts), which hands over every attribute and each dataset's rows as one buffer; this
module builds pyulog's objects on them: the same instance dictionary (25 keys, in pyulog's
order), the same nested classes, numpy columns that are strided views of one structured
array per dataset, as pyulog's are. ``write_ulog`` writes what pyulog writes, byte for byte.
"""

from __future__ import annotations

import contextlib
import copy
import os
import struct
import sys
from types import SimpleNamespace
from typing import Any, BinaryIO, Dict, Iterable, List, Optional, Tuple, Union

import numpy as np

from . import _ulog

__all__ = ["ULog"]

_LEVELS = {
    ord("0"): "EMERGENCY",
    ord("1"): "ALERT",
    ord("2"): "CRITICAL",
    ord("3"): "ERROR",
    ord("4"): "WARNING",
    ord("5"): "NOTICE",
    ord("6"): "INFO",
    ord("7"): "DEBUG",
}


class ULog:
    """A ULog file as pyulog 1.3.0's ``ULog`` reads it (same signature, attributes and
    methods; see pyulog's documentation). ``recover=True`` keeps every row the Rust reader
    recovers (intact rows pyulog's recovery loses in a damaged file, and the rows after a row
    whose format has no ``timestamp``, where pyulog stops reading), the rest as pyulog."""

    #: The 7 magic bytes every ULog file starts with (its version byte follows), as pyulog's.
    HEADER_BYTES = b"ULog\x01\x12\x35"
    #: The payload of an ``S`` (sync) message, as pyulog's.
    SYNC_BYTES = b"\x2F\x73\x13\x20\x25\x0C\xBB\x12"

    # pyulog's names for the message types: the type byte of each message's header (the
    # spec's ``msg_type``), e.g. ``MSG_TYPE_DATA == ord("D")``.
    MSG_TYPE_FORMAT = ord("F")
    MSG_TYPE_DATA = ord("D")
    MSG_TYPE_INFO = ord("I")
    MSG_TYPE_INFO_MULTIPLE = ord("M")
    MSG_TYPE_PARAMETER = ord("P")
    MSG_TYPE_PARAMETER_DEFAULT = ord("Q")
    MSG_TYPE_ADD_LOGGED_MSG = ord("A")
    MSG_TYPE_REMOVE_LOGGED_MSG = ord("R")
    MSG_TYPE_SYNC = ord("S")
    MSG_TYPE_DROPOUT = ord("O")
    MSG_TYPE_LOGGING = ord("L")
    MSG_TYPE_LOGGING_TAGGED = ord("C")
    MSG_TYPE_FLAG_BITS = ord("B")

    # pyulog's table: per type its `struct` code, size in bytes and numpy type.
    _UNPACK_TYPES: Dict[str, List[Any]] = {
        "int8_t": ["b", 1, np.int8],
        "uint8_t": ["B", 1, np.uint8],
        "int16_t": ["h", 2, np.int16],
        "uint16_t": ["H", 2, np.uint16],
        "int32_t": ["i", 4, np.int32],
        "uint32_t": ["I", 4, np.uint32],
        "int64_t": ["q", 8, np.int64],
        "uint64_t": ["Q", 8, np.uint64],
        "float": ["f", 4, np.float32],
        "double": ["d", 8, np.float64],
        "bool": ["?", 1, np.int8],
        "char": ["c", 1, np.int8],
    }

    _disable_str_exceptions = False

    @staticmethod
    def get_field_size(type_str: str) -> int:
        """The size of a basic type in bytes (``'int8_t'`` is 1)."""
        return ULog._UNPACK_TYPES[type_str][1]

    @staticmethod
    def parse_string(cstr: bytes) -> str:
        """UTF-8 text, invalid bytes left out when string exceptions are disabled."""
        if ULog._disable_str_exceptions:
            return str(cstr, "utf-8", "ignore")
        return str(cstr, "utf-8")

    def __init__(
        self,
        log_file: Union[str, "os.PathLike[str]", BinaryIO, None],
        message_name_filter_list: Optional[Union[Iterable[str], str]] = None,
        disable_str_exceptions: bool = True,
        parse_header_only: bool = False,
        *,
        recover: bool = False,
    ):
        self._debug = False
        self._file_corrupt = False
        self._start_timestamp = 0
        self._last_timestamp = 0
        self._msg_info_dict: Dict[str, Any] = {}
        self._msg_info_dict_types: Dict[str, str] = {}
        self._msg_info_multiple_dict: Dict[str, List[List[Any]]] = {}
        self._msg_info_multiple_dict_types: Dict[str, str] = {}
        self._initial_parameters: Dict[str, Any] = {}
        self._default_parameters: Dict[int, Dict[str, Any]] = {}
        self._changed_parameters: List[Tuple[int, str, Any]] = []
        self._message_formats: Dict[str, ULog.MessageFormat] = {}
        self._logged_messages: List[ULog.MessageLogging] = []
        self._logged_messages_tagged: Dict[int, List[ULog.MessageLoggingTagged]] = {}
        self._dropouts: List[ULog.MessageDropout] = []
        self._data_list: List[ULog.Data] = []
        self._subscriptions: Dict[int, Any] = {}
        self._filtered_message_ids: set = set()
        self._missing_message_ids: set = set()
        self._file_version = 0
        self._compat_flags = [0] * 8
        self._incompat_flags = [0] * 8
        self._appended_offsets: List[int] = []
        self._has_sync = True
        self._sync_seq_cnt = 0

        ULog._disable_str_exceptions = disable_str_exceptions

        if log_file is not None:
            self._load_file(log_file, message_name_filter_list, parse_header_only, recover)

    def _load_file(
        self, log_file: Any, message_name_filter_list: Any, parse_header_only: bool, recover: bool
    ) -> None:
        filt = message_name_filter_list
        if filt is not None and not isinstance(filt, str):
            filt = list(filt)
        strict = not ULog._disable_str_exceptions
        if isinstance(log_file, os.PathLike):
            # pyulog takes a str; a pathlib.Path is the same file.
            log_file = os.fsdecode(log_file)
        elif not isinstance(log_file, str) and not (
            hasattr(log_file, "read") and hasattr(log_file, "tell")
        ):
            raise TypeError(
                "ULog takes a path or a binary file object (opened with 'rb'), not "
                f"{type(log_file).__name__} (ulog.open takes a log's bytes)"
            )
        if isinstance(log_file, str):
            # The errors pyulog's own open() raises (no such file, a folder...).
            with open(log_file, "rb"):
                pass
            source: Any = log_file
            base = 0
        else:
            base = log_file.tell()
            source = bytes(log_file.read())
        try:
            r = _ulog.read_pyulog(source, filt, strict, parse_header_only, base, recover)
        except (_ulog.NotAULogError, _ulog.UnsupportedFlagError) as e:
            raise _as_pyulogs(e) from None
        finally:
            if not isinstance(log_file, str):
                log_file.close()
        for line in r["printed"]:
            print(line)
        self._file_corrupt = r["file_corrupt"]
        self._start_timestamp = r["start_timestamp"]
        self._last_timestamp = r["last_timestamp"]
        for key, type_name, value in r["info"]:
            self._msg_info_dict[key] = value
            self._msg_info_dict_types[key] = type_name
        for key, type_name, lists in r["info_multiple"]:
            self._msg_info_multiple_dict[key] = lists
            self._msg_info_multiple_dict_types[key] = type_name
        self._initial_parameters = dict(r["initial_parameters"])
        self._default_parameters = {key: dict(items) for key, items in r["default_parameters"]}
        self._changed_parameters = r["changed_parameters"]
        for name, fields in r["formats"]:
            self._message_formats[name] = ULog.MessageFormat._of(name, fields)
        self._logged_messages = [ULog.MessageLogging._of(*m) for m in r["logged"]]
        for tag, msgs in r["tagged"]:
            self._logged_messages_tagged[tag] = [ULog.MessageLoggingTagged._of(*m) for m in msgs]
        self._dropouts = [ULog.MessageDropout._of(d, t) for d, t in r["dropouts"]]
        for name, multi_id, msg_id, fields, timestamp_idx, rows, _row_size in r["data"]:
            field_data = [ULog._FieldData(n, t) for n, t in fields]
            dtype = np.dtype(
                [(f.field_name, ULog._UNPACK_TYPES[f.type_str][2]) for f in field_data]
            ).newbyteorder("<")
            self._data_list.append(
                ULog.Data(
                    SimpleNamespace(
                        multi_id=multi_id,
                        msg_id=msg_id,
                        message_name=name,
                        field_data=field_data,
                        timestamp_idx=timestamp_idx,
                        buffer=rows,
                        dtype=dtype,
                    )
                )
            )
        self._filtered_message_ids = set(r["filtered_ids"])
        self._missing_message_ids = set(r["missing_ids"])
        self._file_version = r["file_version"]
        self._compat_flags = r["compat_flags"]
        self._incompat_flags = r["incompat_flags"]
        self._appended_offsets = r["appended_offsets"]
        self._has_sync = r["has_sync"]
        self._sync_seq_cnt = r["sync_seq_cnt"]

    # -- pyulog's properties (the internal objects themselves, as pyulog returns them) --

    @property
    def start_timestamp(self) -> int:
        """Timestamp of the file's start (µs)."""
        return self._start_timestamp

    @property
    def last_timestamp(self) -> int:
        """The largest row timestamp (µs)."""
        return self._last_timestamp

    @property
    def msg_info_dict(self) -> Dict[str, Any]:
        """Info messages by key."""
        return self._msg_info_dict

    @property
    def msg_info_multiple_dict(self) -> Dict[str, List[List[Any]]]:
        """Multi info messages by key: a list of lists of values."""
        return self._msg_info_multiple_dict

    @property
    def initial_parameters(self) -> Dict[str, Any]:
        """Parameters as logging started."""
        return self._initial_parameters

    def get_default_parameters(self, default_type: int) -> Dict[str, Any]:
        """Default parameters of a type (0: system, 1: current setup)."""
        return self._default_parameters.get(default_type, {})

    @property
    def changed_parameters(self) -> List[Tuple[int, str, Any]]:
        """Parameter changes: (timestamp, name, value)."""
        return self._changed_parameters

    @property
    def message_formats(self) -> Dict[str, "ULog.MessageFormat"]:
        """Formats by name."""
        return self._message_formats

    @property
    def logged_messages(self) -> List["ULog.MessageLogging"]:
        """Logged strings."""
        return self._logged_messages

    @property
    def logged_messages_tagged(self) -> Dict[int, List["ULog.MessageLoggingTagged"]]:
        """Tagged logged strings by tag."""
        return self._logged_messages_tagged

    @property
    def dropouts(self) -> List["ULog.MessageDropout"]:
        """Dropouts."""
        return self._dropouts

    @property
    def data_list(self) -> List["ULog.Data"]:
        """The datasets: one per subscription with rows."""
        return self._data_list

    @property
    def has_data_appended(self) -> int:
        """Whether the log has appended data (an int, as pyulog's)."""
        return self._incompat_flags[0] & 0x1

    @property
    def file_corruption(self) -> bool:
        """Whether pyulog's reading found corruption."""
        return self._file_corrupt

    @property
    def has_default_parameters(self) -> int:
        """Whether the DEFAULT_PARAMETERS compat flag is set (an int, as pyulog's)."""
        return self._compat_flags[0] & (0x1 << 0)

    def get_dataset(self, name: str, multi_instance: int = 0) -> "ULog.Data":
        """The first dataset of this name and instance; IndexError if there is none."""
        return [
            elem
            for elem in self._data_list
            if elem.name == name and elem.multi_id == multi_instance
        ][0]

    def get_version_info(self, key_name: str = "ver_sw_release"):
        """(major, minor, patch, type) of a version info value, or None."""
        if key_name in self._msg_info_dict:
            val = self._msg_info_dict[key_name]
            return ((val >> 24) & 0xFF, (val >> 16) & 0xFF, (val >> 8) & 0xFF, val & 0xFF)
        return None

    def get_version_info_str(self, key_name: str = "ver_sw_release") -> Optional[str]:
        """'v1.2.3 (RC)', or None for a development version or no version."""
        version = self.get_version_info(key_name)
        if version is not None and version[3] >= 64:
            type_str = ""
            if version[3] < 128:
                type_str = " (alpha)"
            elif version[3] < 192:
                type_str = " (beta)"
            elif version[3] < 255:
                type_str = " (RC)"
            return "v{}.{}.{}{}".format(version[0], version[1], version[2], type_str)
        return None

    def __eq__(self, other):
        if not isinstance(other, ULog):
            return NotImplemented
        return all(
            self_value == getattr(other, field) for field, self_value in self.__dict__.items()
        )

    # -- write_ulog: pyulog's output, from the attributes --

    def write_ulog(self, log_file: Union[str, BinaryIO]) -> None:
        """Writes the log as pyulog writes it (from the attributes)."""
        if isinstance(log_file, str):
            handle: Any = open(log_file, "wb")
        else:
            handle = contextlib.nullcontext(log_file)
        with handle as out:
            out.write(self._header_bytes())
            out.write(self._flags_message())
            for fmt in self._message_formats.values():
                data = bytearray(bytes(fmt.name + ":", "utf-8"))
                for type_name, array_size, field_name in fmt.fields:
                    if array_size > 0:
                        data.extend(bytes("%s[%d] %s;" % (type_name, array_size, field_name), "utf-8"))
                    else:
                        data.extend(bytes("%s %s;" % (type_name, field_name), "utf-8"))
                out.write(_message(self.MSG_TYPE_FORMAT, data))
            for key, value in self._msg_info_dict.items():
                value_type = self._msg_info_dict_types[key]
                data = self._info_data(value_type + " " + key, value, value_type)
                out.write(_message(self.MSG_TYPE_INFO, data))
            for key, value_sets in self._msg_info_multiple_dict.items():
                value_type = self._msg_info_multiple_dict_types[key]
                for value_set in value_sets:
                    continued = False
                    for value in value_set:
                        data = self._info_data(value_type + " " + key, value, value_type, continued)
                        out.write(_message(self.MSG_TYPE_INFO_MULTIPLE, data))
                        continued = True
            for name, value in self._initial_parameters.items():
                out.write(_message(self.MSG_TYPE_PARAMETER, self._parameter_data(name, value)))
            for bit, values in self._default_parameters.items():
                for name, value in values.items():
                    data = bytearray(struct.pack("<B", 1 << bit))
                    data.extend(self._parameter_data(name, value))
                    out.write(_message(self.MSG_TYPE_PARAMETER_DEFAULT, data))
            datasets = sorted(self._data_list, key=lambda d: d.msg_id)
            for d in datasets:
                data = bytearray(struct.pack("<BH", d.multi_id, d.msg_id))
                data.extend(bytes(d.name, "utf-8"))
                out.write(_message(self.MSG_TYPE_ADD_LOGGED_MSG, data))
            items = self._data_items(datasets)
            for m in self._logged_messages:
                data = bytearray(struct.pack("<BQ", m.log_level, m.timestamp))
                data.extend(bytes(m.message, "utf-8"))
                items.append((m.timestamp, _message(self.MSG_TYPE_LOGGING, data)))
            for msgs in self._logged_messages_tagged.values():
                for tagged in msgs:
                    data = bytearray(
                        struct.pack("<BHQ", tagged.log_level, tagged.tag, tagged.timestamp)
                    )
                    data.extend(bytes(tagged.message, "utf-8"))
                    items.append((tagged.timestamp, _message(self.MSG_TYPE_LOGGING_TAGGED, data)))
            for drop in self._dropouts:
                dropout = struct.pack("<H", drop.duration)
                items.append((drop.timestamp, _message(self.MSG_TYPE_DROPOUT, dropout)))
            for t, name, value in self._changed_parameters:
                items.append((t, _message(self.MSG_TYPE_PARAMETER, self._parameter_data(name, value))))
            items.sort(key=lambda x: x[0])
            for _, buffer in items:
                out.write(buffer)

    def _header_bytes(self) -> bytes:
        header = bytearray(self.HEADER_BYTES)
        header.extend(struct.pack("B", self._file_version))
        header.extend(struct.pack("<Q", self._start_timestamp))
        if len(header) != 16:
            raise TypeError("Written header is too short")
        return bytes(header)

    def _flags_message(self) -> bytes:
        data = bytearray(struct.pack("<" + "B" * 8, *self._compat_flags))
        incompat = copy.deepcopy(self._incompat_flags)
        incompat[0] = incompat[0] & 0xFE
        data.extend(struct.pack("<" + "B" * 8, *incompat))
        data.extend(struct.pack("<" + "Q" * 3, 0, 0, 0))
        return _message(self.MSG_TYPE_FLAG_BITS, data)

    def _parameter_data(self, name: str, value) -> bytearray:
        if isinstance(value, int):
            value_type = "int32_t"
        elif isinstance(value, float):
            value_type = "float"
        else:
            raise TypeError("Found unknown parameter value type")
        return self._info_data(value_type + " " + name, value, value_type)

    def _info_data(self, key: str, value, value_type: str, continued=None) -> bytearray:
        key_bytes = bytes(key, "utf-8")
        data = bytearray()
        if continued is not None:
            data.extend(struct.pack("<B", continued))
        data.extend(struct.pack("<B", len(key_bytes)))
        data.extend(key_bytes)
        if value_type.startswith("char["):
            data.extend(bytes(value, "utf-8"))
        elif value_type.startswith("uint8_t["):
            data.extend(value)
        else:
            data.extend(struct.pack("<" + self._UNPACK_TYPES[value_type][0], value))
        return data

    def _data_items(self, datasets) -> List[Tuple[Any, bytes]]:
        """Each row as a `D` message with its timestamp, dataset by dataset (msg_id order)."""
        items: List[Tuple[Any, bytes]] = []
        for d in datasets:
            n = len(d.data[d.field_data[0].field_name])
            if n == 0:
                continue
            timestamps = d.data["timestamp"]
            dtype = np.dtype(
                [(f.field_name, ULog._UNPACK_TYPES[f.type_str][2]) for f in d.field_data]
            ).newbyteorder("<")
            packed = np.empty(n, dtype=dtype)
            for f in d.field_data:
                values = np.asarray(d.data[f.field_name])
                code = ULog._UNPACK_TYPES[f.type_str][0]
                if code == "?":
                    values = (values != 0).astype(np.int8)
                elif code == "c" and np.any(values < 0):
                    # pyulog packs chr(value) as UTF-8: a negative value cannot be.
                    raise ValueError("chr() arg not in range(0x110000)")
                packed[f.field_name] = values
            rows = packed.tobytes()
            size = dtype.itemsize
            head = struct.pack("<HB", size + 2, self.MSG_TYPE_DATA) + struct.pack("<H", d.msg_id)
            for i in range(n):
                items.append((timestamps[i], head + rows[i * size:(i + 1) * size]))
        return items

    # -- pyulog's nested classes --

    class Data:
        """A dataset: one subscription's rows, each field a numpy column."""

        def __init__(self, message_add_logged_obj):
            obj = message_add_logged_obj
            self.multi_id = obj.multi_id
            self.msg_id = obj.msg_id
            self.name = obj.message_name
            self.field_data = obj.field_data
            self.timestamp_idx = obj.timestamp_idx
            np_array = np.frombuffer(obj.buffer, dtype=obj.dtype)
            self.data = {}
            for name in np_array.dtype.names:
                self.data[name] = np_array[name]

        def __eq__(self, other):
            if not isinstance(other, ULog.Data):
                return NotImplemented
            arrays_equal = self.data.keys() == other.data.keys()
            if arrays_equal:
                for l_array, r_array in zip(self.data.values(), other.data.values()):
                    arrays_equal = arrays_equal and np.array_equal(l_array, r_array, equal_nan=True)
            return (
                self.multi_id == other.multi_id
                and self.msg_id == other.msg_id
                and self.name == other.name
                and self.field_data == other.field_data
                and self.timestamp_idx == other.timestamp_idx
                and arrays_equal
            )

        def list_value_changes(self, field_name):
            """(timestamp, value) at the first row with a non-zero timestamp and wherever the
            value changes."""
            t = self.data["timestamp"]
            x = self.data[field_name]
            indices = t != 0
            t = t[indices]
            x = x[indices]
            if len(t) == 0:
                return []
            ret = [(t[0], x[0])]
            indices = np.where(x[:-1] != x[1:])[0] + 1
            ret.extend(zip(t[indices], x[indices]))
            return ret

    class _FieldData:
        """A flattened field: its name and basic type."""

        def __init__(self, field_name, type_str):
            self.field_name = field_name
            self.type_str = type_str

        def __eq__(self, other):
            if not isinstance(other, ULog._FieldData):
                return NotImplemented
            return self.field_name == other.field_name and self.type_str == other.type_str

    class MessageFormat:
        """A format: its name and fields (type, array size or 0, name)."""

        def __init__(self, data, header):
            format_arr = ULog.parse_string(data).split(":")
            self.name = format_arr[0]
            self.fields = []
            for t in format_arr[1].split(";"):
                if len(t) > 0:
                    self.fields.append(self._extract_type(t))

        @classmethod
        def _of(cls, name, fields):
            f = cls.__new__(cls)
            f.name = name
            f.fields = [tuple(x) for x in fields]
            return f

        def __eq__(self, other):
            if not isinstance(other, ULog.MessageFormat):
                return NotImplemented
            return self.name == other.name and self.fields == other.fields

        @staticmethod
        def _extract_type(field_str):
            split = field_str.split(" ")
            type_str = split[0]
            name_str = split[1]
            a_pos = type_str.find("[")
            if a_pos == -1:
                return type_str, 0, name_str
            b_pos = type_str.find("]")
            array_size = int(type_str[a_pos + 1:b_pos])
            if array_size < 0 or array_size > 0xFFFF:
                raise ValueError("invalid array size: %d" % array_size)
            return type_str[:a_pos], array_size, name_str

    class MessageLogging:
        """A logged string."""

        def __init__(self, data, header):
            (self.log_level,) = struct.unpack("<B", data[0:1])
            (self.timestamp,) = struct.unpack("<Q", data[1:9])
            self.message = ULog.parse_string(data[9:])

        @classmethod
        def _of(cls, level, timestamp, message):
            m = cls.__new__(cls)
            m.log_level, m.timestamp, m.message = level, timestamp, message
            return m

        def __eq__(self, other):
            if not isinstance(other, ULog.MessageLogging):
                return NotImplemented
            return (
                self.log_level == other.log_level
                and self.timestamp == other.timestamp
                and self.message == other.message
            )

        def log_level_str(self):
            """The level's name; 'UNKNOWN' for a byte that is not '0' to '7'."""
            return _LEVELS.get(self.log_level, "UNKNOWN")

    class MessageLoggingTagged:
        """A tagged logged string."""

        def __init__(self, data, header):
            (self.log_level,) = struct.unpack("<B", data[0:1])
            (self.tag,) = struct.unpack("<H", data[1:3])
            (self.timestamp,) = struct.unpack("<Q", data[3:11])
            self.message = ULog.parse_string(data[11:])

        @classmethod
        def _of(cls, level, tag, timestamp, message):
            m = cls.__new__(cls)
            m.log_level, m.tag, m.timestamp, m.message = level, tag, timestamp, message
            return m

        def __eq__(self, other):
            if not isinstance(other, ULog.MessageLoggingTagged):
                return NotImplemented
            return (
                self.log_level == other.log_level
                and self.tag == other.tag
                and self.timestamp == other.timestamp
                and self.message == other.message
            )

        def log_level_str(self):
            """The level's name; 'UNKNOWN' for a byte that is not '0' to '7'."""
            return _LEVELS.get(self.log_level, "UNKNOWN")

    class MessageDropout:
        """A dropout: its duration (ms) and the largest timestamp seen before it."""

        def __init__(self, data, header, timestamp):
            (self.duration,) = struct.unpack("<H", data)
            self.timestamp = timestamp

        @classmethod
        def _of(cls, duration, timestamp):
            d = cls.__new__(cls)
            d.duration, d.timestamp = duration, timestamp
            return d

        def __eq__(self, other):
            if not isinstance(other, ULog.MessageDropout):
                return NotImplemented
            return self.duration == other.duration and self.timestamp == other.timestamp


def _message(msg_type: int, data) -> bytes:
    return struct.pack("<HB", len(data), msg_type) + bytes(data)


# Per (this package's class, pyulog's): the class made a subclass of both.
_PYULOG_ERRORS: Dict[Tuple[type, type], type] = {}


def _as_pyulogs(e: Exception) -> Exception:
    """``e`` as an exception that pyulog's own ``except`` clauses catch too
    (``pyulog.exceptions.ULogException``, ``ULogIncompatibleFlagException``), where the
    program has imported pyulog; else ``e`` itself (pyulog is never imported here)."""
    exceptions = sys.modules.get("pyulog.exceptions")
    if exceptions is None:
        return e
    if isinstance(e, _ulog.UnsupportedFlagError):
        theirs = exceptions.ULogIncompatibleFlagException
    else:
        theirs = exceptions.ULogException
    ours = type(e)
    if issubclass(ours, theirs):
        # pyulog's names bound to this package's classes (as its test suite runs here).
        return e
    cls = _PYULOG_ERRORS.get((ours, theirs))
    if cls is None:
        cls = type(
            ours.__name__,
            (ours, theirs),
            {
                "__module__": ours.__module__,
                "__doc__": ours.__doc__,
                # Pickled as this package's class (this one is made at run time).
                "__reduce__": lambda self: (ours, self.args),
            },
        )
        _PYULOG_ERRORS[(ours, theirs)] = cls
    return cls(*e.args)
