//! Free text anonymized (logged strings, `log_message` texts): what in a sentence tells
//! where or when a log was made, or which vehicle made it.

/// What [`redact`] changes, besides the fixed patterns.
pub(super) struct TextRules<'a> {
    /// Dates and times of day (not with `keep_time`).
    pub(super) times: bool,
    /// Meters added to absolute altitudes in the sentences PX4 writes them in.
    pub(super) altitude_offset_m: f64,
    /// Identifiers of the log to remove wherever they appear (its `sys_uuid`).
    pub(super) identifiers: &'a [String],
}

/// The text with, each made harmless:
/// - paths of log files (`/fs/microsd/log/2024-03-18/14_49_10.ulg`, `sess100/log100.ulg`)
///   replaced by `log.ulg`;
/// - dates (`2024-05-01`, `2024/05/01`, `2024_05_01`, `2024-3-4`) and times of day
///   (`12:30:45`, `12_30_45`) made zeros;
/// - `PX4GUID:` values, the log's own identifiers, IPv4 and MAC addresses made zeros, and
///   the value after `serial:`/`s/n:` removed;
/// - the altitude of `RTL: start return at 491 m` and `RTL Mission Land: climb to 491 m`
///   moved by the altitude offset.
///
/// `None` if nothing was changed.
pub(super) fn redact(text: &[u8], rules: &TextRules<'_>) -> Option<Vec<u8>> {
    let mut s = String::from_utf8_lossy(text).into_owned();
    let original = s.clone();
    s = replace_log_paths(&s);
    for id in rules.identifiers.iter().filter(|i| i.len() >= 8) {
        s = s.replace(id.as_str(), &"0".repeat(id.len()));
    }
    s = zero_after(&s, "PX4GUID:", |c| c.is_ascii_hexdigit());
    for marker in ["serial:", "serial number:", "s/n:", "SN:", "S/N:"] {
        s = zero_after(&s, marker, |c| c.is_ascii_alphanumeric() || c == '-');
    }
    s = zero_addresses(&s);
    if rules.times {
        s = zero_dates_and_times(&s);
    }
    for phrase in ["RTL: start return at ", "RTL Mission Land: climb to "] {
        s = shift_meters_after(&s, phrase, rules.altitude_offset_m);
    }
    // Text that was not UTF-8 is kept byte for byte unless something had to change.
    (s != original).then(|| s.into_bytes())
}

/// Every path ending in `.ulg` (the token of path characters before it) replaced by
/// `log.ulg`.
fn replace_log_paths(s: &str) -> String {
    let mut out = String::with_capacity(s.len());
    let mut rest = s;
    while let Some(i) = rest.find(".ulg") {
        let before = &rest[..i];
        let start = before
            .rfind(|c: char| !(c.is_ascii_alphanumeric() || "/._-~".contains(c)))
            .map_or(0, |k| {
                k + before[k..].chars().next().map_or(1, char::len_utf8)
            });
        out.push_str(&before[..start]);
        out.push_str("log.ulg");
        rest = &rest[i + 4..];
    }
    out.push_str(rest);
    out
}

/// The run of characters `keep` takes after each `marker` (and the spaces after it) made
/// zeros, or removed when they are not hexadecimal.
fn zero_after(s: &str, marker: &str, keep: impl Fn(char) -> bool) -> String {
    let mut out = String::with_capacity(s.len());
    let mut rest = s;
    while let Some(i) = rest.find(marker) {
        let after = i + marker.len();
        out.push_str(&rest[..after]);
        let tail = &rest[after..];
        let spaces = tail.len() - tail.trim_start_matches(' ').len();
        out.push_str(&tail[..spaces]);
        let value_len = tail[spaces..]
            .find(|c: char| !keep(c))
            .unwrap_or(tail.len() - spaces);
        let value = &tail[spaces..spaces + value_len];
        if value.chars().all(|c| c.is_ascii_hexdigit()) {
            out.push_str(&"0".repeat(value.len()));
        }
        rest = &tail[spaces + value_len..];
    }
    out.push_str(rest);
    out
}

/// IPv4 addresses (`a.b.c.d`) made `0.0.0.0`, and the hex digits of MAC addresses
/// (`aa:bb:cc:dd:ee:ff`) zeros.
fn zero_addresses(s: &str) -> String {
    let b = s.as_bytes();
    let mut out = Vec::with_capacity(b.len());
    let mut i = 0;
    while i < b.len() {
        let boundary = i == 0 || !(b[i - 1].is_ascii_alphanumeric() || b[i - 1] == b'.');
        if boundary && let Some(end) = ipv4_end(b, i) {
            out.extend_from_slice(b"0.0.0.0");
            i = end;
            continue;
        }
        if boundary
            && i + 17 <= b.len()
            && (0..6)
                .all(|k| b[i + 3 * k].is_ascii_hexdigit() && b[i + 3 * k + 1].is_ascii_hexdigit())
            && (0..5)
                .all(|k| matches!(b[i + 3 * k + 2], b':' | b'-') && b[i + 3 * k + 2] == b[i + 2])
            && b.get(i + 17).is_none_or(|c| !c.is_ascii_hexdigit())
        {
            for k in 0..6 {
                out.extend_from_slice(b"00");
                if k < 5 {
                    out.push(b[i + 2]);
                }
            }
            i += 17;
            continue;
        }
        out.push(b[i]);
        i += 1;
    }
    String::from_utf8(out).expect("ASCII replaced by ASCII")
}

