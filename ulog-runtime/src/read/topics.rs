//! What pyulog users look for first in a whole-file [`Log`]: the topics with their row
//! counts and time ranges, and the parameter changes grouped by name; and, before a
//! conversion of several files, which of them define the topics asked for by name
//! ([`check_topics`]).

use std::path::{Path, PathBuf};

use super::{Log, ParameterChange, Subscription};

/// Topics asked for by name, checked against the definitions section of each of a set of
/// files ([`check_topics`]).
#[derive(Debug, Clone, Default, PartialEq, Eq)]
pub struct TopicCheck {
    /// Each topic asked for that one file or more does not define, in the order asked.
    pub missing: Vec<MissingTopic>,
    /// The files whose definitions could not be read (left to the conversion to report).
    pub unreadable: Vec<PathBuf>,
}

/// A topic asked for that some files do not define ([`TopicCheck`]).
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct MissingTopic {
    /// The name asked for.
    pub topic: String,
    /// The files that do not define it (of those whose definitions could be read), in order.
    pub lacking: Vec<PathBuf>,
    /// No file that could be read defines it: a misspelling, most likely.
    pub in_none: bool,
    /// When `in_none`, the closest names the files define (each once, each file's
    /// closest first, files in order); else empty.
    pub suggestions: Vec<String>,
}

impl TopicCheck {
    /// The first topic asked for that no file defines, as the text of the error a
    /// conversion of `files` files stops on: "no topic `x` in this log" (one file), "… in
    /// any of the logs" or "… in any of the logs that can be read", then "; did you mean
    /// …?" when a name is close; `None` if every topic is defined somewhere. The caller
    /// names the file of a single one, and says where to look when no name is close
    /// ([`MissingTopic::suggestions`] empty).
    pub fn refusal(&self, files: usize) -> Option<(&MissingTopic, String)> {
        let missing = self.missing.iter().find(|m| m.in_none)?;
        let topic = &missing.topic;
        let place = match files {
            1 => "this log",
            _ if !self.unreadable.is_empty() => "any of the logs that can be read",
            _ => "any of the logs",
        };
        let hint = crate::schema::did_you_mean(&missing.suggestions);
        Some((missing, format!("no topic `{topic}` in {place}{hint}")))
    }
}

/// Which of `files` define each of `topics` (a `-m` list, pyulog's
/// `message_name_filter_list`), from each file's definitions section only, before a
/// conversion reads them whole: a topic no file defines is most likely misspelled (with the
/// closest names), one only some files lack is normal in a fleet. Files that cannot be
/// opened or whose definitions cannot be read are listed apart.
///
/// ```
/// # use ulog_runtime::{ULog, Writer, WriterOptions};
/// # #[derive(ULog)] struct Battery { timestamp: u64, voltage_v: f32 }
/// # let mut w = Writer::new(Vec::new(), WriterOptions::default())?;
/// # w.topic::<Battery>(0)?;
/// # let path = std::env::temp_dir().join(format!("check_topics_{}.ulg", std::process::id()));
/// # std::fs::write(&path, w.into_inner())?;
/// let check = ulog_runtime::read::check_topics(&[&path], &["batery".to_owned()]);
/// # std::fs::remove_file(&path)?;
/// assert!(check.missing[0].in_none);
/// assert_eq!(check.missing[0].suggestions, ["battery"]);
/// let (_, text) = check.refusal(1).unwrap();
/// assert_eq!(text, "no topic `batery` in this log; did you mean `battery`?");
/// # Ok::<(), Box<dyn std::error::Error>>(())
/// ```
pub fn check_topics(files: &[impl AsRef<Path>], topics: &[String]) -> TopicCheck {
    let mut check = TopicCheck::default();
    if topics.is_empty() {
        return check;
    }
    let mut definitions = Vec::new();
    for path in files {
        let path = path.as_ref();
        let read = super::open_file(path)
            .map_err(crate::ReadError::from)
            .and_then(|f| super::StreamReader::read_definitions(std::io::BufReader::new(f)));
        match read {
            Ok(meta) => definitions.push((path, meta)),
            Err(_) => check.unreadable.push(path.to_path_buf()),
        }
    }
    for topic in topics {
        let lacking: Vec<PathBuf> = definitions
            .iter()
            .filter(|(_, meta)| meta.schema().get(topic).is_none())
            .map(|(path, _)| path.to_path_buf())
            .collect();
        if lacking.is_empty() {
            continue;
        }
        let in_none = lacking.len() == definitions.len();
        let mut suggestions: Vec<String> = Vec::new();
        if in_none {
            for (_, meta) in &definitions {
                for name in meta.schema().suggest(topic) {
                    if !suggestions.contains(&name) {
                        suggestions.push(name);
                    }
                }
            }
        }
        check.missing.push(MissingTopic {
            topic: topic.clone(),
            lacking,
            in_none,
            suggestions,
        });
    }
    check
}

