//! Names close to one that does not exist, for errors that suggest what was meant.

/// The names closest to `name` by edit distance (and those containing it), at most 3,
/// closest first: the suggestions of an error about a name that does not exist.
///
/// ```
/// use ulog_runtime::schema::{closest_names, did_you_mean};
/// let names = ["vehicle_status", "battery_status", "sensor_combined"];
/// let close = closest_names("vehicle_statuss", names.into_iter());
/// assert_eq!(close, ["vehicle_status"]);
/// assert_eq!(did_you_mean(&close), "; did you mean `vehicle_status`?");
/// assert_eq!(did_you_mean(&[]), "");
/// ```
pub fn closest_names<'a>(name: &str, candidates: impl Iterator<Item = &'a str>) -> Vec<String> {
    let limit = (name.chars().count() / 3).max(2);
    let mut scored: Vec<(usize, &str)> = candidates
        .filter_map(|c| {
            let d = edit_distance(name, c);
            let contains = c.contains(name) || name.contains(c);
            (d <= limit || contains && !c.is_empty()).then_some((d, c))
        })
        .collect();
    scored.sort();
    scored.dedup();
    scored
        .into_iter()
        .take(3)
        .map(|(_, c)| c.to_owned())
        .collect()
}

/// `; did you mean `a`, `b` or `c`?` for suggestions ([`closest_names`]), or nothing.
pub fn did_you_mean(suggestions: &[String]) -> String {
    match suggestions {
        [] => String::new(),
        [one] => format!("; did you mean `{one}`?"),
        many => {
            let quoted: Vec<String> = many.iter().map(|s| format!("`{s}`")).collect();
            let (last, rest) = quoted.split_last().expect("many");
            format!("; did you mean {} or {last}?", rest.join(", "))
        }
    }
}

/// Levenshtein distance over characters.
fn edit_distance(a: &str, b: &str) -> usize {
    let b: Vec<char> = b.chars().collect();
    let mut row: Vec<usize> = (0..=b.len()).collect();
    for (i, ca) in a.chars().enumerate() {
        let mut diag = row[0];
        row[0] = i + 1;
        for (j, &cb) in b.iter().enumerate() {
            let next = (diag + usize::from(ca != cb))
                .min(row[j] + 1)
                .min(row[j + 1] + 1);
            diag = row[j + 1];
            row[j + 1] = next;
        }
    }
    row[b.len()]
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn close_names_first() {
        let names = [
            "vehicle_status",
            "vehicle_attitude",
            "sensor_combined",
            "vehicle_status_flags",
        ];
        assert_eq!(
            closest_names("vehicle_statu", names.into_iter()),
            ["vehicle_status", "vehicle_status_flags"]
        );
        assert_eq!(edit_distance("kitten", "sitting"), 3);
        assert!(closest_names("zzzzzz", names.into_iter()).is_empty());
    }
}
