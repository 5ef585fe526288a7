//! Segments of the vehicle's state over time: flight modes (`vehicle_status.nav_state`,
//! with PX4's names), VTOL states, armed intervals, and flights (in the air, from
//! `vehicle_land_detected`: a takeoff starts one, a landing ends it).

use super::state::FlightState;
use super::{Interval, Missing, ModeSegment, VtolSegment};

/// The mode names flight-review-rs gives `nav_state` (PX4's `vehicle_status`
/// constants).
pub(crate) fn mode_name(nav_state: u8) -> &'static str {
    match nav_state {
        0 => "Manual",
        1 => "Altitude",
        2 => "Position",
        3 => "Mission",
        4 => "Loiter",
        5 => "RTL",
        10 => "Acro",
        12 => "Descend",
        13 => "Terminate",
        14 => "Offboard",
        15 => "Stabilized",
        17 => "Takeoff",
        18 => "Land",
        19 => "Follow",
        20 => "Precision Land",
        21 => "Orbit",
        22 => "VTOL Takeoff",
        _ => "Unknown",
    }
}

/// Segments being built: each open one's start and value.
#[derive(Debug, Clone, Default)]
pub(crate) struct Modes {
    mode: Option<(u64, u8)>,
    modes: Vec<ModeSegment>,
    vtol: Option<(u64, &'static str)>,
    vtols: Vec<VtolSegment>,
    armed_since: Option<u64>,
    armed: Vec<Interval>,
    air_since: Option<u64>,
    flights: Vec<Interval>,
    /// Mode changes in order (time, nav_state), for the mode at any time.
    changes: Vec<(u64, u8)>,
    /// The latest `vehicle_status` time: the open segments last at least until then.
    last_status: u64,
}

impl Modes {
    pub(super) fn status(
        &mut self,
        t: u64,
        nav: Option<u8>,
        armed: bool,
        vtol: Option<&'static str>,
    ) {
        self.last_status = self.last_status.max(t);
        if let Some(n) = nav
            && self.mode.is_none_or(|(_, m)| m != n)
        {
            if let Some((start, m)) = self.mode.take() {
                self.modes.push(segment(m, start, t));
            }
            self.mode = Some((t, n));
            self.changes.push((t, n));
        }
        match (armed, self.armed_since) {
            (true, None) => self.armed_since = Some(t),
            (false, Some(start)) => {
                self.armed.push(Interval {
                    start_us: start,
                    end_us: t,
                });
                self.armed_since = None;
            }
            _ => {}
        }
        if self.vtol.map(|(_, s)| s) != vtol {
            if let Some((start, s)) = self.vtol.take() {
                self.vtols.push(VtolSegment {
                    state: s.to_owned(),
                    start_us: start,
                    end_us: t,
                });
            }
            self.vtol = vtol.map(|s| (t, s));
        }
    }

    pub(super) fn land(&mut self, t: u64, in_air: bool) {
        match (in_air, self.air_since) {
            (true, None) => self.air_since = Some(t),
            (false, Some(start)) => {
                self.flights.push(Interval {
                    start_us: start,
                    end_us: t,
                });
                self.air_since = None;
            }
            _ => {}
        }
    }

    /// The flight mode at time `t`, if one was set by then.
    pub(crate) fn mode_at(&self, t: u64) -> Option<u8> {
        let k = self.changes.partition_point(|&(at, _)| at <= t);
        k.checked_sub(1).map(|k| self.changes[k].1)
    }

    /// Closes the open segments at `end` (the last row's time), or at the latest
    /// `vehicle_status` time if that is later (the last row of a damaged or cut log may be
    /// an old one of another topic).
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
        let end = end.max(self.last_status);
        let mut modes = self.modes.clone();
        if let Some((start, m)) = self.mode {
            modes.push(segment(m, start, end.max(start)));
        }
        let mut vtols = self.vtols.clone();
        if let Some((start, s)) = self.vtol {
            vtols.push(VtolSegment {
                state: s.to_owned(),
                start_us: start,
                end_us: end.max(start),
            });
        }
        // By start time: a log whose rows go back in time (appended parts) gives its
        // intervals out of order.
        let close = |mut v: Vec<Interval>, open: Option<u64>| {
            if let Some(start) = open {
                v.push(Interval {
                    start_us: start,
                    end_us: end.max(start),
                });
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

fn segment(mode: u8, start: u64, end: u64) -> ModeSegment {
    // A damaged log's time may run back: such a segment lasts no time, not 585,000 years.
    let end = end.max(start);
    ModeSegment {
        mode: mode_name(mode).to_owned(),
        mode_id: mode,
        start_us: start,
        end_us: end,
        duration_s: (end - start) as f64 / 1e6,
    }
}
