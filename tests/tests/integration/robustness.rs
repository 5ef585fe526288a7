//! Robustness: corpus files are damaged (truncated, bytes flipped, chunks spliced over other
//! bytes, garbage inserted, ranges deleted) and read by both readers. Properties:
//! - no panic, and bounded time;
//! - every row that ends before the first damaged byte comes back unchanged;
//! - no row is invented: every row returned starts where a row of the clean file starts (or
//!   lies on damaged bytes, e.g. a copy spliced in);
//! - the whole-file and the streaming reader agree;
//! - over many damaged copies, at least 99.9% of the rows the damage did not touch come back.

use std::ops::Range;
use std::path::PathBuf;
use std::sync::OnceLock;
use std::time::{Duration, Instant};

use proptest::prelude::*;
use ulog_runtime::{Event, Log, StreamReader};
use ulog_tests::{corpus_files, short_name};

/// A clean corpus file and its rows: (offset, message length, data).
struct Clean {
    name: String,
    bytes: Vec<u8>,
    rows: Vec<(usize, usize, Vec<u8>)>,
}

/// The clean files used: every corpus file that reads without damage, up to 2 MB (for speed).
fn cleans() -> &'static [Clean] {
    static CLEANS: OnceLock<Vec<Clean>> = OnceLock::new();
    CLEANS.get_or_init(|| {
        corpus_files()
            .into_iter()
            .filter_map(|path: PathBuf| {
                let bytes = std::fs::read(&path).ok()?;
                if bytes.len() > 2_000_000 {
                    return None;
                }
                let log = Log::from_slice(&bytes).ok()?;
                if !log.diagnostics().is_empty() || log.row_count() == 0 {
                    return None;
                }
                let rows = log
                    .data()
                    .map(|r| (r.offset as usize, r.data.len() + 5, r.data.to_vec()))
                    .collect();
                Some(Clean {
                    name: short_name(&path),
                    rows,
                    bytes: bytes.clone(),
                })
            })
            .collect()
    })
}

#[derive(Debug, Clone)]
enum Mutation {
    Truncate(usize),
    Flip(Vec<(usize, u8)>),
    /// Copy `len` bytes from `from` over `to`.
    Splice {
        from: usize,
        to: usize,
        len: usize,
    },
    Insert {
        at: usize,
        bytes: Vec<u8>,
    },
    Delete {
        at: usize,
        len: usize,
    },
}

/// A damaged copy and how to relate it to the clean file.
struct Damaged {
    bytes: Vec<u8>,
    mutation: Mutation,
}

impl Damaged {
    fn new(clean: &[u8], mutation: Mutation) -> Damaged {
        let mut b = clean.to_vec();
        match &mutation {
            Mutation::Truncate(t) => b.truncate(*t),
            Mutation::Flip(flips) => flips.iter().for_each(|&(at, x)| b[at] ^= x),
            Mutation::Splice { from, to, len } => b.copy_within(*from..*from + *len, *to),
            Mutation::Insert { at, bytes } => {
                b.splice(*at..*at, bytes.iter().copied());
            }
            Mutation::Delete { at, len } => {
                b.drain(*at..*at + *len);
            }
        }
        Damaged { bytes: b, mutation }
    }

    /// First damaged byte, in clean-file offsets.
    fn first_damage(&self) -> usize {
        match &self.mutation {
            Mutation::Truncate(t) => *t,
            Mutation::Flip(f) => f.iter().map(|x| x.0).min().unwrap_or(usize::MAX),
            Mutation::Splice { to, .. } => *to,
            Mutation::Insert { at, .. } | Mutation::Delete { at, .. } => *at,
        }
    }

    /// Whether the clean bytes `r` are damaged.
    fn touches(&self, r: Range<usize>) -> bool {
        let hits = |d: Range<usize>| d.start < r.end && r.start < d.end;
        match &self.mutation {
            Mutation::Truncate(t) => r.end > *t,
            Mutation::Flip(f) => f.iter().any(|&(at, _)| r.contains(&at)),
            Mutation::Splice { to, len, .. } => hits(*to..*to + *len),
            Mutation::Insert { at, .. } => r.start < *at && *at < r.end,
            Mutation::Delete { at, len } => hits(*at..*at + *len),
        }
    }

