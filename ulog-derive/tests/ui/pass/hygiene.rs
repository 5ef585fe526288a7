#![no_implicit_prelude]
#![deny(warnings)]
// The generated code names nothing through the prelude, and user items named like std ones
// do not confuse it.

extern crate core;
extern crate std;
extern crate ulog_runtime;

#[allow(dead_code)]
struct Vec;
#[allow(dead_code)]
struct Option;
#[allow(dead_code)]
struct Self_;
#[allow(dead_code)]
type Result = ();

#[derive(ulog_runtime::ULog)]
struct Inner {
    a: i16,
    #[ulog(padding)]
    _pad: [u8; 2],
}

#[derive(ulog_runtime::ULog)]
#[ulog(widen, topics("hygienic_widened", "also_widened"))]
struct Widened {
    timestamp: u64,
    #[ulog(widen)]
    wide: [f64; 2],
    one: ulog_runtime::Char,
}

#[derive(ulog_runtime::ULog)]
#[ulog(name = "hygienic_topic", exact)]
struct Hygienic {
    timestamp: u64,
    inner: [Inner; 2],
    maybe: ::core::option::Option<f32>,
    text: ulog_runtime::Chars<4>,
    #[ulog(rename = "type")]
    r#kind: u8,
}

fn main() {
    let fields = <Hygienic as ulog_runtime::ULog>::FORMAT.fields.len();
    ::std::assert_eq!(fields, 5);
    ::std::assert_eq!(<Widened as ulog_runtime::ULog>::FORMAT.topics.len(), 3);
}
