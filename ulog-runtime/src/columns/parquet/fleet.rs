//! Where a conversion's files go ([`Layout`]), and many logs converted at once, in parallel
//! ([`Converter::convert_files`]).

use std::collections::HashMap;
use std::path::{Path, PathBuf};
use std::sync::Mutex;
use std::sync::atomic::{AtomicUsize, Ordering};

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
    /// The name of a log's folder (`<stem>`, or `log=<stem>` for hive), unique among `names`.
    pub(super) fn log_dir(self, names: &mut FileNames, stem: &str) -> String {
        let prefix = match self {
            Layout::PerLog => "",
            Layout::Hive => "log=",
        };
        names.unique(prefix, stem, "").file_name
    }

    /// The path of a topic instance's file; the other topic name it collided with, if its
    /// name had to be made unique. `names` are the log's file names (per-log layout);
    /// `topic_dirs` the topics' folders (hive), the same for every log of a converter.
    pub(super) fn table_path(
        self,
        root: &Path,
        log_dir: &str,
        names: &mut FileNames,
        topic_dirs: &Mutex<TopicDirs>,
        topic: &str,
        multi_id: u8,
    ) -> (PathBuf, Option<String>) {
        match self {
            Layout::PerLog => {
                let name = names.unique("", topic, &format!("_{multi_id}.parquet"));
                (root.join(log_dir).join(name.file_name), name.collided_with)
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
                    root.join(dir.as_str())
                        .join(log_dir)
                        .join(format!("multi_id={multi_id}"))
                        .join("data.parquet"),
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

/// The topics' folders of a hive layout: distinct topics never share one.
#[derive(Debug, Default)]
pub(super) struct TopicDirs {
    names: FileNames,
    dirs: HashMap<String, String>,
}

impl Converter {
    /// Converts every log of `paths` on `threads` threads (at least one; a log per thread at
    /// a time), giving each its own outputs: logs whose stems would collide (`a/x.ulg` and
    /// `b/x.ulg`) get folders `x` and `x~2` (`log=x`, `log=x~2`). The results are in the order of `paths`; a log that
    /// fails does not stop the others.
    pub fn convert_files(
        &self,
        paths: &[PathBuf],
        threads: usize,
    ) -> Vec<Result<Conversion, ConvertError>> {
        let mut names = FileNames::new();
        let layout = self.options.layout;
        let dirs: Vec<String> = paths
            .iter()
            .map(|p| layout.log_dir(&mut names, &crate::file_names::log_stem(p)))
            .collect();
        let results: Vec<Mutex<Option<Result<Conversion, ConvertError>>>> =
            paths.iter().map(|_| Mutex::new(None)).collect();
        let next = AtomicUsize::new(0);
        let work = || {
            loop {
                let i = next.fetch_add(1, Ordering::Relaxed);
                let Some(path) = paths.get(i) else { break };
                let result = self.convert_as(path, &dirs[i]);
                *results[i].lock().unwrap_or_else(|e| e.into_inner()) = Some(result);
            }
        };
        std::thread::scope(|scope| {
            for _ in 1..threads.clamp(1, paths.len().max(1)) {
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
