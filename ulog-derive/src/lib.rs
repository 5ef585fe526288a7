//! `#[derive(ULog)]` for typed ULog topics.
//!
//! The derive itself is not implemented yet: this crate is the proc-macro home it will live in.
//! Use `ulog_runtime`'s dynamic reader until then.
