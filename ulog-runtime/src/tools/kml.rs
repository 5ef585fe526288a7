//! `ulog2kml`: the GPS track of a log as KML, one line per stretch of one flight mode, as
//! pyulog 1.3.0 makes it and simplekml writes it.

use crate::Log;
use crate::columns::{ColumnValues, Columns};
use crate::pytext::f64_text;

/// The flight modes' colors (KML `aabbggrr`), as pyulog picks them from simplekml's named
/// colors: red, green, blue, violet, yellow, orange, burlywood, azure, lightblue,
/// lawngreen, indianred, hotpink, bisque, cyan, darksalmon, deepskyblue, lime, orchid.
const COLORS: [&str; 18] = [
    "ff0000ff", "ff008000", "ffff0000", "ffee82ee", "ff00ffff", "ff00a5ff", "ff87b8de", "fffffff0",
    "ffe6d8ad", "ff00fc7c", "ff5c5ccd", "ffb469ff", "ffc4e4ff", "ffffff00", "ff7a96e9", "ffffbf00",
    "ff00ff00", "ffd670da",
];

/// Position topics, newest first.
const GNSS_TOPICS: [&str; 2] = ["vehicle_gnss", "vehicle_gps_position"];

/// The names each position field has in one topic or another.
const FIELDS: [(&str, &[&str]); 4] = [
    ("lon", &["lon", "longitude_deg", "receiver.longitude"]),
    ("lat", &["lat", "latitude_deg", "receiver.latitude"]),
    ("alt", &["alt", "altitude_msl_m", "receiver.altitude_msl"]),
    ("fix_type", &["fix_type", "receiver.fix_type"]),
];

/// What [`kml`] draws.
#[derive(Debug, Clone, Default, PartialEq, Eq)]
pub struct KmlOptions {
    /// The position topic (`--topic`); the default is pyulog's.
    pub topic: Option<String>,
    /// A camera trigger topic (`--camera-trigger`, e.g. `camera_capture`) with `lon`,
    /// `lat`, `alt` and `seq`.
    pub camera_trigger: Option<String>,
}

/// Why there is no track.
#[derive(Debug, Clone, PartialEq, Eq, thiserror::Error)]
#[non_exhaustive]
pub enum KmlError {
    /// The topic has no rows in instance 0 (pyulog: `KeyError: '... not found in data'`).
    #[error("{0} not found in data (no rows of its instance 0)")]
    NoTopic(String),
    /// A field the track needs is missing.
    #[error("{topic}: no `{field}` field (nor any of its other names)")]
    NoField {
        /// The topic.
        topic: String,
        /// The field.
        field: String,
    },
}

/// The KML document `ulog2kml` writes for `log`.
///
/// `ulog2kml`: the GPS track of a log as KML, one line per stretch of one flight mode, as
/// pyulog 1.3.0 makes it and simplekml writes it.
///
/// The track is instance 0 of the position topic (`vehicle_gnss`, or `vehicle_gps_position`
/// in older logs, unless one is named): `lon`, `lat`, `alt` under whichever names the topic
/// uses (`longitude_deg`, `receiver.longitude`...), rows with `fix_type` above 2 only,
/// `int32_t` degrees × 1e7 and millimetres scaled; a point at most every 0.1 s. A new line
/// starts at each change of `vehicle_status.nav_state` (and at the end of the log), colored
/// by the flight mode; camera trigger placemarks (`--camera-trigger TOPIC`) follow.
pub fn kml(log: &Log<'_>, options: &KmlOptions) -> Result<String, KmlError> {
    let topic = match &options.topic {
        Some(t) => t.clone(),
        None => {
            let logged = |t: &str| log.topics().iter().any(|s| s.name == t);
            match GNSS_TOPICS.into_iter().find(|t| logged(t)) {
                Some(t) => t.to_owned(),
                // Neither: the error names both.
                None => return Err(KmlError::NoTopic(GNSS_TOPICS.join(" or "))),
            }
        }
    };
    let mut loaded = vec![topic.clone(), "vehicle_status".to_owned()];
    loaded.extend(options.camera_trigger.clone());
    let last_timestamp = log
        .subscriptions()
        .iter()
        .filter(|s| loaded.contains(&s.name))
        .filter_map(|s| log.rows(s).map(|r| r.timestamp).max())
        .fold(log.header().start_timestamp, u64::max);
    let mut doc = Document::default();
    let modes = flight_modes(log, last_timestamp);
    track(log, &topic, &modes, &mut doc)?;
    if let Some(camera) = &options.camera_trigger {
        triggers(log, camera, &mut doc)?;
    }
    Ok(doc.finish())
}

