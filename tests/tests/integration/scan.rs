//! The `scan` example's figures (rows, leaves, sum of finite leaves, overall and per topic)
//! equal pyulog's for every corpus file. pyulog's figures come from `tests/py/scan_reference.py`
//! run live when pyulog is installed (always under CI, where `.ci/run` installs it), otherwise
//! from `tests/data/scan_reference.jsonl`, which that script wrote for the default corpus.
//!
//! Where this reader keeps intact rows pyulog skips after damage (see the conformance suite),
//! those rows are left out of our figures before comparing; the example itself counts them.

use std::collections::HashMap;
use std::path::Path;
use std::process::Command;

use examples::{Scan, Totals};
use serde_json::Value as Json;
use sha2::{Digest, Sha256};
use ulog_runtime::Log;
use ulog_tests::{corpus_files, pyulog_blind_ranges, short_name, under_ci};

fn live_reference(files: &[std::path::PathBuf]) -> Option<Vec<Json>> {
    let script = Path::new(env!("CARGO_MANIFEST_DIR")).join("py/scan_reference.py");
    let out = Command::new("python3")
        .arg(script)
        .args(files)
        .output()
        .ok()?;
    if !out.status.success() {
        eprintln!(
            "scan_reference.py failed: {}",
            String::from_utf8_lossy(&out.stderr)
                .lines()
                .last()
                .unwrap_or("")
        );
        return None;
    }
    let text = String::from_utf8(out.stdout).ok()?;
    text.lines().map(|l| serde_json::from_str(l).ok()).collect()
}

fn committed_reference() -> HashMap<String, Json> {
    let text = include_str!("../../data/scan_reference.jsonl");
    text.lines()
        .map(|l| serde_json::from_str::<Json>(l).expect("valid JSON lines"))
        .map(|j| (j["sha256"].as_str().unwrap().to_owned(), j))
        .collect()
}

fn close(a: f64, b: f64) -> bool {
    a == b || (a - b).abs() <= 1e-9 * a.abs().max(b.abs())
}

/// The same rows and leaves, overall and per topic; the sums may differ in the last bits,
/// being added in another order (rows split between threads).
fn same_scan(a: &Scan, b: &Scan) -> bool {
    let same =
        |a: &Totals, b: &Totals| a.rows == b.rows && a.leaves == b.leaves && close(a.sum, b.sum);
    same(&a.all, &b.all)
        && a.topics.len() == b.topics.len()
        && a.topics
            .iter()
            .zip(&b.topics)
            .all(|(x, y)| x.0 == y.0 && same(x.1, y.1))
}

#[test]
fn scan_figures_equal_pyulogs() {
    let files = corpus_files();
    if files.is_empty() {
        return;
    }
    let live = live_reference(&files);
    assert!(
        live.is_some() || !under_ci(),
        "under CI pyulog must be installed (.ci/run does it)"
    );
    let committed = committed_reference();
    eprintln!(
        "pyulog figures: {}",
        if live.is_some() {
            "computed live"
        } else {
            "committed reference"
        }
    );
    let mut failures = Vec::new();
    let mut compared = 0;
    for (i, path) in files.iter().enumerate() {
        let bytes = std::fs::read(path).unwrap();
        let sha: String = Sha256::digest(&bytes)
            .iter()
            .map(|b| format!("{b:02x}"))
            .collect();
        let reference = match &live {
            Some(all) => &all[i],
            None => match committed.get(&sha) {
                Some(r) => r,
                None => {
                    eprintln!(
                        "note: {}: no committed pyulog figures; install pyulog to check it",
                        short_name(path)
                    );
                    continue;
                }
            },
        };
        compared += 1;
        let log = Log::from_slice(&bytes).unwrap();
        let scan = Scan::log(&log);
        let streamed = Scan::stream(&bytes[..]).unwrap();
        let one_pass = Scan::bytes(&bytes).unwrap();
        let by_reads = Scan::file(&std::fs::File::open(path).unwrap()).unwrap();
        assert!(
            same_scan(&by_reads, &scan),
            "{}: the scan by positioned reads and the indexed scan differ",
            short_name(path)
        );
        assert!(
            same_scan(&one_pass, &scan),
            "{}: one-pass and indexed scans differ",
            short_name(path)
        );
        assert!(
            same_scan(&streamed, &scan),
            "{}: mmap and stream scans differ",
            short_name(path)
        );

        // Our figures over the rows pyulog reads.
        let blind = pyulog_blind_ranges(&log);
        let mut ours = Totals::default();
        let mut topics: HashMap<(String, u64), Totals> = HashMap::new();
        for row in log
            .data()
            .filter(|r| !blind.iter().any(|b| b.contains(&r.offset)))
        {
            ours.add(&row);
            topics
                .entry((
                    row.subscription.name.clone(),
                    u64::from(row.subscription.multi_id),
                ))
                .or_default()
                .add(&row);
        }
        if blind.is_empty() {
            // Nothing set aside: these are the example's own figures (summed in another order).
            assert_eq!((ours.rows, ours.leaves), (scan.all.rows, scan.all.leaves));
            assert!(
                close(ours.sum, scan.all.sum),
                "{} vs {}",
                ours.sum,
                scan.all.sum
            );
        }
        let name = short_name(path);
        let (msgs, leaves, sum) = (
            reference["msgs"].as_u64().unwrap(),
            reference["leaves"].as_u64().unwrap(),
            reference["sum"].as_f64().unwrap(),
        );
        if (ours.rows, ours.leaves) != (msgs, leaves) || !close(ours.sum, sum) {
            failures.push(format!("{name}: ours msgs={} leaves={} sum={:e}, pyulog msgs={msgs} leaves={leaves} sum={sum:e}", ours.rows, ours.leaves, ours.sum));
        }
        for t in reference["topics"].as_array().unwrap() {
            let key = (t[0].as_str().unwrap().to_owned(), t[1].as_u64().unwrap());
            let (rows, sum) = (t[2].as_u64().unwrap(), t[3].as_f64().unwrap());
            match topics.get(&key) {
                Some(x) if x.rows == rows && close(x.sum, sum) => {}
                other => failures.push(format!(
                    "{name}: {key:?}: ours {other:?}, pyulog rows={rows} sum={sum:e}"
                )),
            }
        }
        assert_eq!(
            topics.len(),
            reference["topics"].as_array().unwrap().len(),
            "{name}: topics with rows"
        );
    }
    assert!(failures.is_empty(), "{}", failures.join("\n"));
    eprintln!("{compared} files: scan figures equal pyulog's");
}

/// The scans' conversion of `uint64_t` leaves (`examples::u64_to_f64`, through `i64` below
/// 2^63) gives what `as f64` gives, at the edges of its fast path and of `f64`'s exact
/// integers.
#[test]
fn unsigned_64_bit_leaves_convert_as_the_language_converts_them() {
    for x in [
        0,
        1,
        (1u64 << 53) - 1,
        1 << 53,
        (1 << 53) + 1,
        (1 << 63) - 1,
        1 << 63,
        (1 << 63) + 1,
        (1 << 63) + 1025,
        u64::MAX - 1024,
        u64::MAX,
    ] {
        assert_eq!(
            examples::u64_to_f64(x).to_bits(),
            (x as f64).to_bits(),
            "{x}"
        );
    }
}
