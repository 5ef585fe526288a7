//! Zero-copy parsing of the file header and of every message type of both format versions.
//! Each parser checks lengths only; what the bytes mean is decided by [`super::Metadata`].

/// The 7 magic bytes every ULog file starts with.
pub const MAGIC: [u8; 7] = [0x55, 0x4c, 0x6f, 0x67, 0x01, 0x12, 0x35];
/// The 8 bytes of a sync (`S`) message, searched for to recover from corruption.
pub const SYNC_MAGIC: [u8; 8] = [0x2f, 0x73, 0x13, 0x20, 0x25, 0x0c, 0xbb, 0x12];
/// Size of the file header.
pub const HEADER_LEN: usize = 16;
/// Size of a message header (`u16` size, `u8` type).
pub const MESSAGE_HEADER_LEN: usize = 3;
/// The highest file version this reader knows.
pub const KNOWN_VERSION: u8 = 1;
/// Length of the flag-bits payload this reader understands (longer ones are accepted).
pub const FLAG_BITS_LEN: usize = 40;

/// The 16-byte file header.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct FileHeader {
    /// File format version (0 or 1 today; later versions are read with a warning).
    pub version: u8,
    /// Start of logging, in microseconds.
    pub start_timestamp: u64,
}

impl FileHeader {
    /// Parses the first 16 bytes of a file.
    pub fn parse(bytes: &[u8]) -> Result<FileHeader, crate::ReadError> {
        if bytes.len() < HEADER_LEN {
            if !MAGIC.starts_with(&bytes[..bytes.len().min(MAGIC.len())]) {
                return Err(crate::ReadError::NotULog);
            }
            return Err(crate::ReadError::TooShort { len: bytes.len() });
        }
        if bytes[..7] != MAGIC {
            return Err(crate::ReadError::NotULog);
        }
        Ok(FileHeader {
            version: bytes[7],
            start_timestamp: u64_at(bytes, 8),
        })
    }

    /// The start time as a UTC date, if it is one: some writers put an absolute Unix time in
    /// microseconds here instead of the time since boot. A value is taken for a date when
    /// [`UtcTime::plausible`] takes it (from 2000 up to 2100: boot times, days at most, are
    /// far below; a value past 2100 is damage, neither a date nor a boot time).
    ///
    /// ```
    /// use ulog_runtime::read::FileHeader;
    /// let h = FileHeader { version: 1, start_timestamp: 1_710_773_350_346_000 };
    /// assert_eq!(h.start_utc().unwrap().to_string(), "2024-03-18 14:49:10.346000 UTC");
    /// assert!(FileHeader { version: 1, start_timestamp: 104_889_396 }.start_utc().is_none());
    /// assert!(FileHeader { version: 1, start_timestamp: u64::MAX }.start_utc().is_none());
    /// ```
    pub fn start_utc(&self) -> Option<UtcTime> {
        UtcTime::plausible(self.start_timestamp)
    }

    /// The header as written to a file.
    pub fn to_bytes(&self) -> [u8; HEADER_LEN] {
        let mut out = [0; HEADER_LEN];
        out[..7].copy_from_slice(&MAGIC);
        out[7] = self.version;
        out[8..].copy_from_slice(&self.start_timestamp.to_le_bytes());
        out
    }
}

/// A UTC date and time to the microsecond, from a Unix time ([`FileHeader::start_utc`]).
#[derive(Debug, Clone, Copy, PartialEq, Eq, PartialOrd, Ord)]
pub struct UtcTime {
    /// Year.
    pub year: i64,
    /// Month, 1 to 12.
    pub month: u8,
    /// Day of the month, 1 to 31.
    pub day: u8,
    /// Hour.
    pub hour: u8,
    /// Minute.
    pub minute: u8,
    /// Second.
    pub second: u8,
    /// Microseconds within the second.
    pub micros: u32,
}

impl UtcTime {
    /// The Unix times, in µs, taken for dates in a log: from 2000-01-01 up to 2100-01-01 UTC.
    /// A header's start or a GPS's `time_utc_usec` outside them is not a date: a time since
    /// boot, a GPS without a fix (0), or damage.
    pub const PLAUSIBLE_US: std::ops::Range<u64> = 946_684_800_000_000..4_102_444_800_000_000;