    /// Whether the bytes where the flag bits' `incompat` field sits (offsets 27..35) changed.
    fn changes_incompat_flags(&self) -> bool {
        const INCOMPAT: Range<usize> = 16 + 3 + 8..16 + 3 + 16;
        match &self.mutation {
            // Everything after an insertion or deletion point moves.
            Mutation::Insert { at, .. } | Mutation::Delete { at, .. } => *at < INCOMPAT.end,
            _ => self.touches(INCOMPAT),
        }
    }

    /// Where a clean offset is in the damaged copy (`None`: deleted or cut).
    fn forward(&self, o: usize) -> Option<usize> {
        match &self.mutation {
            Mutation::Truncate(t) => (o < *t).then_some(o),
            Mutation::Insert { at, bytes } => Some(if o >= *at { o + bytes.len() } else { o }),
            Mutation::Delete { at, len } => match o {
                o if o < *at => Some(o),
                o if o >= at + len => Some(o - len),
                _ => None,
            },
            _ => Some(o),
        }
    }

    /// Where a damaged-copy offset was in the clean file (`None`: inside inserted bytes).
    fn backward(&self, o: usize) -> Option<usize> {
        match &self.mutation {
            Mutation::Insert { at, bytes } => match o {
                o if o < *at => Some(o),
                o if o >= at + bytes.len() => Some(o - bytes.len()),
                _ => None,
            },
            Mutation::Delete { at, len } => Some(if o >= *at { o + len } else { o }),
            _ => Some(o),
        }
    }
}

/// What reading a damaged copy gave, judged against the clean file.
#[derive(Debug, Default)]
struct Outcome {
    untouched: usize,
    recovered: usize,
    invented: Vec<usize>,
    lost_before_damage: Vec<usize>,
}

fn read_rows(bytes: &[u8]) -> Result<Vec<(usize, Vec<u8>)>, ulog_runtime::ReadError> {
    let log = Log::from_slice(bytes)?;
    Ok(log
        .data()
        .map(|r| (r.offset as usize, r.data.to_vec()))
        .collect())
}

fn stream_rows(bytes: &[u8], chunk: usize) -> Option<Vec<(usize, Vec<u8>)>> {
    struct Chunked<'a>(&'a [u8], usize);
    impl std::io::Read for Chunked<'_> {
        fn read(&mut self, buf: &mut [u8]) -> std::io::Result<usize> {
            let n = buf.len().min(self.1).min(self.0.len());
            buf[..n].copy_from_slice(&self.0[..n]);
            self.0 = &self.0[n..];
            Ok(n)
        }
    }
    let mut reader = StreamReader::new(Chunked(bytes, chunk)).ok()?;
    let mut rows = Vec::new();
    while let Some(event) = reader.next_event().ok()? {
        if let Event::Row(r) = event {
            rows.push((r.offset as usize, r.data.to_vec()));
        }
    }
    Some(rows)
}

fn judge(clean: &Clean, damaged: &Damaged, rows: &[(usize, Vec<u8>)]) -> Outcome {
    let mut out = Outcome::default();
    let returned: std::collections::HashMap<usize, &Vec<u8>> =
        rows.iter().map(|(o, d)| (*o, d)).collect();
    let starts: std::collections::HashSet<usize> = clean.rows.iter().map(|r| r.0).collect();
    let first = damaged.first_damage();
    for (start, len, data) in &clean.rows {
        let back = returned
            .get(&damaged.forward(*start).unwrap_or(usize::MAX))
            .copied();
        if start + len <= first && back != Some(data) {
            out.lost_before_damage.push(*start);
        }
        if !damaged.touches(*start..start + len) {
            out.untouched += 1;
            out.recovered += usize::from(back == Some(data));
        }
    }
    for (o, d) in rows {
        let legit = match damaged.backward(*o) {
            None => true, // inside inserted bytes
            Some(orig) => starts.contains(&orig) || damaged.touches(orig..orig + d.len() + 5),
        };
        if !legit {
            out.invented.push(*o);
        }
    }
    out
}

