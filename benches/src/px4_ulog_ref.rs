//! px4-ulog 0.6.1's streaming reader (the base of PX4's Flight Review v2) computing the
//! `scan` figures: the baseline the decode benchmarks and the `px4_ulog_scan` binary
//! measure this library against, decoding the same leaves (every non-padding leaf; `char`
//! as a signed byte, `bool` as 0/1; the sum of the finite values as `f64`).

use px4_ulog::stream_parser::LittleEndianParser;
use px4_ulog::stream_parser::file_reader::{LogParser, Message, SimpleCallbackResult};
use px4_ulog::stream_parser::model::{DataMessage, FlattenedFieldType as T};

/// Rows, leaves and the sum of the finite leaves.
#[derive(Debug, Default, Clone, Copy, PartialEq)]
pub struct Figures {
    /// Rows.
    pub rows: u64,
    /// Leaves.
    pub leaves: u64,
    /// Sum of the finite leaves.
    pub sum: f64,
}

impl Figures {
    /// Adds one data message, every leaf decoded as px4-ulog decodes it.
    #[inline]
    pub fn add(&mut self, d: &DataMessage<'_>) {
        self.rows += 1;
        let mut row_sum = 0.0f64;
        for f in d.flattened_format.field_iter() {
            // Offsets count from the start of `data`, which holds the 2-byte msg_id.
            let b = &d.data[usize::from(f.offset)..];
            let x = match f.field_type {
                T::Int8 => f64::from(i8::parse(b)),
                T::UInt8 => f64::from(u8::parse(b)),
                T::Int16 => f64::from(i16::parse(b)),
                T::UInt16 => f64::from(u16::parse(b)),
                T::Int32 => f64::from(i32::parse(b)),
                T::UInt32 => f64::from(u32::parse(b)),
                T::Int64 => i64::parse(b) as f64,
                T::UInt64 => examples::u64_to_f64(u64::parse(b)),
                T::Float => f64::from(f32::parse(b)),
                T::Double => f64::parse(b),
                T::Bool => f64::from(u8::from(bool::parse(b))),
                T::Char => f64::from(b[0] as i8),
            };
            if x.is_finite() {
                row_sum += x;
            }
            self.leaves += 1;
        }
        self.sum += row_sum;
    }
}

/// The figures of a file, read with px4-ulog's file reader (1 MiB chunks).
#[allow(dead_code)]
pub fn scan_file(path: &str) -> std::io::Result<Figures> {
    let mut figures = Figures::default();
    px4_ulog::stream_parser::file_reader::read_file_with_simple_callback(path, &mut |msg| {
        if let Message::Data(d) = msg {
            figures.add(d);
        }
        SimpleCallbackResult::KeepReading
    })?;
    Ok(figures)
}

/// The figures of a file held in memory, through px4-ulog's parser.
#[allow(dead_code)]
pub fn scan_bytes(bytes: &[u8]) -> Figures {
    let mut figures = Figures::default();
    let mut add = |d: &DataMessage<'_>| figures.add(d);
    let mut parser = LogParser::default();
    parser.set_data_message_callback(&mut add);
    parser
        .consume_bytes(bytes)
        .expect("the benchmark log parses");
    drop(parser);
    figures
}
