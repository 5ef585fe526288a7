//! Example programs for `ulog-runtime`: see `examples/`.