fn mutation(len: usize, kind: u8, a: usize, b: usize, n: usize, seed: u8) -> Mutation {
    let at = 16 + a % (len - 16);
    match kind % 5 {
        0 => Mutation::Truncate(at),
        1 => Mutation::Flip(
            (0..1 + n % 8)
                .map(|i| {
                    (
                        16 + a.wrapping_add(i.wrapping_mul(b)) % (len - 16),
                        1 << ((seed as usize + i) % 8),
                    )
                })
                .collect(),
        ),
        2 => {
            let l = 1 + n % 2_000;
            let from = 16 + b % (len - 16 - l.min(len - 17));
            let to = 16 + a % (len - 16 - l.min(len - 17));
            let l = l.min(len - from).min(len - to);
            Mutation::Splice { from, to, len: l }
        }
        3 => Mutation::Insert {
            at,
            bytes: (0..1 + n % 300)
                .map(|i| (i as u8).wrapping_mul(seed).wrapping_add(b as u8))
                .collect(),
        },
        _ => Mutation::Delete {
            at,
            len: (1 + n % 500).min(len - at),
        },
    }
}

/// Checks one damaged copy; `None` if the file is rightly refused (damage set an unknown
/// incompatible flag bit).
fn check(clean: &Clean, damaged: &Damaged, chunk: usize) -> Result<Option<Outcome>, TestCaseError> {
    let started = Instant::now();
    let rows = match read_rows(&damaged.bytes) {
        Ok(rows) => rows,
        Err(ulog_runtime::ReadError::IncompatibleFlags { .. })
            if damaged.changes_incompat_flags() =>
        {
            return Ok(None);
        }
        Err(e) => {
            return Err(TestCaseError::fail(format!(
                "{}: the file header is intact, yet: {e}",
                clean.name
            )));
        }
    };
    let streamed = stream_rows(&damaged.bytes, chunk)
        .ok_or_else(|| TestCaseError::fail("stream must read"))?;
    prop_assert!(
        started.elapsed() < Duration::from_secs(20),
        "too slow: {:?}",
        started.elapsed()
    );
    prop_assert_eq!(
        &rows,
        &streamed,
        "whole-file and streaming readers disagree"
    );
    prop_assert_eq!(
        &rows,
        &fold_file_rows(&damaged.bytes, 2).1,
        "whole-file reader and fold_file disagree"
    );
    let outcome = judge(clean, damaged, &rows);
    prop_assert!(
        outcome.lost_before_damage.is_empty(),
        "{}: rows before the damage lost: {:?}",
        clean.name,
        outcome.lost_before_damage
    );
    prop_assert!(
        outcome.invented.is_empty(),
        "{}: invented rows at {:?}",
        clean.name,
        outcome.invented
    );
    Ok(Some(outcome))
}

proptest! {
    #![proptest_config(ProptestConfig { cases: 96, failure_persistence: None, ..ProptestConfig::default() })]

    #[test]
    fn damaged_files_never_panic_lose_the_prefix_or_invent_rows(
        file in any::<usize>(), kind in any::<u8>(), a in any::<usize>(), b in any::<usize>(),
        n in any::<usize>(), seed in any::<u8>(), chunk in 1usize..70_000,
    ) {
        let cleans = cleans();
        if cleans.is_empty() {
            return Ok(());
        }
        let clean = &cleans[file % cleans.len()];
        let damaged = Damaged::new(&clean.bytes, mutation(clean.bytes.len(), kind, a, b, n, seed));
        check(clean, &damaged, chunk)?;
    }
}

/// A small deterministic generator, so the recovery figure is the same on every run.
struct SplitMix(u64);

impl SplitMix {
    fn next(&mut self) -> u64 {
        self.0 = self.0.wrapping_add(0x9E37_79B9_7F4A_7C15);
        let mut z = self.0;
        z = (z ^ (z >> 30)).wrapping_mul(0xBF58_476D_1CE4_E5B9);
        z = (z ^ (z >> 27)).wrapping_mul(0x94D0_49BB_1331_11EB);
        z ^ (z >> 31)
    }
}