    /// The date of a Unix time in µs if it lies in [`UtcTime::PLAUSIBLE_US`].
    ///
    /// ```
    /// use ulog_runtime::read::UtcTime;
    /// assert_eq!(UtcTime::plausible(1_710_773_350_346_000).unwrap().year, 2024);
    /// assert!(UtcTime::plausible(0).is_none());
    /// assert!(UtcTime::plausible(u64::MAX).is_none()); // the year 586524
    /// ```
    pub fn plausible(us: u64) -> Option<UtcTime> {
        UtcTime::PLAUSIBLE_US
            .contains(&us)
            .then(|| UtcTime::from_unix_us(us))
    }

    /// The date of a Unix time in microseconds (proleptic Gregorian calendar).
    pub fn from_unix_us(us: u64) -> UtcTime {
        let secs = us / 1_000_000;
        let days = i64::try_from(secs / 86_400).expect("u64 seconds / 86400 fits i64");
        let rem = secs % 86_400;
        // Days to a civil date (Howard Hinnant's algorithm).
        let z = days + 719_468;
        let era = z.div_euclid(146_097);
        let doe = z.rem_euclid(146_097);
        let yoe = (doe - doe / 1460 + doe / 36_524 - doe / 146_096) / 365;
        let doy = doe - (365 * yoe + yoe / 4 - yoe / 100);
        let mp = (5 * doy + 2) / 153;
        let day = (doy - (153 * mp + 2) / 5 + 1) as u8;
        let month = if mp < 10 { mp + 3 } else { mp - 9 } as u8;
        let year = yoe + era * 400 + i64::from(month <= 2);
        UtcTime {
            year,
            month,
            day,
            hour: (rem / 3600) as u8,
            minute: (rem / 60 % 60) as u8,
            second: (rem % 60) as u8,
            micros: (us % 1_000_000) as u32,
        }
    }
}

impl std::fmt::Display for UtcTime {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        write!(
            f,
            "{:04}-{:02}-{:02} {:02}:{:02}:{:02}.{:06} UTC",
            self.year, self.month, self.day, self.hour, self.minute, self.second, self.micros
        )
    }
}

/// The flag-bits (`B`) message of version-1 files.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub struct FlagBits {
    /// Compatible flags: a reader may ignore unknown ones.
    pub compat: [u8; 8],
    /// Incompatible flags: a reader must refuse unknown ones.
    pub incompat: [u8; 8],
    /// File offsets of appended data segments (0 = unused).
    pub appended_offsets: [u64; 3],
}

impl FlagBits {
    /// `compat[0]` bit 0: the file has default parameters (`Q` messages).
    pub const COMPAT_DEFAULT_PARAMETERS: u8 = 1;
    /// `incompat[0]` bit 0: data was appended at `appended_offsets`.
    pub const INCOMPAT_DATA_APPENDED: u8 = 1;

    /// Whether the DATA_APPENDED bit is set.
    pub fn has_data_appended(&self) -> bool {
        self.incompat[0] & Self::INCOMPAT_DATA_APPENDED != 0
    }

    /// Whether the DEFAULT_PARAMETERS bit is set.
    pub fn has_default_parameters(&self) -> bool {
        self.compat[0] & Self::COMPAT_DEFAULT_PARAMETERS != 0
    }

    /// The first incompatible bit this reader does not know, as `(byte, bit)`.
    pub fn unknown_incompat_bit(&self) -> Option<(usize, u8)> {
        self.incompat.iter().enumerate().find_map(|(byte, &v)| {
            let unknown = if byte == 0 {
                v & !Self::INCOMPAT_DATA_APPENDED
            } else {
                v
            };
            (unknown != 0).then(|| (byte, unknown.trailing_zeros() as u8))
        })
    }