/// `vehicle_status.nav_state` at each change (the first row with a non-zero timestamp, and
/// each row whose value differs from the previous one), then `(last_timestamp, -1)`; empty
/// without `vehicle_status` or its `nav_state`.
fn flight_modes(log: &Log<'_>, last_timestamp: u64) -> Vec<(u64, i64)> {
    let Ok(status) = log.columns("vehicle_status", 0) else {
        return Vec::new();
    };
    let (Some(t), Some(x)) = (
        status.get("timestamp").and_then(ColumnValues::as_uint64),
        status.get("nav_state").and_then(ints),
    ) else {
        return Vec::new();
    };
    let kept: Vec<(u64, i64)> = t
        .iter()
        .zip(x)
        .filter(|(t, _)| **t != 0)
        .map(|(t, x)| (*t, x))
        .collect();
    let mut out: Vec<(u64, i64)> = Vec::new();
    for (i, &(t, x)) in kept.iter().enumerate() {
        if i == 0 || kept[i - 1].1 != x {
            out.push((t, x));
        }
    }
    // The end, even when no row counted (as pyulog appends it).
    out.push((last_timestamp, -1));
    out
}

/// An integer column's values.
fn ints(c: &ColumnValues) -> Option<Vec<i64>> {
    Some(match c {
        ColumnValues::Int8(v) => v.iter().map(|&x| x.into()).collect(),
        ColumnValues::UInt8(v) | ColumnValues::Char(v) => v.iter().map(|&x| x.into()).collect(),
        ColumnValues::Int16(v) => v.iter().map(|&x| x.into()).collect(),
        ColumnValues::UInt16(v) => v.iter().map(|&x| x.into()).collect(),
        ColumnValues::Int32(v) => v.iter().map(|&x| x.into()).collect(),
        ColumnValues::UInt32(v) => v.iter().map(|&x| x.into()).collect(),
        ColumnValues::Int64(v) => v.clone(),
        ColumnValues::UInt64(v) => v.iter().map(|&x| x as i64).collect(),
        ColumnValues::Bool(v) => v.iter().map(|&x| x.into()).collect(),
        _ => return None,
    })
}

/// A position field's column under any of its names.
fn field<'c>(cols: &'c Columns, name: &str) -> Option<(&'c str, &'c ColumnValues)> {
    let (_, names) = FIELDS
        .iter()
        .find(|(n, _)| *n == name)
        .expect("a known field");
    names.iter().find_map(|n| cols.get(n).map(|c| (*n, c)))
}

fn required<'c>(cols: &'c Columns, topic: &str, name: &str) -> Result<&'c ColumnValues, KmlError> {
    field(cols, name)
        .map(|(_, c)| c)
        .ok_or_else(|| KmlError::NoField {
            topic: topic.to_owned(),
            field: name.to_owned(),
        })
}

fn floats(c: &ColumnValues) -> Vec<f64> {
    c.to_f64().unwrap_or_default()
}

/// The track's lines, a new one at each flight mode change.
fn track(
    log: &Log<'_>,
    topic: &str,
    modes: &[(u64, i64)],
    doc: &mut Document,
) -> Result<(), KmlError> {
    let cols = log
        .columns(topic, 0)
        .ok()
        .filter(|c| c.rows() > 0)
        .ok_or_else(|| KmlError::NoTopic(topic.to_owned()))?;
    let mut lon = floats(required(&cols, topic, "lon")?);
    let mut lat = floats(required(&cols, topic, "lat")?);
    let mut alt = floats(required(&cols, topic, "alt")?);
    let mut t: Vec<u64> = cols
        .get("timestamp")
        .and_then(ColumnValues::as_uint64)
        .unwrap_or_default()
        .to_vec();
    if let Some((_, fix)) = field(&cols, "fix_type") {
        let keep: Vec<bool> = floats(fix).iter().map(|&f| f > 2.0).collect();
        let filter = |v: &mut Vec<f64>| {
            let mut k = keep.iter();
            v.retain(|_| *k.next().unwrap_or(&false));
        };
        filter(&mut lon);
        filter(&mut lat);
        filter(&mut alt);
        let mut k = keep.iter();
        t.retain(|_| *k.next().unwrap_or(&false));
    }
    // Integer degrees × 1e7 and millimetres, in older topics.
    if cols
        .defs()
        .iter()
        .any(|d| d.name == "lon" && d.ulog_type == "int32_t")
    {
        lon.iter_mut().for_each(|x| *x /= 1e7);
        lat.iter_mut().for_each(|x| *x /= 1e7);
        alt.iter_mut().for_each(|x| *x /= 1e3);
    }
    let mut mode = modes.first().map_or(0, |m| m.1);
    let mut mode_idx = 0;
    let mut line = doc.line(topic, mode);
    let mut last_t = 0u64;
    for i in 0..lon.len().min(lat.len()).min(alt.len()).min(t.len()) {
        let cur_t = t[i];
        // pyulog subtracts unsigned 64-bit timestamps: a row older than the last point
        // wraps around, and counts as far later.
        if cur_t.wrapping_sub(last_t) as f64 / 1e6 > 0.1 {
            let point = (lon[i], lat[i], alt[i]);
            doc.point_on(line, point);
            last_t = cur_t;
            while mode_idx + 1 < modes.len() && modes[mode_idx + 1].0 <= cur_t {
                mode_idx += 1;
                mode = modes[mode_idx].1;
                line = doc.line(topic, mode);
                doc.point_on(line, point);
            }
        }
    }
    Ok(())
}

