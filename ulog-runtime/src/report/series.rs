//! The time series a report plots, read from a log by topic and field name: each
//! converted to seconds since the log's start and to the plot's unit, thinned to what a
//! plot can show (every bucket's lowest and highest value kept, so no spike is lost).

use crate::Log;
use crate::columns::{ColumnValues, Columns};

/// Points a series keeps at most.
pub(super) const MAX_POINTS: usize = 2400;

/// One line of a plot.
#[derive(Debug, Clone)]
pub(super) struct Series {
    pub(super) name: String,
    pub(super) points: Vec<(f64, f64)>,
}

/// One topic instance's columns, with its times in seconds since `t0` (µs).
pub(super) struct Table {
    columns: Columns,
    pub(super) time_s: Vec<f64>,
}

impl Table {
    /// The columns of `topic` #`multi_id`, if the log has rows of it.
    pub(super) fn read(log: &Log<'_>, topic: &str, multi_id: u8, t0: u64) -> Option<Table> {
        let columns = log.columns(topic, multi_id).ok()?;
        if columns.rows() == 0 {
            return None;
        }
        let time_s = columns
            .get("timestamp")?
            .as_uint64()?
            .iter()
            .map(|&t| (t as f64 - t0 as f64) / 1e6)
            .collect();
        Some(Table { columns, time_s })
    }

    /// A field's values as `f64`.
    pub(super) fn field(&self, name: &str) -> Option<Vec<f64>> {
        self.columns.get(name).and_then(ColumnValues::to_f64)
    }

    /// The first of `names` the table has.
    pub(super) fn first_field(&self, names: &[&str]) -> Option<Vec<f64>> {
        names.iter().find_map(|n| self.field(n))
    }

    /// A series of the table's times and `values` (finite ones), thinned.
    pub(super) fn series(&self, name: &str, values: &[f64]) -> Series {
        Series {
            name: name.to_owned(),
            points: thin(
                self.time_s
                    .iter()
                    .zip(values)
                    .filter(|(_, v)| v.is_finite())
                    .map(|(&t, &v)| (t, v)),
            ),
        }
    }
}

/// At most [`MAX_POINTS`] points of `points` (in time order): the lowest and highest of
/// each of `MAX_POINTS / 2` buckets of equal counts, in the order they came.
pub(super) fn thin(points: impl Iterator<Item = (f64, f64)>) -> Vec<(f64, f64)> {
    let all: Vec<(f64, f64)> = points.collect();
    if all.len() <= MAX_POINTS {
        return all;
    }
    let buckets = MAX_POINTS / 2;
    let mut out = Vec::with_capacity(MAX_POINTS);
    for b in 0..buckets {
        let bucket = &all[b * all.len() / buckets..(b + 1) * all.len() / buckets];
        let Some(lo) = (0..bucket.len()).min_by(|&i, &j| bucket[i].1.total_cmp(&bucket[j].1))
        else {
            continue;
        };
        let hi = (0..bucket.len())
            .max_by(|&i, &j| bucket[i].1.total_cmp(&bucket[j].1))
            .unwrap_or(lo);
        let (first, second) = if lo <= hi { (lo, hi) } else { (hi, lo) };
        out.push(bucket[first]);
        if second != first {
            out.push(bucket[second]);
        }
    }
    out
}

/// Roll, pitch and yaw (degrees) of unit quaternions `q` (w, x, y, z).
pub(super) fn euler_deg(q: [&[f64]; 4]) -> [Vec<f64>; 3] {
    let n = q[0].len();
    let mut out = [
        Vec::with_capacity(n),
        Vec::with_capacity(n),
        Vec::with_capacity(n),
    ];
    for (i, &w) in q[0].iter().enumerate() {
        let (x, y, z) = (q[1][i], q[2][i], q[3][i]);
        let roll = (2.0 * (w * x + y * z)).atan2(1.0 - 2.0 * (x * x + y * y));
        let pitch = (2.0 * (w * y - z * x)).clamp(-1.0, 1.0).asin();
        let yaw = (2.0 * (w * z + x * y)).atan2(1.0 - 2.0 * (y * y + z * z));
        out[0].push(roll.to_degrees());
        out[1].push(pitch.to_degrees());
        out[2].push(yaw.to_degrees());
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn thinning_keeps_each_buckets_extremes() {
        let points = (0..100_000).map(|i| {
            let t = f64::from(i);
            // A spike at one sample.
            (
                t,
                if i == 51_234 {
                    1000.0
                } else {
                    (t / 1000.0).sin()
                },
            )
        });
        let thin = thin(points);
        assert!(thin.len() <= MAX_POINTS);
        assert!(thin.iter().any(|p| p.1 == 1000.0), "the spike is kept");
        assert!(thin.windows(2).all(|w| w[0].0 < w[1].0), "in time order");
        let short = super::thin((0..10).map(|i| (f64::from(i), 0.0)));
        assert_eq!(short.len(), 10, "a short series as it is");
    }

    #[test]
    fn quaternions_give_their_angles() {
        // 30 degrees of roll, then 20 of pitch, then 90 of yaw.
        let q = |axis: usize, deg: f64| {
            let h = (deg.to_radians() / 2.0).sin_cos();
            let mut v = [h.1, 0.0, 0.0, 0.0];
            v[axis] = h.0;
            v
        };
        let qs = [q(1, 30.0), q(2, 20.0), q(3, 90.0)];
        let cols: Vec<Vec<f64>> = (0..4).map(|k| qs.iter().map(|q| q[k]).collect()).collect();
        let [roll, pitch, yaw] = euler_deg([&cols[0], &cols[1], &cols[2], &cols[3]]);
        assert!((roll[0] - 30.0).abs() < 1e-9 && pitch[0].abs() < 1e-9);
        assert!((pitch[1] - 20.0).abs() < 1e-9 && roll[1].abs() < 1e-9);
        assert!((yaw[2] - 90.0).abs() < 1e-9);
    }
}