/// One topic instance of a log ([`Log::topics`]): every subscription of that name and
/// `multi_id` together.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct TopicSummary {
    /// The topic (format) name.
    pub name: String,
    /// The instance.
    pub multi_id: u8,
    /// The `msg_id`s of its subscriptions, in file order (one unless resubscribed).
    pub msg_ids: Vec<u16>,
    /// Rows read.
    pub rows: usize,
    /// Timestamp of the first row, µs.
    pub first_timestamp: Option<u64>,
    /// Timestamp of the last row, µs.
    pub last_timestamp: Option<u64>,
}

impl Log<'_> {
    /// Every topic instance with at least one row, sorted by name and `multi_id` (as pyulog's
    /// `data_list`, which has only those).
    ///
    /// ```no_run
    /// # let log = ulog_runtime::Log::open("flight.ulg")?;
    /// for t in log.topics() {
    ///     println!("{} #{}: {} rows", t.name, t.multi_id, t.rows);
    /// }
    /// # Ok::<(), ulog_runtime::ReadError>(())
    /// ```
    pub fn topics(&self) -> Vec<TopicSummary> {
        let mut out: Vec<TopicSummary> = Vec::new();
        for sub in self.subscriptions() {
            let rows = self.rows(sub);
            if rows.len() == 0 {
                continue;
            }
            let first = self.rows(sub).next().map(|r| r.timestamp);
            let last = self.rows(sub).next_back().map(|r| r.timestamp);
            match out
                .iter_mut()
                .find(|t| t.name == sub.name && t.multi_id == sub.multi_id)
            {
                Some(t) => {
                    t.msg_ids.push(sub.msg_id);
                    t.rows += rows.len();
                    t.first_timestamp = t.first_timestamp.min(first).or(first);
                    t.last_timestamp = t.last_timestamp.max(last);
                }
                None => out.push(TopicSummary {
                    name: sub.name.clone(),
                    multi_id: sub.multi_id,
                    msg_ids: vec![sub.msg_id],
                    rows: rows.len(),
                    first_timestamp: first,
                    last_timestamp: last,
                }),
            }
        }
        out.sort_by(|a, b| (&a.name, a.multi_id).cmp(&(&b.name, b.multi_id)));
        out
    }

    /// The parameters that changed during the log, each with its changes in file order,
    /// sorted by name.
    pub fn changed_parameters(&self) -> Vec<(&str, Vec<&ParameterChange>)> {
        let mut out: Vec<(&str, Vec<&ParameterChange>)> = Vec::new();
        for c in self.parameter_changes() {
            match out.iter_mut().find(|(n, _)| *n == c.name) {
                Some((_, changes)) => changes.push(c),
                None => out.push((&c.name, vec![c])),
            }
        }
        out.sort_by(|a, b| a.0.cmp(b.0));
        out
    }
}

/// What reading left out of a log ([`Log::skipped`]), for tools that export it to say so.
#[derive(Debug, Clone, Default, PartialEq, Eq)]
pub struct Skipped {
    /// Subscriptions whose rows cannot be decoded: topic, `msg_id`, why.
    pub unreadable_topics: Vec<(String, u16, String)>,
    /// Rows whose size does not fit their format, per topic instance: topic, `multi_id`,
    /// rows.
    pub misfit_rows: Vec<(String, u8, usize)>,
    /// Rows for a `msg_id` no subscription declares.
    pub orphan_rows: usize,
    /// Messages of unknown types, and other messages that could not be used.
    pub unusable_messages: usize,
    /// Bytes skipped as damaged (truncated tails included).
    pub damaged_bytes: u64,
    /// Appended-data offsets of the flag bits that were ignored, impossible (backwards, or
    /// past the end of a file cut short): the data appended there, if any, is not read.
    pub ignored_appended_offsets: Vec<u64>,
}

impl Skipped {
    /// What was left out, a line each, as the exports say it (`ulog csv`, `ulog parquet`,
    /// `ulog json` on stderr, Python's `to_parquet` as warnings): unreadable topics and rows
    /// that do not fit, of `topics` only (all if empty); rows of no subscription (when
    /// `topics` is empty); damaged bytes; appended data not read. The log's text in them
    /// (topic names, why a topic cannot be read) has its control characters escaped.
    pub fn lines(&self, topics: &[String]) -> Vec<String> {
        let wanted = |t: &str| topics.is_empty() || topics.iter().any(|w| w == t);
        let plural = |n: usize| if n == 1 { "" } else { "s" };
        let mut out = Vec::new();
        for (topic, msg_id, why) in self.unreadable_topics.iter().filter(|t| wanted(&t.0)) {
            let line = format!("skipped topic `{topic}` (msg_id {msg_id}): {why}");
            out.push(crate::error::printable(&line).into_owned());
        }
        for (topic, multi_id, rows) in self.misfit_rows.iter().filter(|t| wanted(&t.0)) {
            let line = format!(
                "skipped {rows} row{} of `{topic}` #{multi_id} whose size does not fit the format",
                plural(*rows)
            );
            out.push(crate::error::printable(&line).into_owned());
        }
        if self.orphan_rows > 0 && topics.is_empty() {
            out.push(format!(
                "skipped {} row{} of msg_ids no subscription declares",
                self.orphan_rows,
                plural(self.orphan_rows)
            ));
        }
        out.extend(self.damage_lines());
        out
    }