#[test]
fn at_least_99_9_percent_of_untouched_rows_are_recovered() {
    let cleans = cleans();
    if cleans.is_empty() {
        assert!(!ulog_tests::under_ci(), "no clean corpus file to damage");
        return;
    }
    let mut rng = SplitMix(0x5EED);
    let names = ["truncate", "flip", "splice", "insert", "delete"];
    let mut per_kind = [(0usize, 0usize); 5];
    let mut refused = 0;
    for case in 0..250 {
        let clean = &cleans[case % cleans.len()];
        let kind = (case / cleans.len()) as u8 % 5;
        let r: Vec<usize> = (0..4).map(|_| rng.next() as usize).collect();
        let m = mutation(clean.bytes.len(), kind, r[0], r[1], r[2], r[3] as u8);
        let damaged = Damaged::new(&clean.bytes, m);
        let Some(outcome) =
            check(clean, &damaged, 4096).unwrap_or_else(|e| panic!("{}: {e}", clean.name))
        else {
            refused += 1;
            continue;
        };
        per_kind[kind as usize].0 += outcome.untouched;
        per_kind[kind as usize].1 += outcome.recovered;
    }
    let (untouched, recovered) = per_kind
        .iter()
        .fold((0, 0), |acc, k| (acc.0 + k.0, acc.1 + k.1));
    for (name, (u, r)) in names.iter().zip(per_kind) {
        eprintln!(
            "{name:>8}: {r}/{u} untouched rows recovered ({:.3}%)",
            100.0 * r as f64 / u.max(1) as f64
        );
    }
    let ratio = recovered as f64 / untouched as f64;
    eprintln!(
        "   total: {recovered}/{untouched} ({:.3}%) over {} damaged copies ({refused} more rightly refused: damage set an incompat flag)",
        100.0 * ratio,
        250 - refused
    );
    assert!(refused < 25, "{refused} of 250 copies refused");
    assert!(
        ratio >= 0.999,
        "recovered {:.3}% of untouched rows",
        100.0 * ratio
    );
}

/// Everything a reader returns that the parallel whole-file reader must reproduce: rows
/// (offset, timestamp, data), diagnostics, logged strings + parameter changes + dropouts,
/// the number of sync messages, and the latest timestamp.
#[derive(Debug, PartialEq)]
struct Everything(
    Vec<(u64, u64, Vec<u8>)>,
    Vec<String>,
    Vec<String>,
    usize,
    u64,
);

fn full_read(log: &Log<'_>) -> Everything {
    let rows = log
        .data()
        .map(|r| (r.offset, r.timestamp, r.data.to_vec()))
        .collect();
    let diags = log.diagnostics().iter().map(ToString::to_string).collect();
    let mut other: Vec<String> = log
        .logged_messages()
        .iter()
        .map(|m| format!("{m:?}"))
        .collect();
    other.extend(log.parameter_changes().iter().map(|c| format!("{c:?}")));
    other.extend(log.dropouts().iter().map(|d| format!("{d:?}")));
    Everything(
        rows,
        diags,
        other,
        log.sync_offsets().len(),
        log.metadata().last_timestamp(),
    )
}

fn streamed(bytes: &[u8]) -> Everything {
    let mut reader = StreamReader::new(bytes).unwrap();
    let (mut rows, mut diags, mut logged, mut changes, mut dropouts, mut syncs) =
        (vec![], vec![], vec![], vec![], vec![], 0);
    while let Some(e) = reader.next_event().unwrap() {
        match e {
            Event::Row(r) => rows.push((r.offset, r.timestamp, r.data.to_vec())),
            Event::Diagnostic(d) => diags.push(d.to_string()),
            Event::Logged(m) => logged.push(format!("{m:?}")),
            Event::ParameterChange(c) => changes.push(format!("{c:?}")),
            Event::Dropout(d) => dropouts.push(format!("{d:?}")),
            Event::Sync { .. } => syncs += 1,
            _ => {}
        }
    }
    logged.extend(changes);
    logged.extend(dropouts);
    Everything(
        rows,
        diags,
        logged,
        syncs,
        reader.metadata().last_timestamp(),
    )
}

/// The largest clean corpus log inflated to 24 MB, which the readers split between threads;
/// `None` without a corpus (a failure under CI).
fn large_clean_log() -> Option<Vec<u8>> {
    let Some(clean) = cleans().iter().max_by_key(|c| c.bytes.len()) else {
        assert!(!ulog_tests::under_ci(), "no clean corpus file");
        return None;
    };
    Some(examples::inflate(&clean.bytes, 24_000_000).unwrap())
}