    /// The non-zero appended offsets, in order.
    pub fn appended(&self) -> impl Iterator<Item = u64> + '_ {
        self.appended_offsets.iter().copied().filter(|&o| o != 0)
    }

    fn parse(p: &[u8]) -> FlagBits {
        let mut bits = FlagBits::default();
        bits.compat.copy_from_slice(&p[0..8]);
        bits.incompat.copy_from_slice(&p[8..16]);
        for (i, o) in bits.appended_offsets.iter_mut().enumerate() {
            *o = u64_at(p, 16 + 8 * i);
        }
        bits
    }

    /// The 40-byte payload.
    pub fn to_bytes(&self) -> [u8; FLAG_BITS_LEN] {
        let mut out = [0; FLAG_BITS_LEN];
        out[..8].copy_from_slice(&self.compat);
        out[8..16].copy_from_slice(&self.incompat);
        for (i, o) in self.appended_offsets.iter().enumerate() {
            out[16 + 8 * i..24 + 8 * i].copy_from_slice(&o.to_le_bytes());
        }
        out
    }
}

/// The message type byte.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
#[repr(u8)]
pub enum MessageType {
    /// `B` flag bits.
    FlagBits = b'B',
    /// `F` format definition.
    Format = b'F',
    /// `I` information.
    Info = b'I',
    /// `M` multi information.
    MultiInfo = b'M',
    /// `P` parameter.
    Parameter = b'P',
    /// `Q` default parameter.
    DefaultParameter = b'Q',
    /// `A` subscription.
    Subscribe = b'A',
    /// `R` unsubscription.
    Unsubscribe = b'R',
    /// `D` data.
    Data = b'D',
    /// `L` logged string.
    Logging = b'L',
    /// `C` tagged logged string.
    TaggedLogging = b'C',
    /// `S` sync.
    Sync = b'S',
    /// `O` dropout.
    Dropout = b'O',
}

impl MessageType {
    /// The type for a type byte, if known.
    pub const fn from_byte(b: u8) -> Option<MessageType> {
        Some(match b {
            b'B' => MessageType::FlagBits,
            b'F' => MessageType::Format,
            b'I' => MessageType::Info,
            b'M' => MessageType::MultiInfo,
            b'P' => MessageType::Parameter,
            b'Q' => MessageType::DefaultParameter,
            b'A' => MessageType::Subscribe,
            b'R' => MessageType::Unsubscribe,
            b'D' => MessageType::Data,
            b'L' => MessageType::Logging,
            b'C' => MessageType::TaggedLogging,
            b'S' => MessageType::Sync,
            b'O' => MessageType::Dropout,
            _ => return None,
        })
    }

    /// Smallest payload a message of this type can have.
    pub const fn min_size(self) -> usize {
        match self {
            MessageType::FlagBits => FLAG_BITS_LEN,
            MessageType::Format => 3,
            MessageType::Info | MessageType::Parameter => 2,
            MessageType::MultiInfo | MessageType::DefaultParameter => 3,
            MessageType::Subscribe => 4,
            MessageType::Unsubscribe | MessageType::Dropout | MessageType::Data => 2,
            MessageType::Logging => 9,
            MessageType::TaggedLogging => 11,
            MessageType::Sync => 8,
        }
    }
}

