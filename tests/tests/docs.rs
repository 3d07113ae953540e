//! The project's documents are in the project: nothing in the repository refers to a path outside
//! it (`../shared`, a design brief that is not `docs/`), every `docs/<file>.md §N` a comment cites
//! names a section that file has, and every relative link in the Markdown files leads to a file
//! (and a heading, for `#anchor` links) that exists.

use std::collections::BTreeSet;
use std::path::{Path, PathBuf};

fn root() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("..")
}

/// Every text file of the repository that can refer to another: sources, shaders, Markdown,
/// manifests, CI scripts (build outputs, git's own files, and this file, which names the patterns
/// it looks for, left out).
fn text_files() -> Vec<PathBuf> {
    let this = Path::new(env!("CARGO_MANIFEST_DIR")).join("tests").join("docs.rs").canonicalize().ok();
    tests::files_under(&root(), &["target", ".git", "results"], |path| {
        let name = path.file_name().map(|n| n.to_string_lossy().into_owned()).unwrap_or_default();
        let text = [".rs", ".wgsl", ".md", ".toml", ".sh", ".yml"].iter().any(|e| name.ends_with(e))
            || path.parent().and_then(Path::file_name).is_some_and(|n| n == ".ci");
        text && path.canonicalize().ok() != this
    })
}

/// The section numbers of a Markdown file's numbered headings (`## 4. Structures` → `4`,
/// `### 4.5 Grid family` → `4.5`).
fn sections(doc: &Path) -> BTreeSet<String> {
    let text = std::fs::read_to_string(doc).unwrap_or_default();
    text.lines()
        .filter(|l| l.starts_with('#'))
        .filter_map(|l| l.trim_start_matches('#').split_whitespace().next())
        .map(|n| n.trim_end_matches('.').to_string())
        .filter(|n| !n.is_empty() && n.chars().all(|c| c.is_ascii_digit() || c == '.'))
        .collect()
}

/// GitHub's anchor of a heading: lower case, spaces to hyphens, punctuation dropped.
fn anchor(heading: &str) -> String {
    heading
        .trim()
        .to_lowercase()
        .chars()
        .filter_map(|c| match c {
            ' ' => Some('-'),
            c if c.is_alphanumeric() || c == '-' || c == '_' => Some(c),
            _ => None,
        })
        .collect()
}

fn anchors(doc: &Path) -> BTreeSet<String> {
    let text = std::fs::read_to_string(doc).unwrap_or_default();
    text.lines().filter(|l| l.starts_with('#')).map(|l| anchor(l.trim_start_matches('#'))).collect()
}

fn relative(path: &Path) -> String {
    path.strip_prefix(root()).unwrap_or(path).display().to_string()
}

#[test]
fn nothing_refers_outside_the_repository() {
    let mut found = Vec::new();
    for file in text_files() {
        let text = std::fs::read_to_string(&file).unwrap_or_default();
        for (i, line) in text.lines().enumerate() {
            let bare_brief = line.replace("docs/design.md", "").contains("DESIGN.md");
            if line.contains("../shared") || bare_brief {
                found.push(format!("{}:{}: {}", relative(&file), i + 1, line.trim()));
            }
        }
    }
    assert!(found.is_empty(), "references outside the repository:\n{}", found.join("\n"));
}

#[test]
fn every_cited_design_section_exists() {
    let mut dangling = Vec::new();
    let mut cited = 0;
    for file in text_files() {
        let text = std::fs::read_to_string(&file).unwrap_or_default();
        for (i, line) in text.lines().enumerate() {
            for (at, _) in line.match_indices("docs/") {
                let rest = &line[at..];
                let Some(end) = rest.find(".md") else { continue };
                let doc = &rest[..end + 3];
                if doc.contains(|c: char| c.is_whitespace() || c == '`' || c == ')') {
                    continue;
                }
                let path = root().join(doc);
                let where_ = format!("{}:{}", relative(&file), i + 1);
                if !path.is_file() {
                    dangling.push(format!("{where_}: {doc} does not exist"));
                    continue;
                }
                let Some(after) = rest[end + 3..].strip_prefix(" §") else { continue };
                let numbers: String = after.chars().take_while(|c| c.is_ascii_digit() || ".–-".contains(*c)).collect();
                let have = sections(&path);
                for n in numbers.split(['–', '-']).map(|n| n.trim_end_matches('.')).filter(|n| !n.is_empty()) {
                    cited += 1;
                    if !have.contains(n) {
                        dangling.push(format!("{where_}: {doc} has no section {n}"));
                    }
                }
            }
        }
    }
    assert!(cited > 50, "the code cites the design's sections ({cited} found): is the scan broken?");
    assert!(dangling.is_empty(), "dangling references:\n{}", dangling.join("\n"));
}

#[test]
fn every_relative_markdown_link_leads_somewhere() {
    let mut dangling = Vec::new();
    let mut links = 0;
    for file in text_files().into_iter().filter(|f| f.extension().is_some_and(|e| e == "md")) {
        let text = std::fs::read_to_string(&file).unwrap_or_default();
        let folder = file.parent().unwrap_or(Path::new("."));
        for (i, line) in text.lines().enumerate() {
            for (at, _) in line.match_indices("](") {
                let rest = &line[at + 2..];
                let Some(end) = rest.find(')') else { continue };
                let target = &rest[..end];
                if target.contains("://") || target.starts_with("mailto:") {
                    continue;
                }
                links += 1;
                let (path, fragment) = target.split_once('#').unwrap_or((target, ""));
                let path = if path.is_empty() { file.clone() } else { folder.join(path) };
                let where_ = format!("{}:{}", relative(&file), i + 1);
                if !path.exists() {
                    dangling.push(format!("{where_}: {target}: no such file"));
                } else if !fragment.is_empty() && path.is_file() && !anchors(&path).contains(fragment) {
                    dangling.push(format!("{where_}: {target}: no such heading"));
                }
            }
        }
    }
    assert!(links > 0, "no relative links found: is the scan broken?");
    assert!(dangling.is_empty(), "dangling links:\n{}", dangling.join("\n"));
}