/// Large files are read on several threads; the result must be exactly the sequential one,
/// clean or damaged (damage near the parts' boundaries included).
#[test]
fn parallel_whole_file_reading_equals_sequential_streaming() {
    let Some(big) = large_clean_log() else {
        return;
    };
    let len = big.len();
    let mut cases = vec![("clean", big.clone())];
    for at in [len / 2, len / 3, 2 * len / 3, len / 4 + 1, 3 * len / 4 - 7] {
        let mut b = big.clone();
        b.splice(at..at, [0x41u8, 0x00, 0x41, 0xFF, 0x13]);
        cases.push(("garbage", b));
        let mut b = big.clone();
        b[at..at + 64].fill(0);
        cases.push(("zeros", b));
    }
    let mut cut = big.clone();
    cut.truncate(len / 2 + 3);
    cases.push(("cut", cut));
    for (what, bytes) in cases {
        let log = Log::from_slice(&bytes).unwrap();
        assert!(log.row_count() > 100_000);
        // The summary walks the same way without keeping rows.
        let summary = ulog_runtime::read::summarize(&bytes).unwrap();
        assert_eq!(summary.rows, log.row_count(), "{what}");
        assert_eq!(summary.diagnostics, log.diagnostics(), "{what}");
        assert_eq!(summary.sync_offsets, log.sync_offsets(), "{what}");
        assert_eq!(summary.dropouts, log.dropouts(), "{what}");
        assert_eq!(summary.logged_messages, log.logged_messages(), "{what}");
        // The one-pass fold sees exactly the rows of the index, in file order.
        let (folded, parts) =
            ulog_runtime::read::fold_rows(&bytes, Vec::new, |rows: &mut Vec<u64>, row| {
                rows.push(row.offset)
            })
            .unwrap();
        assert_eq!(folded.rows, log.row_count(), "{what}");
        assert_eq!(
            parts.concat(),
            log.data().map(|r| r.offset).collect::<Vec<_>>(),
            "{what}"
        );
        assert_eq!(
            full_read(&log),
            streamed(&bytes),
            "{what}: parallel and sequential reads differ"
        );
        // The fold by positioned reads of the file, on one thread (windows of the file
        // walked in turn) and on three (parts read side by side), is the fold in memory.
        for threads in [1, 3] {
            let (summary, rows) = fold_file_rows(&bytes, threads);
            assert_eq!(
                summary_figures(&summary),
                summary_figures(&folded),
                "{what}: fold_file on {threads} threads"
            );
            assert_eq!(
                rows,
                log.data()
                    .map(|r| (r.offset as usize, r.data.to_vec()))
                    .collect::<Vec<_>>(),
                "{what}: fold_file's rows on {threads} threads"
            );
        }
    }
}

/// A panic in a fold's closure on a thread that reads a part ahead reaches the caller as that
/// panic (its own message), from the fold of bytes and the fold of a file alike.
#[test]
fn a_panic_in_a_fold_reaches_the_caller_as_itself() {
    let Some(big) = large_clean_log() else {
        return;
    };
    // A row in the last of three parts.
    let late = big.len() as u64 * 5 / 6;
    let fold = |_: &mut (), row: &ulog_runtime::Row<'_>| {
        if row.offset > late {
            panic!("the fold's own panic");
        }
    };
    let path = std::env::temp_dir().join(format!("ulog-fold-panic-{}.ulg", std::process::id()));
    std::fs::write(&path, &big).unwrap();
    let file = std::fs::File::open(&path).unwrap();
    let panics = [
        std::panic::catch_unwind(|| ulog_runtime::read::fold_rows_on(3, &big, || (), fold)),
        std::panic::catch_unwind(|| ulog_runtime::read::fold_file_on(3, &file, || (), fold)),
    ];
    drop(file);
    std::fs::remove_file(&path).unwrap();
    for (what, p) in ["fold_rows", "fold_file"].into_iter().zip(panics) {
        let payload = p.expect_err(what);
        assert_eq!(
            payload.downcast_ref::<&str>(),
            Some(&"the fold's own panic"),
            "{what}"
        );
    }
}

/// What a fold's summary says, comparable.
fn summary_figures(s: &ulog_runtime::read::Summary) -> (usize, Vec<String>, String, u64) {
    (
        s.rows,
        s.diagnostics.iter().map(ToString::to_string).collect(),
        format!(
            "{:?} {:?} {:?} {:?}",
            s.logged_messages, s.parameter_changes, s.dropouts, s.sync_offsets
        ),
        s.metadata.last_timestamp(),
    )
}

