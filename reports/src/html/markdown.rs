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
        } else if let Some(id) = anchor_line(line) {
            // The anchors crate::claims::with_anchors puts before headings, for the glance links.
            let _ = writeln!(out, "<a id=\"{id}\"></a>");
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

/// The id of an `<a id="…"></a>` line whose id is letters, digits and `-` alone.
fn anchor_line(line: &str) -> Option<&str> {
    let id = line.strip_prefix("<a id=\"")?.strip_suffix("\"></a>")?;
    (!id.is_empty() && id.chars().all(|c| c.is_ascii_alphanumeric() || c == '-')).then_some(id)
}

fn heading(line: &str) -> Option<(usize, &str)> {
    let level = line.chars().take_while(|&c| c == '#').count();
    (1..=6).contains(&level).then(|| line[level..].strip_prefix(' ')).flatten().map(|t| (level, t))
}

fn table(out: &mut String, rows: &[&str]) {
    // Cells split at every `|` but an escaped `\|`, which stays in the cell as `|`.
    let cells = |row: &str| -> Vec<String> {
        let inner = row.trim().strip_prefix('|').unwrap_or(row.trim());
        let inner = inner.strip_suffix('|').filter(|i| !i.ends_with('\\')).unwrap_or(inner);
        let (mut cells, mut cell) = (Vec::new(), String::new());
        let mut chars = inner.chars().peekable();
        while let Some(c) = chars.next() {
            match c {
                '\\' if chars.peek() == Some(&'|') => {
                    chars.next();
                    cell.push('|');
                }
                '|' => cells.push(std::mem::take(&mut cell)),
                c => cell.push(c),
            }
        }
        cells.push(cell);
        cells.into_iter().map(|c| c.trim().to_string()).collect()
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
    let text = links(&text);
    let text = pairs(&text, "**", "strong");
    let text = pairs(&text, "`", "code");
    pairs(&text, "*", "em")
}

/// `[text](#id)` as a link within the page; links anywhere else stay text (the page holds no
/// external reference).
fn links(text: &str) -> String {
    let mut out = String::new();
    let mut rest = text;
    while let Some(open) = rest.find('[') {
        let Some((label, after)) = rest[open + 1..].split_once("](#") else { break };
        let Some((id, tail)) = after.split_once(')') else { break };
        if label.contains('[') || id.is_empty() || !id.chars().all(|c| c.is_ascii_alphanumeric() || c == '-') {
            out.push_str(&rest[..=open]);
            rest = &rest[open + 1..];
            continue;
        }
        let _ = write!(out, "{}<a href=\"#{id}\">{label}</a>", &rest[..open]);
        rest = tail;
    }
    out.push_str(rest);
    out
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
    fn anchors_and_links_within_the_page() {
        let html =
            markdown_fragment("<a id=\"paper-t1\"></a>\n\n## T1\n\n| [Table 1](#paper-t1) | [x](https://e.com) |\n");
        assert!(html.starts_with("<a id=\"paper-t1\"></a>\n<h2>T1</h2>"), "{html}");
        assert!(html.contains("<th><a href=\"#paper-t1\">Table 1</a></th>"), "{html}");
        assert!(html.contains("<th>[x](https://e.com)</th>"), "an external link stays text: {html}");
        let piped = markdown_fragment("| a \\| b | c |\n|---|---|\n");
        assert!(piped.contains("<th>a | b</th><th>c</th>"), "{piped}");
        let odd = markdown_fragment("<a id=\"x\" onclick=\"y\"></a>\n");
        assert!(odd.contains("&lt;a id="), "anything else is escaped: {odd}");
    }

    #[test]
    fn unpaired_marks_stay() {
        assert_eq!(pairs("2 * 3", "*", "em"), "2 * 3");
        assert_eq!(pairs("*a* and *b", "*", "em"), "<em>a</em> and *b");
    }
}
