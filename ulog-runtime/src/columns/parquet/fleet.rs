//! Where a conversion's files go ([`Layout`]), which folder a log takes (never another
//! log's: [`Converter::claim_log_dir`]), and many logs converted at once, in parallel
//! ([`Converter::convert_files`]), until told to stop ([`Converter::convert_files_until`]).

use std::collections::HashMap;
use std::path::{Path, PathBuf};
use std::sync::Mutex;
use std::sync::atomic::{AtomicBool, AtomicUsize, Ordering};

use super::convert::{Conversion, ConvertError, Converter};
use crate::file_names::FileNames;

/// Where the files of a conversion go, under the output folder `DIR`. Names from the log
/// pass through [`file_names`](crate::file_names), so none writes outside `DIR`.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
#[non_exhaustive]
pub enum Layout {
    /// A folder per log: `DIR/<stem>/<topic>_<multi_id>.parquet` and
    /// `DIR/<stem>/metadata.json`.
    #[default]
    PerLog,
    /// Hive partitions, one table per topic across all logs:
    /// `DIR/topic=<topic>/log=<stem>/multi_id=<m>/data.parquet`, and
    /// `DIR/metadata/log=<stem>/metadata.json`. Engines that read hive partitions (DuckDB,
    /// Polars, DataFusion, Spark, pyarrow) see `log` and `multi_id` as columns.
    Hive,
}

impl Layout {
    /// The `n`-th choice of the name of a log's folder: `<stem>` (`log=<stem>` for hive),
    /// then `<stem>~2`, `<stem>~3`... (see [`Converter::claim_log_dir`]).
    pub(super) fn log_dir(self, stem: &str, n: u32) -> String {
        let prefix = match self {
            Layout::PerLog => "",
            Layout::Hive => "log=",
        };
        crate::file_names::numbered(prefix, stem, "", n)
    }

    /// Where a topic instance's file goes, whatever log folder holds it; the other topic
    /// name it collided with, if its name had to be made unique. `names` are the log's file
    /// names (per-log layout); `topic_dirs` the topics' folders (hive), the same for every
    /// log of a converter.
    pub(super) fn table_place(
        self,
        names: &mut FileNames,
        topic_dirs: &Mutex<TopicDirs>,
        topic: &str,
        multi_id: u8,
    ) -> (TablePlace, Option<String>) {
        match self {
            Layout::PerLog => {
                let name = names.unique("", topic, &format!("_{multi_id}.parquet"));
                (TablePlace::InLogDir(name.file_name), name.collided_with)
            }
            Layout::Hive => {
                let mut dirs = topic_dirs.lock().unwrap_or_else(|e| e.into_inner());
                let TopicDirs { names, dirs } = &mut *dirs;
                let mut collided = None;
                let dir = dirs.entry(topic.to_owned()).or_insert_with(|| {
                    let name = names.unique("topic=", topic, "");
                    collided = name.collided_with;
                    name.file_name
                });
                (
                    TablePlace::Hive {
                        topic_dir: dir.clone(),
                        multi_id,
                    },
                    collided,
                )
            }
        }
    }

    /// The path of a log's `metadata.json`.
    pub(super) fn metadata_path(self, root: &Path, log_dir: &str) -> PathBuf {
        match self {
            Layout::PerLog => root.join(log_dir).join("metadata.json"),
            Layout::Hive => root.join("metadata").join(log_dir).join("metadata.json"),
        }
    }
}

/// Where a table's file goes, relative to its log's folder: the log's folder is chosen when
/// the log has been read whole ([`Converter::claim_log_dir`]).
#[derive(Debug, Clone)]
pub(super) enum TablePlace {
    /// `DIR/<log_dir>/<file name>`.
    InLogDir(String),
    /// `DIR/<topic_dir>/<log_dir>/multi_id=<m>/data.parquet`.
    Hive {
        /// `topic=<topic>`, unique among the converter's topics.
        topic_dir: String,
        /// The instance.
        multi_id: u8,
    },
}

impl TablePlace {
    /// The file's path when its log's folder is `log_dir`.
    pub(super) fn path(&self, root: &Path, log_dir: &str) -> PathBuf {
        match self {
            TablePlace::InLogDir(name) => root.join(log_dir).join(name),
            TablePlace::Hive {
                topic_dir,
                multi_id,
            } => root
                .join(topic_dir)
                .join(log_dir)
                .join(format!("multi_id={multi_id}"))
                .join("data.parquet"),
        }
    }
}

/// What a log folder holds, as its `metadata.json` says.
enum Held {
    /// No `metadata.json`: free.
    Nothing,
    /// A conversion of the log with this SHA-256.
    Log(String),
    /// A `metadata.json` that does not say which log: never replaced.
    Unknown,
}

/// What the log folder whose `metadata.json` is at `metadata` holds, or why that cannot be
/// told (the output folder is a file, or may not be read): an error, not a reason to try
/// the next name, since every next name would fail alike.
fn held(metadata: &Path) -> std::io::Result<Held> {
    let text = match std::fs::read(metadata) {
        Ok(text) => text,
        Err(e) if e.kind() == std::io::ErrorKind::NotFound => return Ok(Held::Nothing),
        // A folder named `metadata.json`: something, but not a conversion's.
        Err(e) if e.kind() == std::io::ErrorKind::IsADirectory => return Ok(Held::Unknown),
        Err(e) => return Err(e),
    };
    Ok(serde_json::from_slice::<serde_json::Value>(&text)
        .ok()
        .and_then(|doc| Some(doc.get("log")?.get("sha256")?.as_str()?.to_owned()))
        .map_or(Held::Unknown, Held::Log))
}