/// `bytes` written to a file of their own and folded by [`ulog_runtime::read::fold_file_on`]
/// on `threads` threads: the summary and every row's offset and data, in file order.
fn fold_file_rows(
    bytes: &[u8],
    threads: usize,
) -> (ulog_runtime::read::Summary, Vec<(usize, Vec<u8>)>) {
    static FILES: std::sync::atomic::AtomicUsize = std::sync::atomic::AtomicUsize::new(0);
    let path = std::env::temp_dir().join(format!(
        "ulog-fold-file-{}-{}.ulg",
        std::process::id(),
        FILES.fetch_add(1, std::sync::atomic::Ordering::Relaxed)
    ));
    std::fs::write(&path, bytes).unwrap();
    let file = std::fs::File::open(&path).unwrap();
    let folded = ulog_runtime::read::fold_file_on(threads, &file, Vec::new, |rows, row| {
        rows.push((row.offset as usize, row.data.to_vec()));
    });
    drop(file);
    std::fs::remove_file(&path).unwrap();
    let (summary, parts) = folded.unwrap();
    (summary, parts.concat())
}

/// The streaming reader's memory stays bounded by a few messages whatever the file size
/// (here 24 MB, messages up to 17 KB).
#[test]
fn streaming_memory_is_bounded() {
    let Some(clean) = cleans().iter().max_by_key(|c| c.bytes.len()) else {
        assert!(!ulog_tests::under_ci(), "no clean corpus file");
        return;
    };
    let big = examples::inflate(&clean.bytes, 24_000_000).unwrap();
    let mut reader = StreamReader::new(&big[..]).unwrap();
    let (mut rows, mut most) = (0, 0);
    while let Some(event) = reader.next_event().unwrap() {
        rows += usize::from(matches!(event, Event::Row(_)));
        most = most.max(reader.buffered_capacity());
    }
    assert!(rows > 100_000);
    assert!(most <= 512 * 1024, "the stream buffer grew to {most} bytes");
}

/// A log that bends every rule the reader tolerates: values that do not fit their keys, a
/// blob split over continued parts, a key with a space, names outside the format grammar,
/// names that are not UTF-8.
fn odd_log() -> Vec<u8> {
    use ulog_runtime::read::{FileHeader, FlagBits, KeyValue, Message};
    let mut b = FileHeader {
        version: 1,
        start_timestamp: 0,
    }
    .to_bytes()
    .to_vec();
    let mut put = |m: Message<'_>| m.encode(&mut b).unwrap();
    put(Message::FlagBits(FlagBits::default()));
    let info = |key: &'static [u8], value: &'static [u8]| Message::Info(KeyValue { key, value });
    put(info(b"char[11] Build Date", b"2024-03-18 "));
    put(info(b"char[3] sys_name", b"PX4"));
    put(info(b"uint8_t[64] short_blob", &[7; 10]));
    put(info(b"char[5] n\xffame", b"v\xffal"));
    let blob: &'static [u8] = Box::leak(
        (0..=255u8)
            .cycle()
            .take(776)
            .collect::<Vec<_>>()
            .into_boxed_slice(),
    );
    for (i, part) in [&blob[..338], &blob[338..676], &blob[676..]]
        .into_iter()
        .enumerate()
    {
        put(Message::MultiInfo {
            continued: i > 0,
            entry: KeyValue {
                key: b"uint8_t[1169] metadata_events",
                value: part,
            },
        });
    }
    put(Message::Format(
        b"gps.raw:uint64_t timestamp;float alt;int8_t x-y;",
    ));
    put(Message::Format(b"t\xffopic:uint64_t timestamp;uint16_t v;"));
    put(Message::Subscribe {
        multi_id: 0,
        msg_id: 0,
        name: b"gps.raw",
    });
    put(Message::Subscribe {
        multi_id: 0,
        msg_id: 1,
        name: b"t\xffopic",
    });
    for t in 1..=3u64 {
        let mut row = t.to_le_bytes().to_vec();
        row.extend_from_slice(&(t as f32 * 1.5).to_le_bytes());
        row.push(t as u8);
        put(Message::Data {
            msg_id: 0,
            data: &row,
        });
        let mut row = t.to_le_bytes().to_vec();
        row.extend_from_slice(&(t as u16 * 100).to_le_bytes());
        put(Message::Data {
            msg_id: 1,
            data: &row,
        });
    }
    b
}

