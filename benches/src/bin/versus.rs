//! Whole programs side by side, in one run: `ulog` against PX4's flight-review-rs converter
//! (`ulog-convert`, from `../shared/tools/flight-review-rs/`) and the `scan` example against
//! px4-ulog 0.6.1 (`px4_ulog_scan`), on the same log, interleaved (ours, theirs, ours...,
//! the order alternating run by run), page cache warmed by a first untimed run of each
//! (which, for the scans, also checks that both programs print the same figures: the same
//! rows, leaves and sum). Prints, per comparison, the medians of wall time, CPU time (user +
//! system) and peak resident memory of both programs and their ratios, with the CPU model.
//!
//! Before the runs, the log's pages are put in the page cache in a stated way (`--cache`),
//! since how the cache holds them moves every program's system time, and the memory-mapped
//! readers' most: on Linux 6.18 a 400 MB log held in 4 KiB pages cost `scan --mmap` 0.04 to 0.08 s
//! of system time where the same log in the large folios of a sequential read cost it
//! 0.00 to 0.01 s (and `px4_ulog_scan` 0.02 to 0.04 s against 0.01 to 0.02 s). A cache
//! that has held the log for hours drifts toward small pages (the kernel reclaims parts of
//! it and reads them back piecemeal), which made the ratios of one session move by a third.
//! - `--cache read` (the default): the log's cached pages dropped, then the log read once
//!   from start to end, as a program reads a file from disk (the kernel's read-ahead fills
//!   the cache in large folios);
//! - `--cache pages`: the log's cached pages dropped, then read back one 4 KiB page at a
//!   time without read-ahead (`POSIX_FADV_RANDOM`), each page a folio of its own: the state
//!   of a cache refilled piecemeal;
//! - `--cache keep`: the cache as it is.
//!
//! ```text
//! cargo build --release -p ulog-runtime --features cli --bin ulog
//! cargo build --release -p examples --example scan
//! cargo build --release -p ulog-benches --bin px4_ulog_scan --bin versus
//! target/release/versus [--runs N] [--only NAME]... [--cache read|pages|keep] LOG
//! ```
//!
//! Comparisons (`--only` picks some):
//! - `parquet`: `ulog parquet LOG -o DIR` (analysis included) against `ulog-convert LOG DIR`;
//! - `analysis`: `ulog analyze --json LOG` against `ulog-convert --metadata-only LOG DIR`;
//! - `scan`: `scan LOG` (positioned reads, both cores) against `px4_ulog_scan LOG`;
//! - `scan_mmap`: `scan --mmap LOG` (memory map, both cores) against `px4_ulog_scan LOG`;
//! - `scan_stream`: `scan --stream LOG` (one core) against `px4_ulog_scan LOG`.
//!
//! The programs are found beside this one (`target/release/`), `ulog-convert` in
//! `../shared/tools/flight-review-rs/` of the workspace; `ULOG_CONVERT` overrides it.

// `wait4` gives the CPU time and peak memory of one child; std gives neither.
#![allow(unsafe_code)]

use std::path::{Path, PathBuf};
use std::process::{Command, ExitCode, Stdio};
use std::time::Instant;

/// One program's run.
#[derive(Clone, Copy)]
struct Measure {
    wall: f64,
    cpu: f64,
    rss_mib: f64,
}

/// A program to run: its path, arguments, and the output folder it writes (emptied first).
struct Program {
    label: String,
    path: PathBuf,
    args: Vec<String>,
    out: Option<PathBuf>,
}

impl Program {
    /// Runs the program once: its measure.
    fn run(&self) -> Result<Measure, String> {
        self.run_keeping(false).map(|(m, _)| m)
    }

