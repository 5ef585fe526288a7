//! What anonymizing touches, in one place: the fields (by topic, name and type), the topics
//! dropped, the info, multi info and parameters. The [`Anonymize`](super::Anonymize) docs
//! list the same.

/// Topics of raw bytes that embed positions, times or identities in their own protocols
/// (receiver traffic, RTCM corrections, ULog and MAVLink streams, mission storage), of
/// location fingerprints (sky plots, cell ids) and of device identities: not written.
pub(super) const DROPPED_TOPICS: [&str; 18] = [
    "gps_dump",
    "gps_inject_data",
    "ulog_stream",
    "ulog_stream_ack",
    "mavlink_tunnel",
    "esc_serial_passthru",
    "dataman_request",
    "dataman_response",
    "voxl2_io_data",
    "qshell_req",
    "satellite_info",
    "cellular_status",
    "open_drone_id_operator_id",
    "open_drone_id_self_id",
    "open_drone_id_arm_status",
    "device_information",
    "battery_info",
    "gimbal_device_information",
];

/// Last name parts of absolute altitude fields in any topic (meters, `int32_t` in mm).
pub(super) const ALTITUDES: [&str; 12] = [
    "alt",
    "alt_ellipsoid",
    "terrain_alt",
    "pressure_alt",
    "ref_alt",
    "altitude_msl_m",
    "altitude_ellipsoid_m",
    "baro_alt_meter",
    "baro1_alt_meter",
    "alt_est",
    "operator_altitude_geo",
    "altitudeSp",
];

/// Absolute altitudes under a name that is relative elsewhere: (topic, field).
pub(super) const TOPIC_ALTITUDES: [(&str, &str); 8] = [
    ("tecs_status", "altitude_sp"),
    ("tecs_status", "altitude_reference"),
    ("tecs_status", "altitude_filtered"),
    ("transponder_report", "altitude"),
    ("sensor_baro", "altitude"),
    ("fixed_wing_longitudinal_setpoint", "altitude"),
    ("orbit_status", "z"),
    ("figure_eight_status", "z"),
];

/// Topics whose `observation` is minus an absolute altitude.
pub(super) const NEGATED_ALTITUDE_TOPICS: [&str; 3] = [
    "estimator_aid_src_baro_hgt",
    "estimator_aid_src_gnss_hgt",
    "estimator_aid_src_fake_hgt",
];

/// Topics whose `observation[0]`/`observation[1]` (`double`) are a latitude and longitude.
pub(super) const OBSERVED_POSITIONS: [&str; 3] = [
    "estimator_aid_src_gnss_pos",
    "estimator_aid_src_fake_pos",
    "estimator_aid_src_aux_global_position",
];

/// Topics whose `x`/`y` are a latitude and longitude when their `frame` is this value
/// (as PX4 writes them): `double` degrees for frame 0, `int32_t` 1e-7° for frame 5.
pub(super) const FRAMED_POSITIONS: [(&str, u8); 2] =
    [("orbit_status", 0), ("figure_eight_status", 5)];

/// Command topics whose `param5`/`param6` are a latitude and longitude and `param7` an
/// altitude for the MAVLink commands that carry a position.
pub(super) const COMMAND_TOPICS: [&str; 3] = [
    "vehicle_command",
    "gimbal_v1_command",
    "vehicle_command_mode_executor",
];

/// MAVLink commands with a global position in `param5`..`param7`.
pub(super) const POSITION_COMMANDS: [u32; 19] = [
    16, 17, 18, 19, 21, 22, 34, 35, 80, 81, 84, 85, 179, 189, 192, 195, 201, 4501, 100_000,
];

/// Fields that identify a vehicle, a part or another aircraft: made zeros.
pub(super) const IDENTIFIER_FIELDS: [(&str, &str); 8] = [
    ("battery_status", "serial_number"),
    ("battery_status", "manufacture_date"),
    ("transponder_report", "icao_address"),
    ("transponder_report", "callsign"),
    ("transponder_report", "uas_id"),
    ("sensor_uwb", "mac"),
    ("sensor_uwb", "mac_dest"),
    ("sensor_uwb", "sessionid"),
];

/// Topics whose `text` (`char[N]`) is a logged sentence.
pub(super) const TEXT_TOPICS: [&str; 2] = ["log_message", "mavlink_log"];

/// UTC times in any topic (µs since 1970; 0: unknown).
pub(super) const UTC_TIMES: [&str; 4] = [
    "time_utc_usec",
    "timestamp_utc",
    "rtc_timestamp",
    "remote_timestamp",
];