/// Where an IPv4 address starting at `i` ends.
fn ipv4_end(b: &[u8], i: usize) -> Option<usize> {
    let mut at = i;
    for part in 0..4 {
        let digits = b[at..].iter().take_while(|c| c.is_ascii_digit()).count();
        if !(1..=3).contains(&digits) {
            return None;
        }
        let value: u32 = std::str::from_utf8(&b[at..at + digits])
            .ok()?
            .parse()
            .ok()?;
        if value > 255 {
            return None;
        }
        at += digits;
        if part < 3 {
            if b.get(at) != Some(&b'.') {
                return None;
            }
            at += 1;
        }
    }
    let next = b.get(at);
    (next.is_none_or(|c| !c.is_ascii_digit() && *c != b'.')).then_some(at)
}

/// Dates `yyyy-m-d` (`-`, `/` or `_` between, one or two digits for month and day) and
/// times `hh:mm:ss` (`:`, `_`; `-` between digits only in a date) made zeros.
fn zero_dates_and_times(s: &str) -> String {
    let b = s.as_bytes();
    let mut out = b.to_vec();
    let digits_at = |at: usize| b[at..].iter().take_while(|c| c.is_ascii_digit()).count();
    let mut i = 0;
    while i < b.len() {
        let boundary = i == 0 || !b[i - 1].is_ascii_digit();
        if !boundary || !b[i].is_ascii_digit() {
            i += 1;
            continue;
        }
        let n = digits_at(i);
        // A date: four digits, a separator, one or two, the same separator, one or two.
        if n == 4
            && let Some(&sep) = b.get(i + 4)
            && matches!(sep, b'-' | b'/' | b'_')
        {
            let m = digits_at(i + 5);
            if (1..=2).contains(&m) && b.get(i + 5 + m) == Some(&sep) {
                let d = digits_at(i + 6 + m);
                if (1..=2).contains(&d) {
                    let end = i + 6 + m + d;
                    for c in &mut out[i..end] {
                        if c.is_ascii_digit() {
                            *c = b'0';
                        }
                    }
                    i = end;
                    continue;
                }
            }
        }
        // A time of day: two digits, `:` or `_`, two, the same, two.
        if n == 2
            && let Some(&sep) = b.get(i + 2)
            && matches!(sep, b':' | b'_')
            && digits_at(i + 3) == 2
            && b.get(i + 5) == Some(&sep)
            && digits_at(i + 6) == 2
        {
            for k in [0, 1, 3, 4, 6, 7] {
                out[i + k] = b'0';
            }
            i += 8;
            continue;
        }
        i += n;
    }
    String::from_utf8(out).expect("ASCII replaced by ASCII")
}

/// The integer number of meters after `phrase` moved by `offset`.
fn shift_meters_after(s: &str, phrase: &str, offset: f64) -> String {
    let mut out = String::with_capacity(s.len());
    let mut rest = s;
    while let Some(i) = rest.find(phrase) {
        let after = i + phrase.len();
        out.push_str(&rest[..after]);
        let tail = &rest[after..];
        let len = tail
            .char_indices()
            .find(|&(k, c)| !(c.is_ascii_digit() || (k == 0 && c == '-')))
            .map_or(tail.len(), |(k, _)| k);
        match tail[..len].parse::<i64>() {
            #[allow(clippy::cast_possible_truncation)]
            Ok(v) if tail[len..].starts_with(" m") => {
                out.push_str(&(v + offset.round() as i64).to_string());
            }
            _ => out.push_str(&tail[..len]),
        }
        rest = &tail[len..];
    }
    out.push_str(rest);
    out
}

#[cfg(test)]
mod tests {
    use super::*;

    fn r(text: &str) -> String {
        let ids = ["0006000000003037363035325111001b002e".to_owned()];
        let rules = TextRules {
            times: true,
            altitude_offset_m: 100.0,
            identifiers: &ids,
        };
        redact(text.as_bytes(), &rules)
            .map_or_else(|| text.to_owned(), |b| String::from_utf8(b).unwrap())
    }

    #[test]
    fn places_times_and_identifiers_go_and_the_rest_stays() {
        assert_eq!(
            r("[logger] /fs/microsd/log/2019-04-25/12_30_05.ulg\t"),
            "[logger] log.ulg\t"
        );
        assert_eq!(
            r("Opened full log file: sess100/log100.ulg"),
            "Opened full log file: log.ulg"
        );
        assert_eq!(
            r("logging: opening log file 2026-3-4/11_55_42.ulg"),
            "logging: opening log file log.ulg"
        );
        assert_eq!(r("at 10:11:12 on 2024/05/01"), "at 00:00:00 on 0000/00/00");
        assert_eq!(
            r("[mavlink] partner IP: 127.0.0.1 mac 0A:1b:2C:3d:4E:5f"),
            "[mavlink] partner IP: 0.0.0.0 mac 00:00:00:00:00:00"
        );
        assert_eq!(
            r("PX4GUID: 0006000000003037363035325111001b002e x"),
            "PX4GUID: 000000000000000000000000000000000000 x"
        );
        assert_eq!(
            r("uuid 0006000000003037363035325111001b002e"),
            "uuid 000000000000000000000000000000000000"
        );
        assert_eq!(r("battery serial: AB-123 ok"), "battery serial:  ok");
        assert_eq!(
            r("[navigator] RTL: start return at 491 m (3 m above destination)"),
            "[navigator] RTL: start return at 591 m (3 m above destination)"
        );
        for kept in [
            "Takeoff detected",
            "Climb to 5.0 meters above home",
            "battery 12.3 V, 1234-5",
            "version 1.15.2",
            "CDC/ACM serial driver",
        ] {
            assert_eq!(r(kept), kept);
        }
    }
}