/// One message, borrowed from the bytes it was parsed from.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum Message<'a> {
    /// `B`
    FlagBits(FlagBits),
    /// `F`: the raw format text.
    Format(&'a [u8]),
    /// `I`
    Info(KeyValue<'a>),
    /// `M`
    MultiInfo {
        /// Whether this continues the previous `M` with the same key.
        continued: bool,
        /// Key and value.
        entry: KeyValue<'a>,
    },
    /// `P`
    Parameter(KeyValue<'a>),
    /// `Q`
    DefaultParameter {
        /// Bit 0: system default; bit 1: current configuration default.
        default_types: u8,
        /// Key and value.
        entry: KeyValue<'a>,
    },
    /// `A`
    Subscribe {
        /// Instance of the topic.
        multi_id: u8,
        /// Id used by `D` messages.
        msg_id: u16,
        /// Format name.
        name: &'a [u8],
    },
    /// `R`
    Unsubscribe {
        /// The id that is no longer logged.
        msg_id: u16,
    },
    /// `D`
    Data {
        /// The subscription.
        msg_id: u16,
        /// The packed row.
        data: &'a [u8],
    },
    /// `L` (`tag` is `None`) or `C` (`tag` is `Some`).
    Logging {
        /// The raw level byte (ASCII `'0'..='7'` in PX4 logs).
        level: u8,
        /// Tag of a `C` message.
        tag: Option<u16>,
        /// Microseconds.
        timestamp: u64,
        /// The text bytes.
        text: &'a [u8],
    },
    /// `S`
    Sync,
    /// `O`
    Dropout {
        /// Milliseconds lost.
        duration_ms: u16,
    },
    /// A type this reader does not know; skipped.
    Unknown {
        /// The type byte.
        ty: u8,
        /// The payload.
        payload: &'a [u8],
    },
}

/// The key (`type name` text) and raw value of an `I`, `M`, `P` or `Q` message.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct KeyValue<'a> {
    /// The key text, e.g. `char[3] sys_name`.
    pub key: &'a [u8],
    /// The value bytes.
    pub value: &'a [u8],
}

/// A message too short for its type or with an inner length pointing past its end.
#[derive(Debug, Clone, Copy, PartialEq, Eq, thiserror::Error)]
#[error("malformed `{}` message: {reason}", *.ty as char)]
pub struct MalformedMessage {
    /// The type byte.
    pub ty: u8,
    /// What is wrong.
    pub reason: &'static str,
}

impl<'a> Message<'a> {
    /// Parses the payload (the bytes after the 3-byte header) of a message of type `ty`.
    pub fn parse(ty: u8, p: &'a [u8]) -> Result<Message<'a>, MalformedMessage> {
        let Some(kind) = MessageType::from_byte(ty) else {
            return Ok(Message::Unknown { ty, payload: p });
        };
        if p.len() < kind.min_size() {
            return Err(MalformedMessage {
                ty,
                reason: "shorter than the smallest message of its type",
            });
        }
        let key_value = |p: &'a [u8]| -> Result<KeyValue<'a>, MalformedMessage> {
            let key_len = usize::from(p[0]);
            if 1 + key_len > p.len() {
                return Err(MalformedMessage {
                    ty,
                    reason: "key length runs past the end of the message",
                });
            }
            Ok(KeyValue {
                key: &p[1..1 + key_len],
                value: &p[1 + key_len..],
            })
        };
        Ok(match kind {
            MessageType::FlagBits => Message::FlagBits(FlagBits::parse(p)),
            MessageType::Format => Message::Format(p),
            MessageType::Info => Message::Info(key_value(p)?),
            MessageType::Parameter => Message::Parameter(key_value(p)?),
            MessageType::MultiInfo => Message::MultiInfo {
                continued: p[0] != 0,
                entry: key_value(&p[1..])?,
            },
            MessageType::DefaultParameter => Message::DefaultParameter {
                default_types: p[0],
                entry: key_value(&p[1..])?,
            },
            MessageType::Subscribe => Message::Subscribe {
                multi_id: p[0],
                msg_id: u16_at(p, 1),
                name: &p[3..],
            },
            MessageType::Unsubscribe => Message::Unsubscribe {
                msg_id: u16_at(p, 0),
            },
            MessageType::Data => Message::Data {
                msg_id: u16_at(p, 0),
                data: &p[2..],
            },
            MessageType::Logging => Message::Logging {
                level: p[0],
                tag: None,
                timestamp: u64_at(p, 1),
                text: &p[9..],
            },
            MessageType::TaggedLogging => Message::Logging {
                level: p[0],
                tag: Some(u16_at(p, 1)),
                timestamp: u64_at(p, 3),
                text: &p[11..],
            },
            MessageType::Sync => Message::Sync,
            MessageType::Dropout => Message::Dropout {
                duration_ms: u16_at(p, 0),
            },
        })
    }
}

/// A message part too large for the length field that holds its size.
#[derive(Debug, Clone, Copy, PartialEq, Eq, thiserror::Error)]
#[error("`{}` message: {what} of {size} bytes exceeds the {limit} its length field can hold", *.ty as char)]
pub struct MessageTooLarge {
    /// The type byte.
    pub ty: u8,
    /// `"payload"` or `"key"`.
    pub what: &'static str,
    /// The size it would need.
    pub size: usize,
    /// The largest size possible.
    pub limit: usize,
}

impl Message<'_> {
    /// The type byte this message is written with.
    pub fn type_byte(&self) -> u8 {
        match self {
            Message::FlagBits(_) => b'B',
            Message::Format(_) => b'F',
            Message::Info(_) => b'I',
            Message::MultiInfo { .. } => b'M',
            Message::Parameter(_) => b'P',
            Message::DefaultParameter { .. } => b'Q',
            Message::Subscribe { .. } => b'A',
            Message::Unsubscribe { .. } => b'R',
            Message::Data { .. } => b'D',
            Message::Logging { tag: None, .. } => b'L',
            Message::Logging { tag: Some(_), .. } => b'C',
            Message::Sync => b'S',
            Message::Dropout { .. } => b'O',
            Message::Unknown { ty, .. } => *ty,
        }
    }

    /// Appends the message (3-byte header and payload) to `out`, laid out as the
    /// specification says; the inverse of [`Message::parse`]. On error `out` is unchanged.
    ///
    /// ```
    /// use ulog_runtime::read::Message;
    /// let mut out = Vec::new();
    /// Message::Dropout { duration_ms: 119 }.encode(&mut out).unwrap();
    /// assert_eq!(out, [2, 0, b'O', 119, 0]);
    /// assert_eq!(Message::parse(out[2], &out[3..]).unwrap(), Message::Dropout { duration_ms: 119 });
    /// ```
    pub fn encode(&self, out: &mut Vec<u8>) -> Result<(), MessageTooLarge> {
        let ty = self.type_byte();
        if let Message::Info(e)
        | Message::Parameter(e)
        | Message::MultiInfo { entry: e, .. }
        | Message::DefaultParameter { entry: e, .. } = self
            && e.key.len() > usize::from(u8::MAX)
        {
            return Err(MessageTooLarge {
                ty,
                what: "key",
                size: e.key.len(),
                limit: 255,
            });
        }
        let start = out.len();
        out.extend_from_slice(&[0, 0, ty]);
        let kv = |out: &mut Vec<u8>, e: &KeyValue<'_>| {
            out.push(e.key.len() as u8);
            out.extend_from_slice(e.key);
            out.extend_from_slice(e.value);
        };
        match self {
            Message::FlagBits(bits) => out.extend_from_slice(&bits.to_bytes()),
            Message::Format(text) => out.extend_from_slice(text),
            Message::Info(e) | Message::Parameter(e) => kv(out, e),
            Message::MultiInfo { continued, entry } => {
                out.push(u8::from(*continued));
                kv(out, entry);
            }
            Message::DefaultParameter {
                default_types,
                entry,
            } => {
                out.push(*default_types);
                kv(out, entry);
            }
            Message::Subscribe {
                multi_id,
                msg_id,
                name,
            } => {
                out.push(*multi_id);
                out.extend_from_slice(&msg_id.to_le_bytes());
                out.extend_from_slice(name);
            }
            Message::Unsubscribe { msg_id } => out.extend_from_slice(&msg_id.to_le_bytes()),
            Message::Data { msg_id, data } => {
                out.extend_from_slice(&msg_id.to_le_bytes());
                out.extend_from_slice(data);
            }
            Message::Logging {
                level,
                tag,
                timestamp,
                text,
            } => {
                out.push(*level);
                if let Some(tag) = tag {
                    out.extend_from_slice(&tag.to_le_bytes());
                }
                out.extend_from_slice(&timestamp.to_le_bytes());
                out.extend_from_slice(text);
            }
            Message::Sync => out.extend_from_slice(&SYNC_MAGIC),
            Message::Dropout { duration_ms } => out.extend_from_slice(&duration_ms.to_le_bytes()),
            Message::Unknown { payload, .. } => out.extend_from_slice(payload),
        }
        let size = out.len() - start - MESSAGE_HEADER_LEN;
        let Ok(size16) = u16::try_from(size) else {
            out.truncate(start);
            return Err(MessageTooLarge {
                ty,
                what: "payload",
                size,
                limit: usize::from(u16::MAX),
            });
        };
        out[start..start + 2].copy_from_slice(&size16.to_le_bytes());
        Ok(())
    }
}

