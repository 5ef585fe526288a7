//! A log as columns, then as Parquet files: the battery voltage as a vector, Arrow record
//! batches of the attitude, and the whole log converted to a folder.
//!
//! ```text
//! cargo run -p examples --example to_parquet -- ../shared/testdata/ulog/pyulog/sample_log_small.ulg [OUT]
//! ```

use ulog_runtime::Log;
use ulog_runtime::columns::arrow::arrow_array::RecordBatchReader;
use ulog_runtime::columns::arrow::record_batches;
use ulog_runtime::columns::parquet::{Converter, ParquetOptions};

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let mut args = std::env::args_os().skip(1);
    let path = std::path::PathBuf::from(args.next().ok_or("usage: to_parquet FILE [OUT]")?);
    let out = args
        .next()
        .map_or_else(|| std::env::temp_dir().join("to_parquet"), Into::into);
    let log = Log::open(&path)?;

    // One topic instance as typed columns.
    if let Ok(battery) = log.columns("battery_status", 0) {
        let volts = battery
            .get("voltage_v")
            .and_then(|c| c.as_float())
            .unwrap_or_default();
        let mean = volts.iter().map(|&v| f64::from(v)).sum::<f64>() / volts.len().max(1) as f64;
        println!(
            "battery_status: {} rows, mean voltage {mean:.2} V",
            battery.rows()
        );
    }

    // The same as Arrow record batches of at most 10,000 rows.
    // (A log without the topic: an error that suggests the closest names it has.)
    if let Ok(batches) = record_batches(&log, "vehicle_attitude", 0, 10_000) {
        let schema = batches.schema();
        let (mut n, mut rows) = (0, 0);
        for batch in batches {
            n += 1;
            rows += batch?.num_rows();
        }
        println!(
            "vehicle_attitude: {rows} rows in {n} record batches, columns {:?}",
            schema.fields().iter().map(|f| f.name()).collect::<Vec<_>>()
        );
    }

    // The whole log as Parquet, one streaming pass.
    let conversion = Converter::new(&out, ParquetOptions::default()).convert_file(&path)?;
    let rows: usize = conversion.files.iter().map(|f| f.rows).sum();
    println!(
        "{} Parquet files ({rows} rows) and {} written",
        conversion.files.len(),
        conversion.metadata.display()
    );
    Ok(())
}
