//! The report's HTML: one document, its style inline, every plot an inline SVG, every text
//! from the log escaped.

use std::fmt::Write;

use super::Report;

/// Logged messages and parameter changes shown at most (the rest counted).
const MAX_ROWS: usize = 2000;

/// `text` with HTML's special characters escaped and its control characters made visible.
pub(super) fn escape(text: &str) -> String {
    let mut out = String::with_capacity(text.len());
    for c in text.chars() {
        match c {
            '&' => out.push_str("&amp;"),
            '<' => out.push_str("&lt;"),
            '>' => out.push_str("&gt;"),
            '"' => out.push_str("&quot;"),
            '\'' => out.push_str("&#39;"),
            // Control characters, which HTML does not allow in text (a NUL among them),
            // shown as their pictures (␀, ␛...); the C1 ones as the replacement character.
            '\t' | '\n' | '\r' => out.push(c),
            c @ ('\0'..='\x1f') => {
                out.push(char::from_u32(0x2400 + u32::from(c)).unwrap_or('\u{fffd}'))
            }
            '\x7f' => out.push('\u{2421}'),
            '\u{80}'..='\u{9f}' => out.push('\u{fffd}'),
            c => out.push(c),
        }
    }
    out
}

const STYLE: &str = "body{font-family:sans-serif;margin:24px auto;max-width:1160px;color:#222}\
h1{font-size:22px}h2{font-size:18px;margin-top:28px;border-bottom:1px solid #ddd}\
table{border-collapse:collapse;font-size:13px}td,th{border:1px solid #ddd;padding:3px 8px;\
text-align:left;vertical-align:top}th{background:#f4f4f4}pre{background:#f8f8f8;padding:10px;\
font-size:13px;overflow-x:auto}.plot{margin:12px 0}.critical{color:#b00}.warning{color:#a60}";

/// The whole page.
pub(super) fn page(r: &Report) -> String {
    let mut h = String::new();
    let title = escape(&r.file_name);
    let _ = write!(
        h,
        "<!DOCTYPE html>\n<html lang=\"en\"><head><meta charset=\"utf-8\">\
         <title>Flight report: {title}</title><style>{STYLE}</style></head><body>\n\
         <h1>Flight report: {title}</h1>\n"
    );
    table(
        &mut h,
        &["", ""],
        r.facts.iter().map(|(k, v)| vec![escape(k), escape(v)]),
        usize::MAX,
    );
    let _ = write!(
        h,
        "<h2>Summary</h2>\n<pre>{}</pre>\n",
        escape(&r.analysis.to_string())
    );
    h.push_str("<h2>Diagnostics</h2>\n");
    if r.analysis.diagnostics.is_empty() {
        h.push_str("<p>None.</p>\n");
    } else {
        table(
            &mut h,
            &["severity", "from (s)", "to (s)", "what"],
            r.analysis.diagnostics.iter().map(|d| {
                let class = format!("{:?}", d.severity).to_lowercase();
                vec![
                    format!("<span class=\"{class}\">{class}</span>"),
                    format!("{:.1}", d.timestamp_us as f64 / 1e6),
                    d.end_timestamp_us
                        .map_or(String::new(), |e| format!("{:.1}", e as f64 / 1e6)),
                    escape(&d.summary),
                ]
            }),
            usize::MAX,
        );
    }
    h.push_str("<h2>Plots</h2>\n");
    for p in &r.plots {
        let _ = writeln!(
            h,
            "<div class=\"plot\" id=\"{}\" title=\"{}\">{}</div>",
            escape(&p.id),
            escape(&p.title),
            p.svg
        );
    }
    if !r.left_out.is_empty() {
        h.push_str("<h2>Plots the log cannot give</h2>\n");
        table(
            &mut h,
            &["plot", "why"],
            r.left_out.iter().map(|(t, w)| vec![escape(t), escape(w)]),
            usize::MAX,
        );
    }
    h.push_str("<h2>Non-default parameters</h2>\n");
    if r.analysis.non_default_params.is_empty() {
        h.push_str("<p>None the log can tell (it needs the default parameters PX4 logs).</p>\n");
    } else {
        table(
            &mut h,
            &["name", "value", "default"],
            r.analysis
                .non_default_params
                .iter()
                .map(|p| vec![escape(&p.name), p.value.to_string(), p.default.to_string()]),
            usize::MAX,
        );
    }
    h.push_str("<h2>Parameter changes</h2>\n");
    if r.parameter_changes.is_empty() {
        h.push_str("<p>None.</p>\n");
    } else {
        table(
            &mut h,
            &["time (s)", "name", "value"],
            r.parameter_changes
                .iter()
                .map(|(t, n, v)| vec![format!("{t:.3}"), escape(n), escape(v)]),
            MAX_ROWS,
        );
    }
    h.push_str("<h2>Logged messages</h2>\n");
    if r.messages.is_empty() {
        h.push_str("<p>None.</p>\n");
    } else {
        table(
            &mut h,
            &["time (s)", "level", "message"],
            r.messages
                .iter()
                .map(|(t, l, m)| vec![format!("{t:.3}"), escape(l), escape(m)]),
            MAX_ROWS,
        );
    }
    h.push_str("</body></html>\n");
    h
}

/// A table of `rows` (cells already HTML), at most `max` of them and a line counting the
/// others.
fn table(
    h: &mut String,
    head: &[&str],
    rows: impl ExactSizeIterator<Item = Vec<String>>,
    max: usize,
) {
    let total = rows.len();
    h.push_str("<table>");
    if head.iter().any(|c| !c.is_empty()) {
        h.push_str("<tr>");
        for c in head {
            let _ = write!(h, "<th>{}</th>", escape(c));
        }
        h.push_str("</tr>");
    }
    for row in rows.take(max) {
        h.push_str("<tr>");
        for c in row {
            let _ = write!(h, "<td>{c}</td>");
        }
        h.push_str("</tr>");
    }
    h.push_str("</table>\n");
    if total > max {
        let _ = writeln!(h, "<p>({} more not shown.)</p>", total - max);
    }
}

#[cfg(test)]
mod tests {
    #[test]
    fn text_from_a_log_cannot_make_markup() {
        assert_eq!(
            super::escape("<script>alert('x') & \"y\"</script>"),
            "&lt;script&gt;alert(&#39;x&#39;) &amp; &quot;y&quot;&lt;/script&gt;"
        );
        assert_eq!(
            super::escape("a\0b\x1b[31mc\x7f\u{85}\td\n"),
            "a\u{2400}b\u{241b}[31mc\u{2421}\u{fffd}\td\n"
        );
    }
}