pub(crate) fn u16_at(b: &[u8], at: usize) -> u16 {
    u16::from_le_bytes([b[at], b[at + 1]])
}

pub(crate) fn u64_at(b: &[u8], at: usize) -> u64 {
    let mut x = [0; 8];
    x.copy_from_slice(&b[at..at + 8]);
    u64::from_le_bytes(x)
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Builds a message from its parts, as the spec's tables lay them out.
    fn parse<'a>(ty: u8, payload: &'a [u8]) -> Message<'a> {
        Message::parse(ty, payload).unwrap()
    }

    #[test]
    fn header() {
        let mut b = vec![0x55, 0x4c, 0x6f, 0x67, 0x01, 0x12, 0x35, 0x01];
        b.extend_from_slice(&1_234_567u64.to_le_bytes());
        let h = FileHeader::parse(&b).unwrap();
        assert_eq!((h.version, h.start_timestamp), (1, 1_234_567));
        assert_eq!(h.to_bytes().as_slice(), b.as_slice());
        assert!(matches!(
            FileHeader::parse(&b[..10]),
            Err(crate::ReadError::TooShort { len: 10 })
        ));
        b[0] = b'X';
        assert!(matches!(
            FileHeader::parse(&b),
            Err(crate::ReadError::NotULog)
        ));
    }

    #[test]
    fn flag_bits() {
        let mut p = vec![1, 0, 0, 0, 0, 0, 0, 0, 1, 0, 0, 0, 0, 0, 0, 0];
        p.extend_from_slice(&434_369u64.to_le_bytes());
        p.extend_from_slice(&0u64.to_le_bytes());
        p.extend_from_slice(&0u64.to_le_bytes());
        let Message::FlagBits(bits) = parse(b'B', &p) else {
            panic!()
        };
        assert!(bits.has_data_appended() && bits.has_default_parameters());
        assert_eq!(bits.appended().collect::<Vec<_>>(), [434_369]);
        assert_eq!(bits.unknown_incompat_bit(), None);
        assert_eq!(bits.to_bytes().as_slice(), p.as_slice());
        p[8] = 0b101;
        let Message::FlagBits(bits) = parse(b'B', &p) else {
            panic!()
        };
        assert_eq!(bits.unknown_incompat_bit(), Some((0, 2)));
        p[8] = 1;
        p[13] = 0x80;
        let Message::FlagBits(bits) = parse(b'B', &p) else {
            panic!()
        };
        assert_eq!(bits.unknown_incompat_bit(), Some((5, 7)));
    }

    #[test]
    fn key_value_messages() {
        // I: key_len, key, value
        let mut p = vec![16];
        p.extend_from_slice(b"char[3] sys_name");
        p.extend_from_slice(b"PX4");
        assert_eq!(
            parse(b'I', &p),
            Message::Info(KeyValue {
                key: b"char[3] sys_name",
                value: b"PX4"
            })
        );
        assert!(matches!(parse(b'P', &p), Message::Parameter(_)));
        // M: is_continued, key_len, key, value
        let mut m = vec![1];
        m.extend_from_slice(&p);
        assert!(
            matches!(parse(b'M', &m), Message::MultiInfo { continued: true, entry } if entry.value == b"PX4")
        );
        // Q: default_types, key_len, key, value
        let mut q = vec![3, 11];
        q.extend_from_slice(b"float PARAM");
        q.extend_from_slice(&1.5f32.to_le_bytes());
        let Message::DefaultParameter {
            default_types,
            entry,
        } = parse(b'Q', &q)
        else {
            panic!()
        };
        assert_eq!((default_types, entry.key), (3, &b"float PARAM"[..]));
        assert_eq!(entry.value, 1.5f32.to_le_bytes());
        // key_len beyond the end
        let e = Message::parse(b'I', &[200, b'a']).unwrap_err();
        assert_eq!(
            e.to_string(),
            "malformed `I` message: key length runs past the end of the message"
        );
    }

    #[test]
    fn encode_is_the_inverse_of_parse() {
        let bits = FlagBits {
            compat: [1, 0, 0, 0, 0, 0, 0, 0],
            incompat: [0; 8],
            appended_offsets: [9, 0, 0],
        };
        let kv = KeyValue {
            key: b"int32_t P",
            value: &[1, 2, 3, 4],
        };
        let messages = [
            Message::FlagBits(bits),
            Message::Format(b"a:uint8_t x;"),
            Message::Info(kv),
            Message::MultiInfo {
                continued: true,
                entry: kv,
            },
            Message::Parameter(kv),
            Message::DefaultParameter {
                default_types: 2,
                entry: kv,
            },
            Message::Subscribe {
                multi_id: 1,
                msg_id: 300,
                name: b"a",
            },
            Message::Unsubscribe { msg_id: 300 },
            Message::Data {
                msg_id: 300,
                data: &[7],
            },
            Message::Logging {
                level: b'4',
                tag: None,
                timestamp: 5,
                text: b"w",
            },
            Message::Logging {
                level: b'4',
                tag: Some(9),
                timestamp: 5,
                text: b"w",
            },
            Message::Sync,
            Message::Dropout { duration_ms: 3 },
            Message::Unknown {
                ty: b'z',
                payload: &[1, 2],
            },
        ];
        for m in messages {
            let mut out = vec![0xAA];
            m.encode(&mut out).unwrap();
            let size = usize::from(u16_at(&out, 1));
            assert_eq!(size + 4, out.len(), "{m:?}");
            assert_eq!(Message::parse(out[3], &out[4..]).unwrap(), m);
        }
        // The spec's layout of a subscription: size, 'A', multi_id, msg_id, name.
        let mut out = Vec::new();
        Message::Subscribe {
            multi_id: 1,
            msg_id: 0x0203,
            name: b"ab",
        }
        .encode(&mut out)
        .unwrap();
        assert_eq!(out, [5, 0, b'A', 1, 3, 2, b'a', b'b']);
        let big = vec![0; 70_000];
        let mut out = vec![1];
        let e = Message::Format(&big).encode(&mut out).unwrap_err();
        assert_eq!((e.size, out.len()), (70_000, 1));
        assert_eq!(
            e.to_string(),
            "`F` message: payload of 70000 bytes exceeds the 65535 its length field can hold"
        );
        let long_key = vec![b'k'; 256];
        let e = Message::Info(KeyValue {
            key: &long_key,
            value: &[],
        })
        .encode(&mut out)
        .unwrap_err();
        assert_eq!((e.what, out.len()), ("key", 1));
    }

    #[test]
    fn subscription_data_and_strings() {
        assert_eq!(
            parse(b'A', &[2, 0x34, 0x12, b'a', b'b']),
            Message::Subscribe {
                multi_id: 2,
                msg_id: 0x1234,
                name: b"ab"
            }
        );
        assert_eq!(parse(b'R', &[7, 0]), Message::Unsubscribe { msg_id: 7 });
        assert_eq!(
            parse(b'D', &[1, 0, 9, 9]),
            Message::Data {
                msg_id: 1,
                data: &[9, 9]
            }
        );
        let mut l = vec![b'6'];
        l.extend_from_slice(&99u64.to_le_bytes());
        l.extend_from_slice(b"hi");
        assert_eq!(
            parse(b'L', &l),
            Message::Logging {
                level: b'6',
                tag: None,
                timestamp: 99,
                text: b"hi"
            }
        );
        let mut c = vec![b'3', 5, 0];
        c.extend_from_slice(&77u64.to_le_bytes());
        c.extend_from_slice(b"tagged");
        assert_eq!(
            parse(b'C', &c),
            Message::Logging {
                level: b'3',
                tag: Some(5),
                timestamp: 77,
                text: b"tagged"
            }
        );
        assert_eq!(parse(b'S', &SYNC_MAGIC), Message::Sync);
        assert_eq!(
            parse(b'O', &[119, 0]),
            Message::Dropout { duration_ms: 119 }
        );
        assert_eq!(
            parse(b'z', &[1]),
            Message::Unknown {
                ty: b'z',
                payload: &[1]
            }
        );
        for (ty, short) in [
            (b'L', 8),
            (b'C', 10),
            (b'D', 1),
            (b'A', 3),
            (b'B', 39),
            (b'S', 7),
        ] {
            assert!(
                Message::parse(ty, &vec![b'0'; short]).is_err(),
                "{}",
                ty as char
            );
        }
    }
}
