//! The integration tests over the corpus and the independent references, in one binary (one
//! link; the Python package's tests, which wait on pytest, run beside the others). Run one
//! part with a filter: `cargo test -p ulog-tests --test integration conformance::`.

mod conformance;
mod python;
mod robustness;
mod scan;
mod typed;
mod writer;
