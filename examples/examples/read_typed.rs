//! Reads a real PX4 log into derived structs: the attitude quaternion and the IMU, with
//! fields that changed across PX4 versions declared optional.
//!
//! ```text
//! cargo run -p examples --example read_typed -- ../shared/testdata/ulog/pyulog/sample.ulg
//! ```

use ulog_runtime::{Log, ULog};

/// `vehicle_attitude` of any PX4 version: `rollspeed` left the topic in 2018,
/// `timestamp_sample` arrived in 2020.
#[derive(ULog, Debug)]
struct VehicleAttitude {
    timestamp: u64,
    q: [f32; 4],
    rollspeed: Option<f32>,
    timestamp_sample: Option<u64>,
}

/// The fields of `sensor_combined` that every PX4 version has, with the same types.
#[derive(ULog, Debug)]
struct SensorCombined {
    timestamp: u64,
    gyro_rad: [f32; 3],
    accelerometer_m_s2: [f32; 3],
}

/// Roll, pitch, yaw in degrees from a unit quaternion `[w, x, y, z]`.
fn euler_deg([w, x, y, z]: [f32; 4]) -> [f32; 3] {
    let roll = (2.0 * (w * x + y * z)).atan2(1.0 - 2.0 * (x * x + y * y));
    let pitch = (2.0 * (w * y - z * x)).clamp(-1.0, 1.0).asin();
    let yaw = (2.0 * (w * z + x * y)).atan2(1.0 - 2.0 * (y * y + z * z));
    [roll.to_degrees(), pitch.to_degrees(), yaw.to_degrees()]
}

fn main() -> std::process::ExitCode {
    match run() {
        Ok(()) => std::process::ExitCode::SUCCESS,
        Err(e) => {
            eprintln!("error: {e}");
            std::process::ExitCode::FAILURE
        }
    }
}

fn run() -> Result<(), Box<dyn std::error::Error>> {
    let path = std::env::args()
        .nth(1)
        .ok_or("usage: read_typed FILE.ulg")?;
    let log = Log::open(&path)?;

    let attitude = log.topic::<VehicleAttitude>()?;
    let rows: Vec<VehicleAttitude> = attitude.instance(attitude.multi_ids()[0])?.collect();
    let (first, last) = (rows.first().ok_or("empty")?, rows.last().ok_or("empty")?);
    let seconds = (last.timestamp - first.timestamp) as f64 / 1e6;
    println!(
        "vehicle_attitude: {} rows over {seconds:.1} s ({:.0} Hz); rollspeed {}, timestamp_sample {}",
        rows.len(),
        rows.len() as f64 / seconds.max(1e-9),
        if first.rollspeed.is_some() {
            "logged"
        } else {
            "absent"
        },
        if first.timestamp_sample.is_some() {
            "logged"
        } else {
            "absent"
        },
    );
    let max_tilt = rows
        .iter()
        .map(|r| {
            let [roll, pitch, _] = euler_deg(r.q);
            roll.abs().max(pitch.abs())
        })
        .fold(0.0f32, f32::max);
    println!(
        "  final roll/pitch/yaw {:.1?} deg, max tilt {max_tilt:.1} deg",
        euler_deg(last.q)
    );

    match log.topic::<SensorCombined>() {
        Ok(imu) => {
            let mut n = 0usize;
            let mut g = 0.0f64;
            for (_, row) in imu.rows() {
                let [x, y, z] = row.accelerometer_m_s2.map(f64::from);
                g += (x * x + y * y + z * z).sqrt();
                n += 1;
            }
            println!(
                "sensor_combined: {n} rows, mean |accel| {:.2} m/s²",
                g / n.max(1) as f64
            );
        }
        // A log without the topic, or with an incompatible definition, says which.
        Err(e) => println!("sensor_combined: {e}"),
    }
    Ok(())
}
