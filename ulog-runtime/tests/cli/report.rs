//! `ulog report` in a real browser: the report of every corpus log is made, opened in
//! headless Chromium (Debian's `chromium`, installed by `.ci/run`), and every plot it holds
//! is laid out at its size with drawn lines in it; one full report is screenshot.

use std::collections::BTreeMap;
use std::path::{Path, PathBuf};
use std::process::Command;

use super::corpus::{corpus_files, short_name, under_ci};
use super::{stdout, temp_dir};

/// The browser, if there is one (required under CI).
fn chromium() -> Option<PathBuf> {
    let found = ["chromium", "chromium-browser"].iter().find_map(|name| {
        Command::new(name)
            .arg("--version")
            .output()
            .ok()
            .filter(|o| o.status.success())
            .map(|_| PathBuf::from(name))
    });
    assert!(
        found.is_some() || !under_ci(),
        "under CI chromium must be installed (.ci/run installs it)"
    );
    if found.is_none() {
        eprintln!("no chromium: the reports are made but not opened");
    }
    found
}

fn headless(browser: &Path) -> Command {
    let mut c = Command::new(browser);
    c.args([
        "--headless",
        "--no-sandbox",
        "--disable-gpu",
        "--hide-scrollbars",
        "--no-first-run",
        "--virtual-time-budget=10000",
    ]);
    c
}

/// Measures, in the browser, each plot of the page: `id width height lines shapes` a line:
/// the lines drawn (polylines and paths of some length) and the filled shapes with an area
/// (the background among them).
const PROBE: &str = r#"<script>
const rows = [...document.querySelectorAll('.plot')].map(d => {
  const svg = d.querySelector('svg');
  if (!svg) return d.id + ' 0 0 0 0';
  const box = svg.getBoundingClientRect();
  const sized = (sel, ok) => [...svg.querySelectorAll(sel)].filter(e => ok(e.getBBox())).length;
  const lines = sized('polyline, path', b => b.width > 0 || b.height > 0);
  const shapes = sized('rect, circle', b => b.width > 0 && b.height > 0);
  return [d.id, Math.round(box.width), Math.round(box.height), lines, shapes].join(' ');
});
// The marker split, so that the script's own text does not hold it.
document.body.insertAdjacentHTML('beforeend', '<pre id="pro' + 'be">' + rows.join('\n') + '</pre>');
</script>"#;

/// The plots a report's HTML holds, by id.
fn plot_ids(html: &str) -> Vec<String> {
    html.split("<div class=\"plot\" id=\"")
        .skip(1)
        .filter_map(|s| s.split('"').next())
        .map(str::to_owned)
        .collect()
}

#[test]
fn every_plot_of_every_corpus_report_renders_in_a_browser() {
    let dir = temp_dir("report");
    let browser = chromium();
    let mut fullest: Option<(usize, PathBuf)> = None;
    let mut seen: BTreeMap<String, usize> = BTreeMap::new();
    for log in corpus_files() {
        let name = short_name(&log);
        let html_path = dir.join(format!("{}.html", name.replace('/', "_")));
        let text = stdout(&[
            "report",
            log.to_str().unwrap(),
            "-o",
            html_path.to_str().unwrap(),
        ]);
        let html = std::fs::read_to_string(&html_path).unwrap();
        let ids = plot_ids(&html);
        assert!(
            text.contains(&format!(": {} plots", ids.len())),
            "{name}: {text}"
        );
        // Self-contained: nothing fetched at view time.
        for outside in ["<script", "src=\"http", "href=\"http", "@import", "url("] {
            assert!(!html.contains(outside), "{name}: `{outside}` in the report");
        }
        for id in &ids {
            *seen.entry(id.clone()).or_default() += 1;
        }
        if fullest.as_ref().is_none_or(|(n, _)| ids.len() > *n) {
            fullest = Some((ids.len(), html_path.clone()));
        }
        let Some(browser) = &browser else { continue };
        if ids.is_empty() {
            continue;
        }
        let probed = dir.join("probed.html");
        std::fs::write(&probed, html.replace("</body>", &format!("{PROBE}</body>"))).unwrap();
        let out = headless(browser)
            .arg("--dump-dom")
            .arg(format!("file://{}", probed.display()))
            .output()
            .expect("chromium runs");
        let dom = String::from_utf8_lossy(&out.stdout);
        let probe = dom
            .split("<pre id=\"probe\">")
            .nth(1)
            .and_then(|s| s.split("</pre>").next())
            .unwrap_or_else(|| panic!("{name}: the page did not load: {dom:.300}"));
        let measured: Vec<(String, u32, u32, u32, u32)> = probe
            .lines()
            .map(|l| {
                let f: Vec<&str> = l.split(' ').collect();
                let n = |i: usize| f.get(i).and_then(|v| v.parse().ok()).unwrap_or(0);
                (f[0].to_owned(), n(1), n(2), n(3), n(4))
            })
            .collect();
        assert_eq!(
            measured.iter().map(|m| &m.0).collect::<Vec<_>>(),
            ids.iter().collect::<Vec<_>>(),
            "{name}: every plot is in the page"
        );
        for (id, width, height, lines, shapes) in &measured {
            assert!(
                *width >= 600 && *height >= 100,
                "{name}: plot {id} laid out at {width}x{height}"
            );
            if id == "modes" {
                // The background and a mode's bar, at least.
                assert!(
                    *shapes >= 2,
                    "{name}: the mode timeline has {shapes} shapes"
                );
            } else {
                assert!(*lines >= 1, "{name}: plot {id} draws no line");
            }
        }
    }
    // The corpus holds logs that give each kind of plot.
    if !seen.is_empty() {
        for id in [
            "modes",
            "altitude",
            "speed",
            "attitude_roll",
            "rate_yaw",
            "outputs",
            "battery_voltage",
            "battery_current",
            "gps",
            "vibration",
            "gyro_psd",
            "step_response",
            "track",
        ] {
            assert!(
                seen.contains_key(id),
                "no corpus report has a {id} plot: {seen:?}"
            );
        }
    }
    if let (Some(browser), Some((_, page))) = (&browser, &fullest) {
        let png = dir.join("fullest.png");
        let out = headless(browser)
            .arg("--window-size=1200,9000")
            .arg(format!("--screenshot={}", png.display()))
            .arg(format!("file://{}", page.display()))
            .output()
            .expect("chromium runs");
        let bytes = std::fs::read(&png).unwrap_or_else(|e| {
            panic!(
                "no screenshot ({e}): {}",
                String::from_utf8_lossy(&out.stderr)
            )
        });
        assert_eq!(&bytes[..8], b"\x89PNG\r\n\x1a\n", "a PNG");
        assert!(
            bytes.len() > 100_000,
            "a page of plots, not a blank one: {} bytes",
            bytes.len()
        );
    }
    std::fs::remove_dir_all(&dir).unwrap();
}
