#![no_main]
//! See `ulog_fuzz::stream_chunks`.
libfuzzer_sys::fuzz_target!(|data: &[u8]| ulog_fuzz::stream_chunks(data));