    /// The damage alone, a line each: damaged bytes skipped, appended data not read (what
    /// the verbs that mirror a pyulog tool say on stderr where pyulog prints its
    /// `File corruption detected` among its output).
    pub fn damage_lines(&self) -> Vec<String> {
        let mut out = Vec::new();
        if self.damaged_bytes > 0 {
            out.push(format!(
                "{} damaged byte{} skipped (`ulog info -v` lists where)",
                self.damaged_bytes,
                if self.damaged_bytes == 1 { "" } else { "s" }
            ));
        }
        for offset in &self.ignored_appended_offsets {
            out.push(format!(
                "appended data at byte {offset} not read: the offset is impossible (backwards, \
                 or past the end of a file cut short)"
            ));
        }
        out
    }

    /// Whether nothing was left out.
    pub fn is_empty(&self) -> bool {
        *self == Skipped::default()
    }

    /// What the diagnostics of a reading pass say was left out.
    pub fn of(diagnostics: &[crate::Diagnostic]) -> Skipped {
        let mut out = Skipped::default();
        for d in diagnostics {
            out.add(d);
        }
        out
    }

    /// Counts what one diagnostic says was left out (for a pass that does not keep its
    /// diagnostics).
    pub fn add(&mut self, d: &crate::Diagnostic) {
        use crate::DiagnosticKind as K;
        if let Some(r) = d.damaged_range() {
            self.damaged_bytes += r.end - r.start;
        }
        match &d.kind {
            K::BadSubscription {
                topic,
                msg_id,
                error,
            } => self
                .unreadable_topics
                .push((topic.clone(), *msg_id, error.to_string())),
            K::PayloadSize {
                topic, multi_id, ..
            } => match self
                .misfit_rows
                .iter_mut()
                .find(|(t, m, _)| t == topic && m == multi_id)
            {
                Some(entry) => entry.2 += 1,
                None => self.misfit_rows.push((topic.clone(), *multi_id, 1)),
            },
            K::UnknownMsgId { .. } => self.orphan_rows += 1,
            K::BadAppendedOffset(offset) => self.ignored_appended_offsets.push(*offset),
            K::UnknownMessageType { .. } | K::Malformed(_) | K::InvalidFormat { .. } => {
                self.unusable_messages += 1;
            }
            _ => {}
        }
    }
}

impl Log<'_> {
    /// File offsets of the messages with text that is not UTF-8 (formats, keys, info values,
    /// parameter names, logged strings), whose invalid bytes the reader left out. pyulog's tools
    /// fail on such a log unless given `-i`; `ulog`'s verbs do the same.
    pub fn not_utf8(&self) -> Vec<u64> {
        use crate::DiagnosticKind as K;
        let mut at: Vec<u64> = self
            .diagnostics()
            .iter()
            .filter(|d| {
                matches!(
                    d.kind,
                    K::OddFormat { not_utf8: true, .. } | K::KeptValue { not_utf8: true, .. }
                )
            })
            .map(|d| d.offset)
            .chain(
                self.logged_messages()
                    .iter()
                    .filter(|m| !m.valid_utf8)
                    .map(|m| m.offset),
            )
            .chain(
                self.parameter_changes()
                    .iter()
                    .filter(|c| !c.valid_utf8)
                    .map(|c| c.offset),
            )
            .collect();
        at.sort_unstable();
        at.dedup();
        at
    }

    /// What was left out while reading, from [`Log::diagnostics`], grouped as an export
    /// reports it.
    pub fn skipped(&self) -> Skipped {
        Skipped::of(self.diagnostics())
    }
}

