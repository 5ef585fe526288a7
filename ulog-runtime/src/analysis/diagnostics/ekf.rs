//! EKF innovation failure: in flight, one of `estimator_status`'s innovation test ratios
//! (velocity, position, height, magnetometer, airspeed, sideslip; from PX4 1.16 on, where
//! `mag_test_ratio` is gone, heading: `hdg_test_ratio`) above 1 (the innovation outside its
//! gate) for at least 2 s without a break: a warning, critical from 5 s. A ratio that is not
//! finite (PX4 writes `inf` while a test has no variance to judge by) neither extends nor
//! ends an episode. One finding per episode, per estimator instance and innovation.

use super::{Diagnostic, Episode, Evidence, Severity, secs};
use crate::analysis::LazyIndex;
use crate::analysis::state::FlightState;
use crate::columns::Leaf;

/// The ratio above which an innovation fails its test.
pub const THRESHOLD: f64 = 1.0;
/// Episodes at least this long are warnings, µs.
pub const WARNING_US: u64 = 2_000_000;
/// And this long critical.
pub const CRITICAL_US: u64 = 5_000_000;

const RATIOS: [(&str, &str); 7] = [
    ("vel_test_ratio", "velocity"),
    ("pos_test_ratio", "position"),
    ("hgt_test_ratio", "height"),
    ("mag_test_ratio", "magnetometer"),
    ("tas_test_ratio", "airspeed"),
    ("beta_test_ratio", "sideslip"),
    // PX4 1.16's replacement of `mag_test_ratio`: read only where that is absent.
    ("hdg_test_ratio", "heading"),
];

/// [`RATIOS`]' index of `mag_test_ratio`, and of `hdg_test_ratio` that replaced it.
const MAG: usize = 3;
const HEADING: usize = 6;

/// Where `estimator_status`'s ratios are.
pub(crate) struct Fields {
    multi_id: u8,
    ratios: Vec<(usize, Leaf)>,
}

impl Fields {
    pub(crate) fn bind(multi_id: u8, index: &LazyIndex<'_>) -> Option<Fields> {
        let ratios: Vec<(usize, Leaf)> = RATIOS
            .iter()
            .enumerate()
            .filter_map(|(k, (name, _))| Some((k, index.get(name)?)))
            .collect();
        let has_mag = ratios.iter().any(|&(k, _)| k == MAG);
        let ratios: Vec<(usize, Leaf)> = ratios
            .into_iter()
            .filter(|&(k, _)| !(k == HEADING && has_mag))
            .collect();
        (!ratios.is_empty()).then_some(Fields { multi_id, ratios })
    }
}

#[derive(Debug, Clone, Default)]
struct Track {
    episode: Episode,
    worst: f64,
}

/// Where ratio `k` of `f`'s estimator is in [`Ekf`]'s `slots`.
fn slot(f: &Fields, k: usize) -> usize {
    usize::from(f.multi_id) * RATIOS.len() + k
}

/// Every estimator's innovations.
#[derive(Debug, Clone, Default)]
pub(crate) struct Ekf {
    /// In the order they were first seen.
    tracks: Vec<((u8, usize), Track)>,
    /// Per estimator instance and ratio (`multi_id * RATIOS.len() + k`): its track's index + 1.
    slots: Vec<u16>,
    /// Episodes open now, over every track.
    open: usize,
    found: Vec<(u8, usize, u64, u64, f64)>,
}

impl Ekf {
    pub(crate) fn row(&mut self, f: &Fields, data: &[u8], t: u64, state: &FlightState) {
        let flying = state.flying();
        // Out of flight, with no episode to end and a track for every ratio (the first
        // sight of each makes it, in order), a row changes nothing: its ratios are not read.
        if !flying && self.open == 0 && f.ratios.iter().all(|&(k, _)| self.tracks_of(f, k)) {
            return;
        }
        for &(k, leaf) in &f.ratios {
            let Some(r) = leaf.f64(data).filter(|r| r.is_finite()) else {
                continue;
            };
            let slot = slot(f, k);
            if self.slots.len() <= slot {
                self.slots.resize(slot + 1, 0);
            }
            if self.slots[slot] == 0 {
                self.tracks.push(((f.multi_id, k), Track::default()));
                // At most 256 instances × 7 ratios.
                self.slots[slot] = self.tracks.len() as u16;
            }
            let track = &mut self.tracks[usize::from(self.slots[slot]) - 1].1;
            let bad = flying && r > THRESHOLD;
            if bad {
                track.worst = track.worst.max(r);
            }
            let was_open = track.episode.since.is_some();
            if let Some((start, end)) = track.episode.see(bad, t) {
                if end - start >= WARNING_US {
                    self.found.push((f.multi_id, k, start, end, track.worst));
                }
                track.worst = 0.0;
            }
            match (was_open, track.episode.since.is_some()) {
                (false, true) => self.open += 1,
                (true, false) => self.open -= 1,
                _ => {}
            }
        }
    }

    /// Whether ratio `k` of `f`'s estimator has a track.
    fn tracks_of(&self, f: &Fields, k: usize) -> bool {
        self.slots.get(slot(f, k)).is_some_and(|&s| s != 0)
    }

    /// Whether any row was taken.
    pub(crate) fn seen(&self) -> bool {
        !self.tracks.is_empty()
    }

    pub(crate) fn finish(mut self, end: u64) -> Vec<Diagnostic> {
        for ((m, k), track) in &mut self.tracks {
            if let Some((start, stop)) = track.episode.close(end)
                && stop - start >= WARNING_US
            {
                self.found.push((*m, *k, start, stop, track.worst));
            }
        }
        self.found
            .into_iter()
            .map(|(multi_id, k, start, end, ratio)| {
                let name = RATIOS[k].1;
                Diagnostic {
                    id: "ekf_failure".to_owned(),
                    summary: format!(
                        "EKF {multi_id} {name} innovation test ratio above 1 (up to {ratio:.2}) \
                         for {:.1} s from {:.1} s in flight",
                        secs(end - start),
                        secs(start)
                    ),
                    severity: if end - start >= CRITICAL_US {
                        Severity::Critical
                    } else {
                        Severity::Warning
                    },
                    timestamp_us: start,
                    end_timestamp_us: Some(end),
                    evidence: Evidence::EkfFailure {
                        multi_id,
                        innovation: name.to_owned(),
                        test_ratio: ratio,
                        threshold: THRESHOLD,
                    },
                }
            })
            .collect()
    }
}
