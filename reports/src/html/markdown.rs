//! The Markdown subset the paper reproductions are written in (crate::paper), as HTML, so that
//! report.md and report.html share one source for those tables and claims.

use std::fmt::Write;

use super::esc;

/// The Markdown the paper sections are written in (headings, pipe tables, bullet lists,
/// paragraphs, `**bold**`, `*italic*`, `` `code` ``), as HTML; `**held**` and `**not held**`
/// are coloured.
pub fn markdown_fragment(md: &str) -> String {
    let mut out = String::new();
    let lines: Vec<&str> = md.lines().collect();
    let mut i = 0;
    while i < lines.len() {
        let line = lines[i].trim_end();
        if line.is_empty() {
            i += 1;
        } else if let Some((level, text)) = heading(line) {
            let _ = writeln!(out, "<h{level}>{}</h{level}>", inline(text));
            i += 1;
        } else if line.starts_with('|') {
            let start = i;
            while i < lines.len() && lines[i].starts_with('|') {
                i += 1;
            }
            table(&mut out, &lines[start..i]);
        } else if line.starts_with("- ") {
            out.push_str("<ul>\n");
            while i < lines.len() && lines[i].starts_with("- ") {
                let _ = writeln!(out, "<li>{}</li>", inline(&lines[i][2..]));
                i += 1;
            }
            out.push_str("</ul>\n");
        } else {
            let start = i;
            while i < lines.len()
                && !lines[i].trim().is_empty()
                && heading(lines[i]).is_none()
                && !lines[i].starts_with(['|', '-'])
            {
                i += 1;
            }
            let _ = writeln!(out, "<p>{}</p>", inline(&lines[start..i].join(" ")));
        }
    }
    out
}

fn heading(line: &str) -> Option<(usize, &str)> {
    let level = line.chars().take_while(|&c| c == '#').count();
    (1..=6).contains(&level).then(|| line[level..].strip_prefix(' ')).flatten().map(|t| (level, t))
}

fn table(out: &mut String, rows: &[&str]) {
    let cells = |row: &str| -> Vec<String> {
        row.trim().trim_start_matches('|').trim_end_matches('|').split('|').map(|c| c.trim().to_string()).collect()
    };
    let is_rule = |row: &str| row.chars().all(|c| matches!(c, '|' | '-' | ':' | ' '));
    let _ = writeln!(out, "<div class=\"scroll\"><table>");
    for (i, row) in rows.iter().enumerate() {
        if is_rule(row) {
            continue;
        }
        let tag = if i == 0 { "th" } else { "td" };
        out.push_str("<tr>");
        for c in cells(row) {
            let _ = write!(out, "<{tag}>{}</{tag}>", inline(&c));
        }
        out.push_str("</tr>\n");
    }
    let _ = writeln!(out, "</table></div>");
}

/// Escapes a line and renders its inline Markdown.
fn inline(text: &str) -> String {
    let text = esc(text)
        .replace("**held**", "<strong class=\"held\">held</strong>")
        .replace("**not held**", "<strong class=\"not-held\">not held</strong>");
    let text = pairs(&text, "**", "strong");
    let text = pairs(&text, "`", "code");
    pairs(&text, "*", "em")
}

/// Replaces each pair of `mark`s around text with `<tag>…</tag>`; an unpaired mark stays.
fn pairs(text: &str, mark: &str, tag: &str) -> String {
    let parts: Vec<&str> = text.split(mark).collect();
    if parts.len() < 3 {
        return text.to_string();
    }
    let mut out = String::new();
    for (i, part) in parts.iter().enumerate() {
        out.push_str(part);
        if i + 1 < parts.len() {
            let closing = i % 2 == 1;
            if !closing && i + 2 >= parts.len() {
                out.push_str(mark);
            } else {
                let _ = write!(out, "<{}{tag}>", if closing { "/" } else { "" });
            }
        }
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn markdown_fragments_become_html() {
        let md = "## Title\n\nSome `ug` text\nmore.\n\n| a | b |\n|---|---:|\n| *paper x* | 1 |\n\n- claim: **held**\n- other: **not held**\n";
        let html = markdown_fragment(md);
        assert!(html.contains("<h2>Title</h2>"), "{html}");
        assert!(html.contains("<p>Some <code>ug</code> text more.</p>"), "{html}");
        assert!(html.contains("<tr><th>a</th><th>b</th></tr>"), "{html}");
        assert!(html.contains("<td><em>paper x</em></td><td>1</td>"), "{html}");
        assert!(html.contains("<li>claim: <strong class=\"held\">held</strong></li>"), "{html}");
        assert!(html.contains("<strong class=\"not-held\">not held</strong>"), "{html}");
    }

    #[test]
    fn unpaired_marks_stay() {
        assert_eq!(pairs("2 * 3", "*", "em"), "2 * 3");
        assert_eq!(pairs("*a* and *b", "*", "em"), "<em>a</em> and *b");
    }
}
