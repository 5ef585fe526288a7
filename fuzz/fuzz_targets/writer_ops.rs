#![no_main]
//! See `ulog_fuzz::writer_ops`.
libfuzzer_sys::fuzz_target!(|data: &[u8]| ulog_fuzz::writer_ops(data));