/// PX4 events with arguments to change, by id (`component << 24 | sub id`).
pub(super) mod events {
    /// `logger_open_file_time`: `uint16_t` year, `uint8_t` month, day, hour, minute, second.
    pub(in super::super) const OPEN_FILE_TIME: u32 = 17_980_399;
    /// `vrtl_return_at` and `rtl_mission_land_climb`: an `int32_t` altitude AMSL first.
    pub(in super::super) const ALTITUDE_FIRST: [u32; 2] = [22_161_044, 27_006_470];
    /// `navigator_traffic*`: a `uint32_t` ICAO address of another aircraft first.
    pub(in super::super) const ICAO_FIRST: [u32; 4] =
        [18_578_544, 23_921_860, 27_014_176, 27_441_269];
}

/// Info keys that identify the vehicle or name the original file: not written.
pub(super) const DROPPED_INFO: [&str; 2] = ["sys_uuid", "replay"];

/// Multi info keys kept: the events metadata, performance counters, excluded topics. Every
/// other (boot console output with its GUID and paths, hard fault dumps of memory, what a
/// newer writer adds) is not written.
pub(super) fn keeps_multi_info(key: &str) -> bool {
    key == "metadata_events"
        || key == "excluded_optional_topics"
        || key.starts_with("perf_counter_")
        || key.starts_with("perf_top_")
}

/// Parameters that hold a position, an altitude, the time zone, a location's magnetic
/// declination or a count that tells vehicles apart: written as 0.
pub(super) const ZEROED_PARAMETERS: [&str; 13] = [
    "LPE_LAT",
    "LPE_LON",
    "NAV_AH_LAT",
    "NAV_AH_LON",
    "NAV_AH_ALT",
    "NAV_DLL_CH_LAT",
    "NAV_DLL_CH_LON",
    "NAV_DLL_CH_ALT",
    "EKF2_MAG_DECL",
    "SDLOG_UTC_OFFSET",
    "COM_FLIGHT_UUID",
    "LND_FLIGHT_T_HI",
    "LND_FLIGHT_T_LO",
];

/// Whether a latitude field's last name part is one, and the longitude's name that goes
/// with it: `lat` / `lon` as a word of the name (`lat`, `ref_lat`, `lat_est`), `latitude`
/// / `longitude` (`latitude_deg`, `operator_latitude`). Names of counters, flags and
/// deltas (`lat_lon_reset_counter`, `delta_lat_lon`) are not.
pub(super) fn longitude_of(base: &str) -> Option<String> {
    if [
        "reset", "valid", "delta", "accel", "counter", "variance", "std",
    ]
    .iter()
    .any(|w| base.contains(w))
    {
        return None;
    }
    let words: Vec<&str> = base.split('_').collect();
    let k = words.iter().position(|w| *w == "lat" || *w == "latitude")?;
    let mut lon: Vec<&str> = words.clone();
    lon[k] = if words[k] == "lat" {
        "lon"
    } else {
        "longitude"
    };
    Some(lon.join("_"))
}

/// Whether a `uint64_t` field's last name part names a time (shifted when the log's clock
/// is absolute): `timestamp`, `timestamp_*`, `*_timestamp`, `time_*`, `*_time`; not
/// relative ones (`*_relative`, `*_rel`).
pub(super) fn is_time_name(base: &str) -> bool {
    let relative = base.ends_with("_relative") || base.ends_with("_rel");
    let time = base.starts_with("timestamp")
        || base.ends_with("_timestamp")
        || base.starts_with("time_")
        || base.ends_with("_time");
    time && !relative
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn latitude_fields_find_their_longitude() {
        for (lat, lon) in [
            ("lat", "lon"),
            ("ref_lat", "ref_lon"),
            ("lat_est", "lon_est"),
            ("latitude_deg", "longitude_deg"),
            ("latitude", "longitude"),
            ("operator_latitude", "operator_longitude"),
        ] {
            assert_eq!(longitude_of(lat).as_deref(), Some(lon), "{lat}");
        }
        for not in [
            "lat_lon_reset_counter",
            "delta_lat_lon",
            "lat_accel",
            "flat",
            "lat_lon_valid",
        ] {
            assert_eq!(longitude_of(not), None, "{not}");
        }
        assert!(is_time_name("timestamp") && is_time_name("timestamp_sample"));
        assert!(is_time_name("armed_time") && is_time_name("time_last_fuse"));
        assert!(!is_time_name("timestamp_time_relative") && !is_time_name("control_mode_flags"));
    }
}
