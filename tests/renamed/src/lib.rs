//! A crate that depends on `ulog-runtime` under another name (`my_ulog` in Cargo.toml), so
//! `::ulog_runtime` does not exist here: the derive's output compiles only because
//! `#[ulog(crate = "my_ulog")]` points it at the renamed crate.

use my_ulog::{Chars, ULog};

/// A nested type through the renamed crate.
#[derive(ULog, Debug, Clone, Copy, PartialEq)]
#[ulog(crate = "my_ulog")]
pub struct Cell {
    /// Volts.
    pub voltage: f32,
    #[ulog(padding)]
    _pad: [u8; 4],
}

/// A topic through the renamed crate.
#[derive(ULog, Debug, Clone, PartialEq)]
#[ulog(crate = "my_ulog", name = "battery")]
pub struct Battery {
    /// Microseconds.
    pub timestamp: u64,
    /// The cells.
    pub cells: [Cell; 2],
    /// Pack id.
    pub id: Chars<4>,
}

#[cfg(test)]
mod tests {
    use super::*;
    use my_ulog::{Log, Writer, WriterOptions};

    #[test]
    fn derived_through_a_renamed_crate_round_trips() {
        let cell = Cell {
            voltage: 4.1,
            _pad: [0; 4],
        };
        let value = Battery {
            timestamp: 9,
            cells: [cell; 2],
            id: Chars::new("P1").unwrap(),
        };
        let mut w = Writer::new(Vec::new(), WriterOptions::default()).unwrap();
        let sub = w.topic::<Battery>(0).unwrap();
        w.write(&sub, &value).unwrap();
        let log = Log::from_vec(w.into_inner()).unwrap();
        let format = log.metadata().schema().get("battery").unwrap().to_string();
        assert_eq!(
            format,
            "battery:uint64_t timestamp;cell[2] cells;char[4] id;"
        );
        let rows: Vec<Battery> = log
            .topic::<Battery>()
            .unwrap()
            .rows()
            .map(|(_, b)| b)
            .collect();
        assert_eq!(rows, [value]);
    }
}
