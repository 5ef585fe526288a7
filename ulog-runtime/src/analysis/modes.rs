//! Segments of the vehicle's state over time: flight modes (`vehicle_status.nav_state`,
//! with PX4's names), VTOL states, armed intervals, and flights (in the air, from
//! `vehicle_land_detected`: a takeoff starts one, a landing ends it). Where a topic's time
//! runs back (a damaged log, or parts of logs joined), its open segments end at its last
//! time before the jump and start again at the new time.

use super::state::FlightState;
use super::{Interval, Missing, ModeSegment, VtolSegment};

/// The firmware's (major, minor) version, where the log gives it (`ver_sw_release`, not
/// 0): two `nav_state` values changed meaning between PX4 versions.
pub(crate) type Version = Option<(u8, u8)>;

/// `nav_state` 23 to 30 (PX4 1.15 on): modes of external components (ROS 2, say).
const EXTERNAL: [&str; 8] = [
    "External 1",
    "External 2",
    "External 3",
    "External 4",
    "External 5",
    "External 6",
    "External 7",
    "External 8",
];

/// The mode name of a `nav_state` (PX4's `vehicle_status` constants): flight-review-rs's
/// names; for the modes of older PX4 it does not name (6 to 9, 16), Flight Review's; for
/// the newer ones, PX4's. Two values changed meaning: 6 is RC Recovery before PX4 1.15 and
/// Position Slow from it on, 8 is Land (engine fail) before PX4 1.17 and Altitude Cruise
/// from it on; in a log without the version they are "Unknown", as every value PX4 does
/// not name is.
pub(crate) fn mode_name(nav_state: u8, version: Version) -> &'static str {
    let from = |major: u8, minor: u8| version.map(|v| v >= (major, minor));
    match nav_state {
        0 => "Manual",
        1 => "Altitude",
        2 => "Position",
        3 => "Mission",
        4 => "Loiter",
        5 => "RTL",
        6 => match from(1, 15) {
            Some(true) => "Position Slow",
            Some(false) => "RC Recovery",
            None => "Unknown",
        },
        7 => "Return to groundstation",
        8 => match from(1, 17) {
            Some(true) => "Altitude Cruise",
            Some(false) => "Land (engine fail)",
            None => "Unknown",
        },
        9 => "Land (GPS fail)",
        10 => "Acro",
        12 => "Descend",
        13 => "Terminate",
        14 => "Offboard",
        15 => "Stabilized",
        16 => "Rattitude",
        17 => "Takeoff",
        18 => "Land",
        19 => "Follow",
        20 => "Precision Land",
        21 => "Orbit",
        22 => "VTOL Takeoff",
        23..=30 => EXTERNAL[usize::from(nav_state - 23)],
        _ => "Unknown",
    }
}

/// Segments being built: each open one's start and value.
#[derive(Debug, Clone, Default)]
pub(crate) struct Modes {
    mode: Option<(u64, u8)>,
    /// Closed mode segments: (nav_state, start, end).
    modes: Vec<(u8, u64, u64)>,
    vtol: Option<(u64, &'static str)>,
    vtols: Vec<VtolSegment>,
    armed_since: Option<u64>,
    armed: Vec<Interval>,
    air_since: Option<u64>,
    flights: Vec<Interval>,
    /// Mode changes in order (time, nav_state), for the mode at any time.
    changes: Vec<(u64, u8)>,
    /// The last `vehicle_status` row's time (the open segments last at least until then),
    /// and `vehicle_land_detected`'s.
    prev_status: Option<u64>,
    prev_land: Option<u64>,
}

impl Modes {
    pub(super) fn status(
        &mut self,
        t: u64,
        nav: Option<u8>,
        armed: bool,
        vtol: Option<&'static str>,
    ) {
        if let Some(prev) = self.prev_status.replace(t)
            && t < prev
        {
            // Time ran back: what is open ends at the last time before the jump, and
            // starts again below as this row says.
            if let Some((start, m)) = self.mode.take() {
                self.modes.push((m, start, prev));
            }
            if let Some(start) = self.armed_since.take() {
                self.armed.push(interval(start, prev));
            }
            if let Some((start, s)) = self.vtol.take() {
                self.vtols.push(vtol_segment(s, start, prev));
            }
        }
        if let Some(n) = nav
            && self.mode.is_none_or(|(_, m)| m != n)
        {
            if let Some((start, m)) = self.mode.take() {
                self.modes.push((m, start, t));
            }
            self.mode = Some((t, n));
            self.changes.push((t, n));
        }
        match (armed, self.armed_since) {
            (true, None) => self.armed_since = Some(t),
            (false, Some(start)) => {
                self.armed.push(interval(start, t));
                self.armed_since = None;
            }
            _ => {}
        }
        if self.vtol.map(|(_, s)| s) != vtol {
            if let Some((start, s)) = self.vtol.take() {
                self.vtols.push(vtol_segment(s, start, t));
            }
            self.vtol = vtol.map(|s| (t, s));
        }
    }