impl Converter {
    /// The folder of the log with digest `sha256` and stem `stem`: the first of `<stem>`,
    /// `<stem>~2`, `<stem>~3`... that holds this same log (its `metadata.json` has this
    /// SHA-256: a new conversion replaces it) or holds nothing, never one that holds another
    /// log (or a `metadata.json` that does not say which). The choice, and whether it is
    /// not the first; or the error that stopped the search (a `metadata.json` that cannot be
    /// read for another reason than its absence, such as an output folder that is a file).
    pub(super) fn claim_log_dir(
        &self,
        stem: &str,
        sha256: &str,
    ) -> Result<(String, bool), ConvertError> {
        let layout = self.options.layout;
        for n in 1..=u32::MAX {
            let dir = layout.log_dir(stem, n);
            let path = layout.metadata_path(&self.root, &dir);
            match held(&path).map_err(|source| ConvertError::Io { path, source })? {
                Held::Nothing => return Ok((dir, n > 1)),
                Held::Log(other) if other == sha256 => return Ok((dir, n > 1)),
                Held::Log(_) | Held::Unknown => {}
            }
        }
        Err(ConvertError::Io {
            path: self.root.clone(),
            source: std::io::Error::other(format!("every folder name for `{stem}` is taken")),
        })
    }
}

/// The topics' folders of a hive layout: distinct topics never share one.
#[derive(Debug, Default)]
pub(super) struct TopicDirs {
    names: FileNames,
    dirs: HashMap<String, String>,
}

impl Converter {
    /// Converts every log of `paths` on `threads` threads (at least one; a log per thread at
    /// a time). Logs with the same stem (`a/x.ulg` and `b/x.ulg`) are converted one after
    /// the other, in the order of `paths`: each goes to the first folder of `x`, `x~2`...
    /// that holds the same log or nothing ([`Conversion::log_dir`], with a note when it is
    /// not the first), so no conversion replaces another log's files. The results are in the
    /// order of `paths`; a log that fails does not stop the others.
    pub fn convert_files(
        &self,
        paths: &[PathBuf],
        threads: usize,
    ) -> Vec<Result<Conversion, ConvertError>> {
        self.convert_files_until(paths, threads, &AtomicBool::new(false))
    }

    /// [`convert_files`](Self::convert_files), stopping when `stop` is set (by another
    /// thread, a signal handler's flag): no log is started after that, and each log not
    /// started is [`ConvertError::Stopped`]. The logs under way when it is set are
    /// finished: stopping leaves no log half-written.
    ///
    /// ```no_run
    /// # use std::path::PathBuf;
    /// use std::sync::atomic::{AtomicBool, Ordering};
    /// use ulog_runtime::columns::parquet::{ConvertError, Converter, ParquetOptions};
    ///
    /// let stop = AtomicBool::new(false);
    /// let logs: Vec<PathBuf> = vec!["a.ulg".into(), "b.ulg".into()];
    /// let converter = Converter::new("fleet", ParquetOptions::default());
    /// let results = std::thread::scope(|s| {
    ///     let work = s.spawn(|| converter.convert_files_until(&logs, 2, &stop));
    ///     // ... on a user's request to stop:
    ///     stop.store(true, Ordering::Relaxed);
    ///     work.join().expect("the conversion does not panic")
    /// });
    /// let stopped = results
    ///     .iter()
    ///     .filter(|r| matches!(r, Err(ConvertError::Stopped { .. })))
    ///     .count();
    /// println!("{stopped} logs not converted");
    /// ```
    pub fn convert_files_until(
        &self,
        paths: &[PathBuf],
        threads: usize,
        stop: &AtomicBool,
    ) -> Vec<Result<Conversion, ConvertError>> {
        let layout = self.options.layout;
        let stems: Vec<String> = paths
            .iter()
            .map(|p| crate::file_names::log_stem(p))
            .collect();
        // Logs whose folders could collide (names equal without regard to case) form one
        // group, converted in order by one thread.
        let mut groups: Vec<Vec<usize>> = Vec::new();
        let mut group_of: HashMap<String, usize> = HashMap::new();
        for (i, stem) in stems.iter().enumerate() {
            let key = layout.log_dir(stem, 1).to_lowercase();
            let g = *group_of.entry(key).or_insert_with(|| {
                groups.push(Vec::new());
                groups.len() - 1
            });
            groups[g].push(i);
        }
        let results: Vec<Mutex<Option<Result<Conversion, ConvertError>>>> =
            paths.iter().map(|_| Mutex::new(None)).collect();
        let next = AtomicUsize::new(0);
        let threads = threads.max(1);
        let at_once = threads.min(groups.len().max(1));
        // One log at a time: its row groups encoded on the other threads.
        let encoders = if at_once > 1 {
            self.encoders(at_once)
        } else {
            self.options.encoders.unwrap_or(threads - 1)
        };
        let work = || {
            loop {
                let g = next.fetch_add(1, Ordering::Relaxed);
                let Some(group) = groups.get(g) else { break };
                for &i in group {
                    let result = if stop.load(Ordering::Relaxed) {
                        Err(ConvertError::Stopped {
                            log: paths[i].display().to_string(),
                        })
                    } else {
                        self.convert_as(&paths[i], &stems[i], encoders)
                    };
                    *results[i].lock().unwrap_or_else(|e| e.into_inner()) = Some(result);
                }
            }
        };
        std::thread::scope(|scope| {
            for _ in 1..at_once {
                scope.spawn(work);
            }
            work();
        });
        results
            .into_iter()
            .map(|m| {
                m.into_inner()
                    .unwrap_or_else(|e| e.into_inner())
                    .expect("every log converted")
            })
            .collect()
    }
}
