//! The geometry and the calendar of anonymizing: a rotation of the sphere that moves one
//! point to another (every distance and angle kept), and UTC dates moved by an offset.

/// The rotation taking one point of the sphere to another, north kept at the point:
/// `Rz(lon1) · Ry(lat1 - lat0) · Rz(-lon0)`, to the reference's meridian, along it to the
/// target's latitude, then around the axis to the target's longitude.
#[derive(Debug, Clone, Copy)]
pub(super) struct Rotation {
    m: [[f64; 3]; 3],
}

/// The unit vector of a latitude and longitude (degrees).
pub(super) fn unit(lat: f64, lon: f64) -> [f64; 3] {
    let (lat, lon) = (lat.to_radians(), lon.to_radians());
    [lat.cos() * lon.cos(), lat.cos() * lon.sin(), lat.sin()]
}

fn mul(a: [[f64; 3]; 3], b: [[f64; 3]; 3]) -> [[f64; 3]; 3] {
    let mut m = [[0.0; 3]; 3];
    for (i, row) in m.iter_mut().enumerate() {
        for (j, v) in row.iter_mut().enumerate() {
            *v = (0..3).map(|k| a[i][k] * b[k][j]).sum();
        }
    }
    m
}

impl Rotation {
    pub(super) fn new(from: (f64, f64), to: (f64, f64)) -> Rotation {
        let rz = |a: f64| {
            let (s, c) = a.to_radians().sin_cos();
            [[c, -s, 0.0], [s, c, 0.0], [0.0, 0.0, 1.0]]
        };
        // About the y axis: raises the latitude of a point on the 0° meridian.
        let ry = |a: f64| {
            let (s, c) = a.to_radians().sin_cos();
            [[c, 0.0, -s], [0.0, 1.0, 0.0], [s, 0.0, c]]
        };
        Rotation {
            m: mul(rz(to.1), mul(ry(to.0 - from.0), rz(-from.1))),
        }
    }

    /// The rotated latitude and longitude (longitude in `(-180, 180]`).
    pub(super) fn apply(&self, lat: f64, lon: f64) -> (f64, f64) {
        let p = unit(lat, lon);
        let q: [f64; 3] = std::array::from_fn(|i| {
            self.m[i][0] * p[0] + self.m[i][1] * p[1] + self.m[i][2] * p[2]
        });
        (
            q[2].clamp(-1.0, 1.0).asin().to_degrees(),
            q[1].atan2(q[0]).to_degrees(),
        )
    }
}

/// Days since 1970-01-01 of a proleptic Gregorian date.
pub(super) fn days_from_civil(year: i64, month: u32, day: u32) -> i64 {
    let y = if month <= 2 { year - 1 } else { year };
    let era = y.div_euclid(400);
    let yoe = y - era * 400;
    let m = i64::from(month);
    let doy = (153 * (if m > 2 { m - 3 } else { m + 9 }) + 2) / 5 + i64::from(day) - 1;
    let doe = yoe * 365 + yoe / 4 - yoe / 100 + doy;
    era * 146_097 + doe - 719_468
}

/// The date of a day since 1970-01-01.
pub(super) fn civil_from_days(days: i64) -> (i64, u32, u32) {
    let z = days + 719_468;
    let era = z.div_euclid(146_097);
    let doe = z - era * 146_097;
    let yoe = (doe - doe / 1460 + doe / 36_524 - doe / 146_096) / 365;
    let doy = doe - (365 * yoe + yoe / 4 - yoe / 100);
    let mp = (5 * doy + 2) / 153;
    let day = (doy - (153 * mp + 2) / 5 + 1) as u32;
    let month = if mp < 10 { mp + 3 } else { mp - 9 } as u32;
    (yoe + era * 400 + i64::from(month <= 2), month, day)
}

/// A UTC date and time of day (as PX4's `logger_open_file_time` event carries it) moved by
/// `offset_us`.
pub(super) fn shift_civil(
    (year, month, day, hour, minute, second): (i64, u32, u32, u32, u32, u32),
    offset_us: i64,
) -> (i64, u32, u32, u32, u32, u32) {
    let seconds = days_from_civil(year, month, day) * 86_400
        + i64::from(hour) * 3600
        + i64::from(minute) * 60
        + i64::from(second)
        + offset_us.div_euclid(1_000_000);
    let (days, rest) = (seconds.div_euclid(86_400), seconds.rem_euclid(86_400));
    let (y, m, d) = civil_from_days(days);
    #[allow(clippy::cast_possible_truncation, clippy::cast_sign_loss)]
    let rest = rest as u32;
    (y, m, d, rest / 3600, rest / 60 % 60, rest % 60)
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The angle between two points, as atan2(|p × q|, p · q) (precise at small angles), in
    /// meters on a sphere of the Earth's mean radius.
    fn dist(a: (f64, f64), b: (f64, f64)) -> f64 {
        let (p, q) = (unit(a.0, a.1), unit(b.0, b.1));
        let dot: f64 = (0..3).map(|i| p[i] * q[i]).sum();
        let cross = [
            p[1] * q[2] - p[2] * q[1],
            p[2] * q[0] - p[0] * q[2],
            p[0] * q[1] - p[1] * q[0],
        ];
        let norm = cross.iter().map(|c| c * c).sum::<f64>().sqrt();
        norm.atan2(dot) * 6_371_000.0
    }

    #[test]
    fn the_rotation_keeps_distances_and_north() {
        let r = Rotation::new((47.397_742, 8.545_594), (-33.9, 151.2));
        let (lat, lon) = r.apply(47.397_742, 8.545_594);
        assert!((lat + 33.9).abs() < 1e-9 && (lon - 151.2).abs() < 1e-9);
        // A point 100 m north stays 100 m north.
        let north = r.apply(47.397_742 + 100.0 / 111_195.0, 8.545_594);
        assert!((north.1 - 151.2).abs() < 1e-9, "{north:?}");
        for (a, b) in [
            ((47.39, 8.54), (47.41, 8.56)),
            ((47.39, 8.54), (47.390_01, 8.540_01)),
        ] {
            let d = dist(a, b);
            let moved = dist(r.apply(a.0, a.1), r.apply(b.0, b.1));
            assert!((d - moved).abs() < 1e-4, "{d} vs {moved}");
        }
    }

    #[test]
    fn dates_move_across_months_years_and_leap_days() {
        assert_eq!(days_from_civil(1970, 1, 1), 0);
        assert_eq!(days_from_civil(2000, 3, 1), 11_017);
        assert_eq!(civil_from_days(11_016), (2000, 2, 29));
        for days in [-1_000_000, -1, 0, 59, 10_957, 20_000, 2_000_000] {
            let (y, m, d) = civil_from_days(days);
            assert_eq!(days_from_civil(y, m, d), days);
        }
        // 2024-03-18 14:49:10 plus a day and a half less a second.
        assert_eq!(
            shift_civil((2024, 3, 18, 14, 49, 10), 129_599_000_000),
            (2024, 3, 20, 2, 49, 9)
        );
        assert_eq!(
            shift_civil((2024, 1, 1, 0, 0, 0), -1_000_000),
            (2023, 12, 31, 23, 59, 59)
        );
    }
}