/// A placemark per camera trigger of instance 0 of `topic`.
fn triggers(log: &Log<'_>, topic: &str, doc: &mut Document) -> Result<(), KmlError> {
    let Some(cols) = log.columns(topic, 0).ok().filter(|c| c.rows() > 0) else {
        return Ok(());
    };
    let lon = floats(required(&cols, topic, "lon")?);
    let lat = floats(required(&cols, topic, "lat")?);
    let alt = floats(required(&cols, topic, "alt")?);
    let seq = cols
        .get("seq")
        .and_then(ints)
        .ok_or_else(|| KmlError::NoField {
            topic: topic.to_owned(),
            field: "seq".to_owned(),
        })?;
    for i in 0..lon.len() {
        doc.trigger(seq[i], (lon[i], lat[i], alt[i]));
    }
    Ok(())
}

/// A KML document as simplekml writes it: every feature and style numbered in the order
/// it is made, styles first.
#[derive(Default)]
struct Document {
    next_id: u32,
    styles: Vec<String>,
    features: Vec<Feature>,
}

enum Feature {
    Line {
        id: u32,
        placemark: u32,
        style: u32,
        name: String,
        coords: Vec<(f64, f64, f64)>,
    },
    Point {
        id: u32,
        placemark: u32,
        name: String,
        coord: (f64, f64, f64),
    },
}

impl Document {
    fn id(&mut self) -> u32 {
        // The document itself is 1.
        self.next_id = self.next_id.max(1) + 1;
        self.next_id
    }

    /// A new line for a flight mode; returns its index.
    fn line(&mut self, topic: &str, mode: i64) -> usize {
        let id = self.id();
        let placemark = self.id();
        let style = self.id();
        let line_style = self.id();
        let color = COLORS[(mode.max(0) as usize) % COLORS.len()];
        self.styles.push(format!(
            "        <Style id=\"{style}\">\n            <LineStyle id=\"{line_style}\">\n                <color>{color}</color>\n                <colorMode>normal</colorMode>\n                <width>3</width>\n            </LineStyle>\n        </Style>\n"
        ));
        self.features.push(Feature::Line {
            id,
            placemark,
            style,
            name: format!("{topic}:{mode}"),
            coords: Vec::new(),
        });
        self.features.len() - 1
    }

    fn point_on(&mut self, line: usize, p: (f64, f64, f64)) {
        if let Feature::Line { coords, .. } = &mut self.features[line] {
            coords.push(p);
        }
    }

    fn trigger(&mut self, seq: i64, coord: (f64, f64, f64)) {
        let id = self.id();
        let placemark = self.id();
        self.features.push(Feature::Point {
            id,
            placemark,
            name: format!("Camera Trigger {seq}"),
            coord,
        });
    }

    fn finish(self) -> String {
        let coord =
            |(x, y, z): (f64, f64, f64)| format!("{},{},{}", f64_text(x), f64_text(y), f64_text(z));
        let mut out = String::from(
            "<?xml version=\"1.0\" encoding=\"UTF-8\"?>\n<kml xmlns=\"http://www.opengis.net/kml/2.2\" xmlns:gx=\"http://www.google.com/kml/ext/2.2\">\n    <Document id=\"1\">\n",
        );
        for s in &self.styles {
            out.push_str(s);
        }
        for f in &self.features {
            match f {
                Feature::Line {
                    id,
                    placemark,
                    style,
                    name,
                    coords,
                } => {
                    let text = if coords.is_empty() {
                        "0.0, 0.0, 0.0".to_owned()
                    } else {
                        coords.iter().map(|&c| coord(c)).collect::<Vec<_>>().join(" ")
                    };
                    out.push_str(&format!(
                        "        <Placemark id=\"{placemark}\">\n            <name>{}</name>\n            <styleUrl>#{style}</styleUrl>\n            <LineString id=\"{id}\">\n                <altitudeMode>absolute</altitudeMode>\n                <coordinates>{text}</coordinates>\n            </LineString>\n        </Placemark>\n",
                        escape(name)
                    ));
                }
                Feature::Point {
                    id,
                    placemark,
                    name,
                    coord: c,
                } => out.push_str(&format!(
                    "        <Placemark id=\"{placemark}\">\n            <name>{}</name>\n            <Point id=\"{id}\">\n                <coordinates>{}</coordinates>\n            </Point>\n        </Placemark>\n",
                    escape(name),
                    coord(*c)
                )),
            }
        }
        out.push_str("    </Document>\n</kml>\n");
        out
    }
}

/// Text for an XML element.
fn escape(s: &str) -> String {
    s.replace('&', "&amp;")
        .replace('<', "&lt;")
        .replace('>', "&gt;")
}