#[test]
fn odd_logs_keep_at_least_what_pyulog_keeps() {
    use serde_json::Value as Json;
    use ulog_runtime::{Scalar, Value};
    let bytes = odd_log();
    let log = Log::from_slice(&bytes).unwrap();
    let dir = std::env::temp_dir().join(format!("ulog-odd-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let path = dir.join("odd.ulg");
    std::fs::write(&path, &bytes).unwrap();
    let script = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("py/dump_values.py");
    let out = std::process::Command::new("python3")
        .arg(&script)
        .arg(&path)
        .output();
    std::fs::remove_dir_all(&dir).unwrap();
    let Some(out) = out.ok().filter(|o| o.status.success()) else {
        assert!(
            !ulog_tests::under_ci(),
            "under CI pyulog must be installed (.ci/run does it)"
        );
        eprintln!("pyulog not available: nothing compared");
        return;
    };
    let p: Json = serde_json::from_slice(&out.stdout).unwrap();
    let meta = log.metadata();
    // Every info value pyulog has, ours has too: pyulog cuts a key at its second space
    // (`Build` for `Build Date`); we keep the whole name.
    for (key, theirs) in p["info"].as_object().unwrap() {
        let ours = meta
            .info()
            .iter()
            .find(|i| i.key == *key || i.key.starts_with(&format!("{key} ")))
            .unwrap_or_else(|| panic!("info {key}"));
        match theirs {
            Json::String(text) => assert_eq!(ours.value.as_str(), Some(text.as_str()), "{key}"),
            other => {
                let hex: String = ours.raw.iter().map(|b| format!("{b:02x}")).collect();
                assert_eq!(other["hex"].as_str(), Some(hex.as_str()), "{key}");
            }
        }
    }
    assert!(meta.info_value("Build Date").is_some());
    // The blob's parts join to the bytes pyulog joins.
    for (key, values) in p["info_multiple"].as_object().unwrap() {
        let m = meta.multi_info().iter().find(|m| m.key == *key).unwrap();
        for (i, parts) in values.as_array().unwrap().iter().enumerate() {
            let theirs: String = parts
                .as_array()
                .unwrap()
                .iter()
                .map(|part| part["hex"].as_str().unwrap().to_owned())
                .collect();
            let ours: String = m
                .joined(i)
                .unwrap()
                .iter()
                .map(|b| format!("{b:02x}"))
                .collect();
            assert_eq!(ours, theirs, "{key} {i}");
        }
    }
    // Every row of every topic pyulog reads, under its name, with every value.
    let data = p["data"].as_object().unwrap();
    assert_eq!(data.len(), 2, "{data:?}");
    for (key, columns) in data {
        let (topic, multi_id) = key.rsplit_once('/').unwrap();
        let sub = log
            .subscription(topic, multi_id.parse().unwrap())
            .unwrap_or_else(|| panic!("{key}"));
        for (col, values) in columns.as_object().unwrap() {
            for (row, theirs) in log.rows(sub).zip(values.as_array().unwrap()) {
                let Value::Struct(fields) = row.value().unwrap() else {
                    panic!()
                };
                let ours = fields
                    .iter()
                    .find(|(n, _)| n == col)
                    .unwrap()
                    .1
                    .as_scalar()
                    .unwrap();
                let theirs = theirs.as_f64().unwrap();
                let ours = match ours {
                    Scalar::Float(x) => f64::from(x),
                    other => other.as_f64(),
                };
                assert_eq!(ours, theirs, "{key} {col}");
            }
        }
    }
}

/// The fuzz targets' checks (`fuzz/src/lib.rs`) on every input the fuzzers once failed on,
/// kept in `tests/fuzz_regressions/<target>/`: each must now pass.
#[path = "../../../fuzz/src/lib.rs"]
#[allow(dead_code, unreachable_pub)]
mod fuzz_checks;

/// A fuzz target's check: panics when the input shows a bug.
type FuzzCheck = fn(&[u8]);

#[test]
fn fuzz_regressions_pass() {
    let root = PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("fuzz_regressions");
    let targets: [(&str, FuzzCheck); 11] = [
        ("whole_file", fuzz_checks::whole_file),
        ("stream_chunks", fuzz_checks::stream_chunks),
        ("format_roundtrip", fuzz_checks::format_roundtrip),
        ("layout", fuzz_checks::layout),
        ("typed", fuzz_checks::typed),
        ("codegen_log", fuzz_checks::codegen_log),
        ("codegen_text", fuzz_checks::codegen_text),
        ("writer_ops", fuzz_checks::writer_ops),
        ("rewrite", fuzz_checks::rewrite),
        ("parquet", fuzz_checks::parquet),
        ("pyulog_compat", fuzz_checks::pyulog_compat),
    ];
    let mut ran = 0;
    for (target, check) in targets {
        let Ok(entries) = std::fs::read_dir(root.join(target)) else {
            continue;
        };
        for entry in entries {
            let path = entry.unwrap().path();
            let data = std::fs::read(&path).unwrap();
            let name = path.display().to_string();
            let outcome = std::panic::catch_unwind(|| check(&data));
            assert!(outcome.is_ok(), "{name}: the {target} check fails again");
            ran += 1;
        }
    }
    assert!(ran > 0, "regression inputs under {}", root.display());
    eprintln!("{ran} fuzz regressions pass");
}

/// The Parquet fuzz check on every corpus log: each topic instance written, read back with
/// its rows and row groups, its `FLOAT` statistics those of its values.
#[test]
fn the_parquet_fuzz_check_passes_on_every_corpus_log() {
    fuzz_check_on_every_corpus_log("parquet", fuzz_checks::parquet);
}

/// Runs a fuzz target's check on every corpus log; a failure names the log.
fn fuzz_check_on_every_corpus_log(target: &str, check: FuzzCheck) {
    for path in corpus_files() {
        let data = std::fs::read(&path).unwrap();
        let outcome = std::panic::catch_unwind(|| check(&data));
        assert!(
            outcome.is_ok(),
            "{}: the {target} check fails",
            short_name(&path)
        );
    }
}

/// The streaming fuzz check on every corpus log, read 4 KiB at a time (a first byte of 0: no
/// chunk sizes): the stream gives the whole-file reader's rows, logged strings, parameter
/// changes and dropouts, and ends with its initial parameters, info and multi info.
#[test]
fn the_stream_chunks_fuzz_check_passes_on_every_corpus_log() {
    fuzz_check_on_every_corpus_log("stream_chunks", |log| {
        fuzz_checks::stream_chunks(&[&[0u8][..], log].concat())
    });
}

/// The pyulog-compatibility fuzz check on every corpus log: pyulog's reading under each
/// option ends and the options agree (whole rows, header-only formats, strict strings, a
/// topic filter, the recovered datasets).
#[test]
fn the_pyulog_compat_fuzz_check_passes_on_every_corpus_log() {
    fuzz_check_on_every_corpus_log("pyulog_compat", fuzz_checks::pyulog_compat);
}

/// Every single-bit flip of the size field of rows of every clean corpus log loses at most
/// that row: where the declared size does not fit the row's format and the format's own
/// size ends on a message, the reader resynchronizes there.
#[test]
fn a_flipped_bit_in_a_rows_size_costs_at_most_that_row() {
    let mut trials = 0;
    let mut failures = Vec::new();
    for clean in cleans() {
        // Rows spread over the file: the first, and nine more at even steps.
        let picks: Vec<usize> = (0..10).map(|k| k * clean.rows.len() / 10).collect();
        for &i in &picks {
            let (start, _, _) = clean.rows[i];
            for bit in 0..16 {
                let mut bytes = clean.bytes.clone();
                let size = u16::from_le_bytes([bytes[start], bytes[start + 1]]) ^ (1 << bit);
                bytes[start..start + 2].copy_from_slice(&size.to_le_bytes());
                let rows = read_rows(&bytes).unwrap();
                let got: std::collections::HashMap<usize, &Vec<u8>> =
                    rows.iter().map(|(o, d)| (*o, d)).collect();
                let lost = clean
                    .rows
                    .iter()
                    .filter(|(o, _, d)| *o != start && got.get(o) != Some(&d))
                    .count();
                trials += 1;
                if lost > 0 {
                    failures.push(format!(
                        "{} row {i} bit {bit}: {lost} other rows lost",
                        clean.name
                    ));
                }
                assert_eq!(
                    stream_rows(&bytes, 4096).unwrap(),
                    rows,
                    "{} row {i} bit {bit}: the stream reads the same",
                    clean.name
                );
            }
        }
    }
    assert!(
        failures.is_empty(),
        "{trials} flips:\n{}",
        failures.join("\n")
    );
    eprintln!("{trials} single-bit flips of a row's size: no other row lost");
}