    /// Runs the program once: its measure, and, if `keep_output`, what it printed (read
    /// once it ended, so at most a pipe's buffer, 64 KiB on Linux: the scans' one line).
    fn run_keeping(&self, keep_output: bool) -> Result<(Measure, String), String> {
        if let Some(out) = &self.out {
            if out.exists() {
                std::fs::remove_dir_all(out).map_err(|e| format!("{}: {e}", out.display()))?;
            }
            std::fs::create_dir_all(out).map_err(|e| format!("{}: {e}", out.display()))?;
        }
        let start = Instant::now();
        let child = Command::new(&self.path)
            .args(&self.args)
            .stdout(if keep_output {
                Stdio::piped()
            } else {
                Stdio::null()
            })
            .stderr(Stdio::piped())
            .spawn()
            .map_err(|e| format!("{}: {e}", self.path.display()))?;
        let pid = libc::pid_t::try_from(child.id()).map_err(|e| e.to_string())?;
        let mut status = 0;
        // SAFETY: an all-zero `rusage` is a valid value of that plain C struct.
        let mut usage: libc::rusage = unsafe { std::mem::zeroed() };
        // SAFETY: `pid` is our child, not yet reaped (std's `Child` is never waited on);
        // `status` and `usage` are valid for writes.
        let reaped = unsafe { libc::wait4(pid, &raw mut status, 0, &raw mut usage) };
        let wall = start.elapsed().as_secs_f64();
        if reaped != pid {
            return Err(format!("{}: wait4 failed", self.label));
        }
        if !libc::WIFEXITED(status) || libc::WEXITSTATUS(status) != 0 {
            let mut err = String::new();
            if let Some(mut e) = child.stderr {
                use std::io::Read;
                let _ = e.read_to_string(&mut err);
            }
            let how = if libc::WIFEXITED(status) {
                format!("exit code {}", libc::WEXITSTATUS(status))
            } else if libc::WIFSIGNALED(status) {
                format!("signal {}", libc::WTERMSIG(status))
            } else {
                format!("wait status {status}")
            };
            let err = err.trim_end();
            let sep = if err.is_empty() { "" } else { ": " };
            return Err(format!("{} failed ({how}){sep}{err}", self.label));
        }
        let mut printed = String::new();
        if let Some(mut o) = child.stdout {
            use std::io::Read;
            o.read_to_string(&mut printed)
                .map_err(|e| format!("{}: {e}", self.label))?;
        }
        let secs = |t: libc::timeval| t.tv_sec as f64 + t.tv_usec as f64 / 1e6;
        Ok((
            Measure {
                wall,
                cpu: secs(usage.ru_utime) + secs(usage.ru_stime),
                rss_mib: usage.ru_maxrss as f64 / 1024.0,
            },
            printed,
        ))
    }
}

/// How the log is put in the page cache before the runs (see the module's doc).
#[derive(Clone, Copy, PartialEq, Eq, Debug)]
enum Cache {
    Read,
    Pages,
    Keep,
}

impl Cache {
    fn parse(s: &str) -> Option<Cache> {
        match s {
            "read" => Some(Cache::Read),
            "pages" => Some(Cache::Pages),
            "keep" => Some(Cache::Keep),
            _ => None,
        }
    }

    /// What the runs start from, for the report.
    fn describe(self) -> &'static str {
        match self {
            Cache::Read => "log read into the page cache once, start to end (large folios)",
            Cache::Pages => "log read into the page cache one 4 KiB page at a time (small folios)",
            Cache::Keep => "page cache as found",
        }
    }

    /// Drops the log's cached pages and reads it back as `self` says. (A log on tmpfs, or
    /// mapped by another process meanwhile, keeps its pages: the runs then start from the
    /// cache as it was.)
    #[cfg(target_os = "linux")]
    fn prepare(self, log: &str) -> Result<(), String> {
        use std::io::Read;
        use std::os::fd::AsRawFd;
        use std::os::unix::fs::FileExt;
        if self == Cache::Keep {
            return Ok(());
        }
        let err = |e: std::io::Error| format!("{log}: {e}");
        let mut file = std::fs::File::open(log).map_err(err)?;
        // Written pages not yet on disk cannot be dropped.
        file.sync_data().map_err(err)?;
        let fd = file.as_raw_fd();
        let advise = |advice| {
            // SAFETY: `fd` is an open file of this function; the call only advises.
            match unsafe { libc::posix_fadvise(fd, 0, 0, advice) } {
                0 => Ok(()),
                e => Err(err(std::io::Error::from_raw_os_error(e))),
            }
        };
        advise(libc::POSIX_FADV_DONTNEED)?;
        let mut buf = vec![0u8; 1 << 20];
        match self {
            Cache::Read => while file.read(&mut buf).map_err(err)? > 0 {},
            Cache::Pages => {
                advise(libc::POSIX_FADV_RANDOM)?;
                let mut at = 0u64;
                loop {
                    let n = file.read_at(&mut buf[..4096], at).map_err(err)?;
                    if n == 0 {
                        break;
                    }
                    at += n as u64;
                }
            }
            Cache::Keep => {}
        }
        Ok(())
    }

    /// Elsewhere only the cache as found can be measured.
    #[cfg(not(target_os = "linux"))]
    fn prepare(self, _log: &str) -> Result<(), String> {
        match self {
            Cache::Keep => Ok(()),
            _ => Err(
                "--cache read and pages need Linux (posix_fadvise): use --cache keep".to_owned(),
            ),
        }
    }
}

