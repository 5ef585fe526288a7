//! The vehicle's state as the rows go by: armed, in the air, its flight mode and VTOL
//! state, read from `vehicle_status` and `vehicle_land_detected`; what the other consumers
//! ask of each row ("was it flying then?"), and what [`Modes`] makes segments of.

use super::modes::{Modes, Version};
use crate::analysis::LazyIndex;
use crate::columns::Leaf;

/// Where a state topic's fields are.
pub(super) enum Fields {
    Status {
        nav_state: Option<Leaf>,
        arming_state: Option<Leaf>,
        vehicle_type: Option<Leaf>,
        in_transition_mode: Option<Leaf>,
        is_vtol: Option<Leaf>,
        is_rotary_wing: Option<Leaf>,
    },
    Land {
        landed: Leaf,
    },
}

impl Fields {
    pub(super) fn bind(topic: &str, index: &LazyIndex<'_>) -> Option<Fields> {
        match topic {
            "vehicle_status" => Some(Fields::Status {
                nav_state: index.get("nav_state"),
                arming_state: index.get("arming_state"),
                vehicle_type: index.get("vehicle_type"),
                in_transition_mode: index.get("in_transition_mode"),
                is_vtol: index.get("is_vtol"),
                is_rotary_wing: index.get("is_rotary_wing"),
            }),
            "vehicle_land_detected" => Some(Fields::Land {
                landed: index.get("landed")?,
            }),
            _ => None,
        }
    }
}

/// PX4's `arming_state` ARMED (2 in every version that has the field).
const ARMED: f64 = 2.0;

/// The vehicle's state at the current row.
#[derive(Debug, Clone, Default)]
pub(crate) struct FlightState {
    /// Armed (from `vehicle_status.arming_state`).
    pub(crate) armed: bool,
    /// In the air, once `vehicle_land_detected` said.
    pub(crate) in_air: Option<bool>,
    /// The flight mode, once `vehicle_status` said.
    pub(crate) nav_state: Option<u8>,
    /// Whether any `vehicle_status` row was seen.
    pub(crate) status_seen: bool,
    /// When the vehicle last disarmed or landed, µs.
    pub(crate) last_stop_us: Option<u64>,
    /// The firmware's version, for the names of the modes.
    pub(crate) version: Version,
}

impl FlightState {
    /// Armed and, where the log says, in the air: what "in flight" means for the analyses
    /// restricted to it.
    pub(crate) fn flying(&self) -> bool {
        self.armed && self.in_air.unwrap_or(true)
    }

    /// Learns the firmware's version from the log's definitions, before the rows.
    pub(super) fn start(&mut self, meta: &crate::read::Metadata) {
        self.version = meta
            .version_info()
            .filter(|v| v.major > 0)
            .map(|v| (v.major, v.minor));
    }

    pub(super) fn row(&mut self, f: &Fields, data: &[u8], t: u64, modes: &mut Modes) {
        match f {
            Fields::Status {
                nav_state,
                arming_state,
                vehicle_type,
                in_transition_mode,
                is_vtol,
                is_rotary_wing,
            } => {
                let get = |l: &Option<Leaf>| l.and_then(|l| l.f64(data));
                self.status_seen = true;
                #[allow(clippy::cast_possible_truncation, clippy::cast_sign_loss)]
                if let Some(n) = get(nav_state) {
                    // A value no `uint8_t` holds (NaN, 2.5, -1 of a crafted log's float or
                    // wider field) as 255, a mode PX4 does not have ("Unknown"), not
                    // rounded or saturated into a real one (NaN would be 0, "Manual").
                    let whole = n.fract() == 0.0 && (0.0..=255.0).contains(&n);
                    self.nav_state = Some(if whole { n as u8 } else { u8::MAX });
                }
                if let Some(a) = get(arming_state) {
                    let armed = a == ARMED;
                    if self.armed && !armed {
                        self.last_stop_us = Some(t);
                    }
                    self.armed = armed;
                }
                // The VTOL state: a transition, or flying as the type says (old logs:
                // `is_rotary_wing`); none while the type is another (0, unknown).
                let vtol = if get(is_vtol).is_some_and(|v| v != 0.0) {
                    let transition = get(in_transition_mode).is_some_and(|v| v != 0.0);
                    let rotary = match get(vehicle_type) {
                        // ROTARY_WING 1, FIXED_WING 2.
                        Some(v) if v == 1.0 || v == 2.0 => Some(v == 1.0),
                        Some(_) => None,
                        None => get(is_rotary_wing).map(|v| v != 0.0),
                    };
                    match (transition, rotary) {
                        (true, _) => Some("Transition"),
                        (false, Some(true)) => Some("MC"),
                        (false, Some(false)) => Some("FW"),
                        (false, None) => None,
                    }
                } else {
                    None
                };
                modes.status(t, self.nav_state, self.armed, vtol);
            }
            Fields::Land { landed } => {
                if let Some(l) = landed.f64(data) {
                    let in_air = l == 0.0;
                    if self.in_air == Some(true) && !in_air {
                        self.last_stop_us = Some(t);
                    }
                    self.in_air = Some(in_air);
                    modes.land(t, in_air);
                }
            }
        }
    }
}
