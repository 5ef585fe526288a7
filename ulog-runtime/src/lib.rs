//! Read PX4 ULog (`.ulg`) flight logs.
//!
//! Modules: [`schema`] (formats and layouts), [`read`] (zero-copy and streaming readers with
//! corruption recovery), [`value`] (dynamic values for any format).

pub mod schema;
