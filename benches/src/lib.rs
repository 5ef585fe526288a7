//! What the benchmarks share: the baselines they are measured against in the same run.
//!
//! - [`px4_ulog_ref`]: px4-ulog 0.6.1 computing the `scan` figures (`px4_ulog_scan FILE`).

pub mod px4_ulog_ref;
