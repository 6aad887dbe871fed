//! The documentation's links hold: every relative link and picture in README.md, ARCHITECTURE.md and docs/
//! names a file that exists, and every `#anchor` into a Markdown file names one of its headings (GitHub's rule:
//! lower case, punctuation dropped, spaces to hyphens, a repeated heading numbered `-1`, `-2`, ...). Links
//! inside code blocks and inline code are not links; `http:`/`mailto:` ones are not checked (no network here).

use std::collections::{HashMap, HashSet};
use std::path::{Path, PathBuf};

fn repo() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).parent().expect("app/ has a parent").to_path_buf()
}

/// The Markdown files the check covers: the two front pages and every `.md` below docs/.
fn markdown_files(root: &Path) -> Vec<PathBuf> {
    let mut files = vec![root.join("README.md"), root.join("ARCHITECTURE.md")];
    let mut dirs = vec![root.join("docs")];
    while let Some(dir) = dirs.pop() {
        for entry in std::fs::read_dir(&dir).unwrap_or_else(|e| panic!("reading {}: {e}", dir.display())) {
            let path = entry.expect("a directory entry").path();
            if path.is_dir() {
                dirs.push(path);
            } else if path.extension().is_some_and(|e| e == "md") {
                files.push(path);
            }
        }
    }
    files.sort();
    files
}

/// The lines of `text` outside fenced code blocks, with their 1-based numbers.
fn prose_lines(text: &str) -> Vec<(usize, &str)> {
    let mut fenced = false;
    let mut out = Vec::new();
    for (i, line) in text.lines().enumerate() {
        if line.trim_start().starts_with("```") {
            fenced = !fenced;
            continue;
        }
        if !fenced {
            out.push((i + 1, line));
        }
    }
    out
}

/// GitHub's anchor for a heading's text.
fn slug(heading: &str) -> String {
    heading
        .trim()
        .to_lowercase()
        .chars()
        .filter(|c| c.is_alphanumeric() || matches!(c, ' ' | '-' | '_'))
        .map(|c| if c == ' ' { '-' } else { c })
        .collect()
}

fn anchors(text: &str) -> HashSet<String> {
    let mut seen: HashMap<String, usize> = HashMap::new();
    let mut out = HashSet::new();
    for (_, line) in prose_lines(text) {
        let hashes = line.chars().take_while(|&c| c == '#').count();
        if !(1..=6).contains(&hashes) || !line[hashes..].starts_with(' ') {
            continue;
        }
        let base = slug(&line[hashes..]);
        let n = seen.entry(base.clone()).or_insert(0);
        out.insert(if *n == 0 { base.clone() } else { format!("{base}-{n}") });
        *n += 1;
    }
    out
}

/// The targets of `](target)` links on a line, inline code removed first.
fn link_targets(line: &str) -> Vec<String> {
    let mut plain = String::new();
    let mut in_code = false;
    for c in line.chars() {
        if c == '`' {
            in_code = !in_code;
        } else if !in_code {
            plain.push(c);
        }
    }
    let mut out = Vec::new();
    let mut rest = plain.as_str();
    while let Some(i) = rest.find("](") {
        rest = &rest[i + 2..];
        let end = rest.find(|c: char| c == ')' || c.is_whitespace()).unwrap_or(rest.len());
        out.push(rest[..end].to_string());
        rest = &rest[end..];
    }
    out
}

fn broken_links(root: &Path) -> Vec<String> {
    let mut broken = Vec::new();
    let mut cache: HashMap<PathBuf, HashSet<String>> = HashMap::new();
    for file in markdown_files(root) {
        let text = std::fs::read_to_string(&file).unwrap_or_else(|e| panic!("reading {}: {e}", file.display()));
        let shown = file.strip_prefix(root).unwrap_or(&file).display().to_string();
        for (number, line) in prose_lines(&text) {
            for target in link_targets(line) {
                let scheme = target.split_once(':').is_some_and(|(s, _)| s.chars().all(|c| c.is_ascii_alphabetic()));
                if target.is_empty() || scheme {
                    continue;
                }
                let (path, anchor) = match target.split_once('#') {
                    Some((p, a)) => (p, Some(a)),
                    None => (target.as_str(), None),
                };
                let resolved = if path.is_empty() { file.clone() } else { file.parent().unwrap().join(path) };
                if !resolved.exists() {
                    broken.push(format!("{shown}:{number}: {target}: no such file"));
                    continue;
                }
                let Some(anchor) = anchor else { continue };
                if resolved.extension().is_none_or(|e| e != "md") {
                    continue;
                }
                let known = cache.entry(resolved.clone()).or_insert_with(|| {
                    anchors(&std::fs::read_to_string(&resolved).expect("a Markdown file that exists reads"))
                });
                if !known.contains(anchor) {
                    broken.push(format!("{shown}:{number}: {target}: no heading with that anchor"));
                }
            }
        }
    }
    broken
}

#[test]
fn headings_give_githubs_anchors() {
    assert_eq!(
        slug(" Centers by greedy covering (`centers=cover`, twentieth session)"),
        "centers-by-greedy-covering-centerscover-twentieth-session"
    );
    assert_eq!(slug("Fig. 10's convergence, Table 1-2's shape"), "fig-10s-convergence-table-1-2s-shape");
    let text = "# A\n## A\n```\n# not a heading\n```\n#not one either\n### Tiles: 256² maps\n";
    let found = anchors(text);
    assert_eq!(found, HashSet::from(["a".to_string(), "a-1".to_string(), "tiles-256²-maps".to_string()]));
}

#[test]
fn link_targets_skip_inline_code() {
    let line = "see [a](docs/a.md#x) and `[b](not/a/link.md)` then ![p](assets/p.png)";
    assert_eq!(link_targets(line), vec!["docs/a.md#x", "assets/p.png"]);
}

#[test]
fn a_broken_link_and_a_missing_anchor_are_found() {
    let dir = std::env::temp_dir().join(format!("shadowlab-docs-links-{}", std::process::id()));
    std::fs::create_dir_all(dir.join("docs")).unwrap();
    std::fs::write(dir.join("README.md"), "[ok](docs/a.md#two) [gone](docs/b.md) [bad](docs/a.md#three)\n").unwrap();
    std::fs::write(dir.join("ARCHITECTURE.md"), "# One\n[self](#one)\n").unwrap();
    std::fs::write(dir.join("docs/a.md"), "# Two\n").unwrap();
    let broken = broken_links(&dir);
    std::fs::remove_dir_all(&dir).ok();
    assert_eq!(broken.len(), 2, "{broken:?}");
    assert!(broken[0].contains("docs/b.md: no such file"), "{broken:?}");
    assert!(broken[1].contains("docs/a.md#three: no heading"), "{broken:?}");
}

#[test]
fn every_link_in_the_documentation_holds() {
    let broken = broken_links(&repo());
    assert!(broken.is_empty(), "broken links in the documentation:\n{}", broken.join("\n"));
}