fn median(mut v: Vec<f64>) -> f64 {
    v.sort_by(f64::total_cmp);
    let n = v.len();
    if n % 2 == 1 {
        v[n / 2]
    } else {
        (v[n / 2 - 1] + v[n / 2]) / 2.0
    }
}

fn cpu_model() -> String {
    std::fs::read_to_string("/proc/cpuinfo")
        .ok()
        .and_then(|s| {
            s.lines()
                .find(|l| l.starts_with("model name"))
                .and_then(|l| l.split(':').nth(1))
                .map(|m| m.trim().to_owned())
        })
        .unwrap_or_else(|| "unknown".to_owned())
}

fn main() -> ExitCode {
    let mut runs = 5usize;
    let mut only: Vec<String> = Vec::new();
    let mut log = None;
    let mut cache = Cache::Read;
    let mut args = std::env::args().skip(1);
    while let Some(a) = args.next() {
        match a.as_str() {
            "--help" | "-h" => {
                println!(
                    "versus: whole programs side by side, in one run\n{}",
                    usage_text()
                );
                return ExitCode::SUCCESS;
            }
            "--runs" => match args.next().and_then(|n| n.parse().ok()) {
                Some(n) if n > 0 => runs = n,
                _ => return usage("--runs takes a positive number"),
            },
            "--only" => match args.next() {
                Some(n) if NAMES.contains(&n.as_str()) => only.push(n),
                Some(n) => return usage(&format!("no comparison named `{n}`")),
                None => return usage("--only takes a comparison's name"),
            },
            "--cache" => match args.next().as_deref().and_then(Cache::parse) {
                Some(c) => cache = c,
                None => return usage("--cache takes read, pages or keep"),
            },
            _ if log.is_none() && !a.starts_with('-') => log = Some(a),
            _ => return usage(&format!("unexpected argument `{a}`")),
        }
    }
    let Some(log) = log else {
        return usage("no log given");
    };
    match compare(&log, runs, &only, cache) {
        Ok(()) => ExitCode::SUCCESS,
        Err(e) => {
            eprintln!("versus: {e}");
            ExitCode::FAILURE
        }
    }
}

/// The comparisons `--only` picks from.
const NAMES: [&str; 5] = ["parquet", "analysis", "scan", "scan_mmap", "scan_stream"];

fn usage_text() -> String {
    format!(
        "usage: versus [--runs N] [--only NAME]... [--cache read|pages|keep] LOG\n\
         --runs: timed runs of each program (default 5; the medians are printed); \
         NAME: {} (all by default); --cache: how the log is put in the page cache first \
         (read: read once start to end, the default; pages: a 4 KiB page at a time; keep: as \
         it is)",
        NAMES.join(", ")
    )
}

fn usage(why: &str) -> ExitCode {
    eprintln!("versus: {why}\n{}", usage_text());
    ExitCode::from(2)
}

