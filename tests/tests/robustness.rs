//! Robustness suite (see below).