impl<'a> Log<'a> {
    /// The topic instances with rows, each as its subscriptions (one unless resubscribed)
    /// in file order, instances in the order they were first subscribed; only `topics` if
    /// not empty. Subscriptions whose format cannot be read are left out.
    pub fn instances(&self, topics: &[String]) -> Vec<Vec<&Subscription>> {
        let mut groups: Vec<Vec<&Subscription>> = Vec::new();
        for sub in self.subscriptions() {
            if sub.format().is_none() || (!topics.is_empty() && !topics.contains(&sub.name)) {
                continue;
            }
            match groups
                .iter_mut()
                .find(|g| g[0].name == sub.name && g[0].multi_id == sub.multi_id)
            {
                Some(g) => g.push(sub),
                None => groups.push(vec![sub]),
            }
        }
        groups.retain(|g| g.iter().any(|s| self.rows(s).len() > 0));
        groups
    }

    /// The rows of one topic instance's subscriptions (as [`Log::instances`] gives them),
    /// in file order: a resubscribed instance's rows interleave as the file has them.
    pub fn instance_rows<'s>(&'s self, subs: &[&'s Subscription]) -> InstanceRows<'s> {
        match subs {
            [one] => InstanceRows::One(self.rows(one)),
            _ => {
                let mut offsets: Vec<u64> = subs
                    .iter()
                    .flat_map(|s| self.rows(s).map(|r| r.offset))
                    .collect();
                offsets.sort_unstable();
                InstanceRows::Merged(self, offsets.into_iter())
            }
        }
    }
}

/// The rows of one topic instance, in file order ([`Log::instance_rows`]).
#[derive(Debug)]
pub enum InstanceRows<'a> {
    /// One subscription's.
    One(super::Rows<'a>),
    /// Several subscriptions' merged by file offset.
    Merged(&'a Log<'a>, std::vec::IntoIter<u64>),
}

impl<'a> InstanceRows<'a> {
    /// The rows left, in at most `parts` runs of consecutive rows, in order (for as many
    /// threads to take one each).
    pub(crate) fn split(self, parts: usize) -> Vec<InstanceRows<'a>> {
        match self {
            InstanceRows::One(rows) => rows
                .split(parts)
                .into_iter()
                .map(InstanceRows::One)
                .collect(),
            InstanceRows::Merged(log, offsets) => {
                let offsets = offsets.as_slice();
                let per = offsets.len().div_ceil(parts.max(1)).max(1);
                offsets
                    .chunks(per)
                    .map(|run| {
                        // The variant owns its offsets.
                        let run: Vec<u64> = run.to_vec();
                        InstanceRows::Merged(log, run.into_iter())
                    })
                    .collect()
            }
        }
    }
}

impl<'a> Iterator for InstanceRows<'a> {
    type Item = super::Row<'a>;

    #[inline]
    fn next(&mut self) -> Option<super::Row<'a>> {
        match self {
            InstanceRows::One(rows) => rows.next(),
            InstanceRows::Merged(log, offsets) => {
                let at = offsets.next()?;
                if let Some(&ahead) = offsets.as_slice().get(super::log::PREFETCH_ROWS) {
                    super::log::prefetch(log.bytes(), ahead, 128);
                }
                Some(log.row_at(at))
            }
        }
    }

    fn size_hint(&self) -> (usize, Option<usize>) {
        match self {
            InstanceRows::One(rows) => rows.size_hint(),
            InstanceRows::Merged(_, offsets) => offsets.size_hint(),
        }
    }
}

#[cfg(test)]
mod tests {
    use super::Skipped;

    #[test]
    fn damage_lines_count_bytes_in_the_singular_and_the_plural() {
        let line = |damaged_bytes| {
            Skipped {
                damaged_bytes,
                ..Skipped::default()
            }
            .damage_lines()
        };
        assert_eq!(
            line(1),
            ["1 damaged byte skipped (`ulog info -v` lists where)"]
        );
        assert_eq!(
            line(2),
            ["2 damaged bytes skipped (`ulog info -v` lists where)"]
        );
        assert!(line(0).is_empty());
    }

    #[test]
    fn what_a_damaged_log_makes_the_reader_say_has_no_control_characters() {
        // A type name zeroed in a definition: the reason and the diagnostic print it
        // escaped, the data keeps it as read.
        let why = "t.x: type `f\0\0` is not a basic type".to_owned();
        let skipped = Skipped {
            unreadable_topics: vec![("t\n".to_owned(), 3, why.clone())],
            ..Skipped::default()
        };
        assert_eq!(
            skipped.lines(&[]),
            ["skipped topic `t\\n` (msg_id 3): t.x: type `f\\u{0}\\u{0}` is not a basic type"]
        );
        assert_eq!(skipped.unreadable_topics[0].2, why);
        let d = crate::Diagnostic {
            offset: 59,
            kind: crate::DiagnosticKind::MissingTimestamp {
                topic: "a\u{1b}b".to_owned(),
            },
        };
        assert_eq!(
            d.to_string(),
            "at byte 59: topic `a\\u{1b}b` has no unsigned integer `timestamp` field; its rows \
             get timestamp 0"
        );
    }
}