fn compare(log: &str, runs: usize, only: &[String], cache: Cache) -> Result<(), String> {
    let here = std::env::current_exe().map_err(|e| e.to_string())?;
    let dir = here.parent().ok_or("no folder of this program")?;
    let convert = std::env::var_os("ULOG_CONVERT").map_or_else(
        || {
            Path::new(env!("CARGO_MANIFEST_DIR"))
                .join("../../shared/tools/flight-review-rs/ulog-convert")
        },
        PathBuf::from,
    );
    let work = std::env::temp_dir().join(format!("ulog-versus-{}", std::process::id()));
    let prog = |label: &str, path: PathBuf, args: &[&str], out: Option<&str>| Program {
        label: label.to_owned(),
        path,
        args: args.iter().map(|s| (*s).to_owned()).collect(),
        out: out.map(|o| work.join(o)),
    };
    let ours_out = work.join("ours").display().to_string();
    let theirs_out = work.join("theirs").display().to_string();
    let ulog = dir.join("ulog");
    let scan = dir.join("examples/scan");
    let px4 = dir.join("px4_ulog_scan");
    let pairs = [
        (
            "parquet",
            prog(
                "ulog parquet",
                ulog.clone(),
                &["parquet", log, "-o", &ours_out],
                Some("ours"),
            ),
            prog(
                "ulog-convert",
                convert.clone(),
                &[log, &theirs_out],
                Some("theirs"),
            ),
        ),
        (
            "analysis",
            prog(
                "ulog analyze --json",
                ulog,
                &["analyze", "--json", log],
                None,
            ),
            prog(
                "ulog-convert --metadata-only",
                convert,
                &["--metadata-only", log, &theirs_out],
                Some("theirs"),
            ),
        ),
        (
            "scan",
            prog("scan", scan.clone(), &[log], None),
            prog("px4_ulog_scan", px4.clone(), &[log], None),
        ),
        (
            "scan_mmap",
            prog("scan --mmap", scan.clone(), &[log, "--mmap"], None),
            prog("px4_ulog_scan", px4.clone(), &[log], None),
        ),
        (
            "scan_stream",
            prog("scan --stream", scan, &[log, "--stream"], None),
            prog("px4_ulog_scan", px4, &[log], None),
        ),
    ];
    let chosen: Vec<_> = pairs
        .iter()
        .filter(|(name, ..)| only.is_empty() || only.iter().any(|o| o == name))
        .collect();
    if chosen.is_empty() {
        return Err(format!("no comparison named {only:?}"));
    }
    cache.prepare(log)?;
    let mut results: Vec<(Vec<Measure>, Vec<Measure>)> =
        vec![(Vec::new(), Vec::new()); chosen.len()];
    // A first run of each warms the page cache and checks that both work (and, for the
    // scans, that both print the same figures: the same work done).
    for (name, ours, theirs) in &chosen {
        let scans = name.starts_with("scan");
        let (_, mine) = ours.run_keeping(scans)?;
        let (_, other) = theirs.run_keeping(scans)?;
        if mine != other {
            return Err(format!(
                "{} and {} printed different figures:\n{}\n{}",
                ours.label,
                theirs.label,
                mine.trim_end(),
                other.trim_end()
            ));
        }
    }
    println!(
        "CPU: {}; medians of {runs} {} each, interleaved; log {log}; {}",
        cpu_model(),
        if runs == 1 { "run" } else { "runs" },
        cache.describe()
    );
    for r in 0..runs {
        for (i, (_, ours, theirs)) in chosen.iter().enumerate() {
            if r % 2 == 0 {
                results[i].0.push(ours.run()?);
                results[i].1.push(theirs.run()?);
            } else {
                results[i].1.push(theirs.run()?);
                results[i].0.push(ours.run()?);
            }
        }
    }
    let _ = std::fs::remove_dir_all(&work);
    for ((name, ours, theirs), (o, t)) in chosen.iter().zip(&results) {
        let med = |m: &[Measure], f: fn(&Measure) -> f64| median(m.iter().map(f).collect());
        let row = |label: &str, m: &[Measure]| {
            println!(
                "  {label:<30} wall {:>7.3} s  cpu {:>7.3} s  peak RSS {:>7.1} MiB",
                med(m, |x| x.wall),
                med(m, |x| x.cpu),
                med(m, |x| x.rss_mib)
            );
        };
        println!("{name}:");
        row(&ours.label, o);
        row(&theirs.label, t);
        println!(
            "  ratio (ours / theirs)          wall {:>7.3}    cpu {:>7.3}    peak RSS {:>7.3}",
            med(o, |x| x.wall) / med(t, |x| x.wall),
            med(o, |x| x.cpu) / med(t, |x| x.cpu),
            med(o, |x| x.rss_mib) / med(t, |x| x.rss_mib)
        );
    }
    Ok(())
}