    pub(super) fn land(&mut self, t: u64, in_air: bool) {
        if let Some(prev) = self.prev_land.replace(t)
            && t < prev
            && let Some(start) = self.air_since.take()
        {
            self.flights.push(interval(start, prev));
        }
        match (in_air, self.air_since) {
            (true, None) => self.air_since = Some(t),
            (false, Some(start)) => {
                self.flights.push(interval(start, t));
                self.air_since = None;
            }
            _ => {}
        }
    }

    /// The mode changes by time, for [`Modes::mode_at`] (a log whose time runs back
    /// gives them out of order).
    pub(crate) fn sort_changes(&mut self) {
        self.changes.sort_by_key(|&(at, _)| at);
    }

    /// The flight mode at time `t`, if one was set by then (after [`Modes::sort_changes`]).
    pub(crate) fn mode_at(&self, t: u64) -> Option<u8> {
        let k = self.changes.partition_point(|&(at, _)| at <= t);
        k.checked_sub(1).map(|k| self.changes[k].1)
    }

    /// Closes the open segments at `end` (the last row's time), or at the last
    /// `vehicle_status` row's time if that is later (the last row of a damaged or cut log
    /// may be an old one of another topic).
    #[allow(clippy::type_complexity)]
    pub(super) fn finish(
        &self,
        end: u64,
        state: &FlightState,
        missing: &mut Vec<Missing>,
    ) -> (
        Vec<ModeSegment>,
        Vec<VtolSegment>,
        Vec<Interval>,
        Vec<Interval>,
    ) {
        let end = end.max(self.prev_status.unwrap_or(0));
        let mut modes: Vec<ModeSegment> = self
            .modes
            .iter()
            .map(|&(m, start, stop)| segment(m, start, stop, state.version))
            .collect();
        if let Some((start, m)) = self.mode {
            modes.push(segment(m, start, end, state.version));
        }
        let mut vtols = self.vtols.clone();
        if let Some((start, s)) = self.vtol {
            vtols.push(vtol_segment(s, start, end));
        }
        // By start time: a log whose rows go back in time (appended parts, logs joined)
        // gives its segments out of order.
        modes.sort_by_key(|m| m.start_us);
        vtols.sort_by_key(|v| v.start_us);
        let close = |mut v: Vec<Interval>, open: Option<u64>| {
            if let Some(start) = open {
                v.push(interval(start, end));
            }
            v.sort_by_key(|i| i.start_us);
            v
        };
        if !state.status_seen {
            missing.push(Missing {
                fact: "flight_modes, vtol_states, armed".to_owned(),
                reason: "the log has no vehicle_status rows".to_owned(),
            });
        }
        if state.in_air.is_none() {
            missing.push(Missing {
                fact: "flights".to_owned(),
                reason:
                    "the log has no vehicle_land_detected rows (in-air facts use the armed time)"
                        .to_owned(),
            });
        }
        (
            modes,
            vtols,
            close(self.armed.clone(), self.armed_since),
            close(self.flights.clone(), self.air_since),
        )
    }
}

// A damaged log's time may run back: a segment or interval whose end would come before its
// start lasts no time, not 585,000 years.

fn segment(mode: u8, start: u64, end: u64, version: Version) -> ModeSegment {
    let end = end.max(start);
    ModeSegment {
        mode: mode_name(mode, version).to_owned(),
        mode_id: mode,
        start_us: start,
        end_us: end,
        duration_s: (end - start) as f64 / 1e6,
    }
}

fn vtol_segment(state: &str, start: u64, end: u64) -> VtolSegment {
    VtolSegment {
        state: state.to_owned(),
        start_us: start,
        end_us: end.max(start),
    }
}

fn interval(start: u64, end: u64) -> Interval {
    Interval {
        start_us: start,
        end_us: end.max(start),
    }
}
