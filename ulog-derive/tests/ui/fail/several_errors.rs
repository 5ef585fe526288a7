// One build shows every problem of a struct: attribute errors, name errors and field types
// together, and code using the type gets no follow-on errors.
use ulog_runtime::{ULog, Writer, WriterOptions};

#[derive(ULog)]
#[ulog(topic = "sensor")]
struct Sensor {
    timestamp: u64,
    #[ulog(rename = "bad name")]
    value: f32,
    history: Vec<f32>,
    #[ulog(padding, padding)]
    _pad: [u8; 3],
}

fn main() {
    let mut w = Writer::new(Vec::new(), WriterOptions::default()).unwrap();
    let _sub = w.topic::<Sensor>(0).unwrap();
    let _format = Sensor::FORMAT.to_format();
}
