//! What other readers make of a log: [`pyulog`], the data model pyulog 1.3.0's `ULog` builds
//! of a file, by its rules (what it keeps, skips and cuts), for code that must give the
//! answers a pyulog script gets (the Python package's `ulog.ULog`).

pub mod pyulog;
