//! The user's documentation: every relative link in README.md, BENCHMARKS.md, tests/README.md
//! and docs/*.md names a file that exists (and, with `#anchor`, a heading of that file, as
//! GitHub makes its anchors), every page of docs/ is reachable from the README, and the README
//! and BENCHMARKS.md stay within the sizes that keep them readable.

use std::collections::{BTreeSet, HashSet};
use std::path::{Path, PathBuf};

fn root() -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR"))
}

/// The Markdown files the checks cover.
fn pages() -> Vec<PathBuf> {
    let mut pages: Vec<PathBuf> = ["README.md", "BENCHMARKS.md", "tests/README.md"]
        .iter()
        .map(|p| root().join(p))
        .collect();
    let mut docs: Vec<PathBuf> = std::fs::read_dir(root().join("docs"))
        .expect("docs/ exists")
        .map(|e| e.expect("a docs/ entry").path())
        .filter(|p| p.extension().is_some_and(|e| e == "md"))
        .collect();
    docs.sort();
    pages.extend(docs);
    pages
}

/// The targets of the page's inline links and images, `[text](target)`, outside code blocks
/// and code spans.
fn links(text: &str) -> Vec<String> {
    let mut found = Vec::new();
    let mut in_block = false;
    for line in text.lines() {
        if line.trim_start().starts_with("```") {
            in_block = !in_block;
            continue;
        }
        if in_block {
            continue;
        }
        // Code spans are not links: drop them before looking.
        let mut plain = String::new();
        for (i, part) in line.split('`').enumerate() {
            if i % 2 == 0 {
                plain.push_str(part);
            }
        }
        let mut rest = plain.as_str();
        while let Some(at) = rest.find("](") {
            let after = &rest[at + 2..];
            let Some(end) = after.find(')') else { break };
            found.push(after[..end].trim().to_string());
            rest = &after[end..];
        }
    }
    found
}

/// GitHub's anchor for a heading: lower case, punctuation dropped (letters, digits, spaces,
/// hyphens and underscores kept), spaces to hyphens.
fn slug(heading: &str) -> String {
    heading
        .trim()
        .to_lowercase()
        .chars()
        .filter(|c| c.is_alphanumeric() || *c == ' ' || *c == '-' || *c == '_')
        .map(|c| if c == ' ' { '-' } else { c })
        .collect()
}

fn anchors(text: &str) -> HashSet<String> {
    let mut in_block = false;
    let mut found = HashSet::new();
    for line in text.lines() {
        if line.trim_start().starts_with("```") {
            in_block = !in_block;
        } else if !in_block && line.starts_with('#') {
            found.insert(slug(line.trim_start_matches('#')));
        }
    }
    found
}

fn is_external(target: &str) -> bool {
    ["http://", "https://", "mailto:"]
        .iter()
        .any(|p| target.starts_with(p))
}

#[test]
fn every_relative_link_resolves() {
    let mut broken = Vec::new();
    for page in pages() {
        let text = std::fs::read_to_string(&page).expect("page readable");
        let dir = page.parent().expect("a folder");
        for target in links(&text) {
            if is_external(&target) {
                continue;
            }
            let (file, anchor) = match target.split_once('#') {
                Some((f, a)) => (f, Some(a)),
                None => (target.as_str(), None),
            };
            let path = if file.is_empty() {
                page.clone()
            } else {
                dir.join(file)
            };
            if !path.exists() {
                broken.push(format!("{}: {target} (no such file)", page.display()));
                continue;
            }
            if let Some(anchor) = anchor {
                let linked = std::fs::read_to_string(&path).expect("linked page readable");
                if !anchors(&linked).contains(anchor) {
                    broken.push(format!("{}: {target} (no such heading)", page.display()));
                }
            }
        }
    }
    assert!(broken.is_empty(), "broken links:\n{}", broken.join("\n"));
}

/// Every page of docs/ is linked from the README or from a page the README links.
#[test]
fn every_docs_page_is_reachable_from_the_readme() {
    let canonical = |p: &Path| p.canonicalize().expect("an existing page");
    let readme = canonical(&root().join("README.md"));
    let mut reached = BTreeSet::from([readme.clone()]);
    let mut frontier = vec![readme];
    for _ in 0..2 {
        let mut next = Vec::new();
        for page in &frontier {
            let text = std::fs::read_to_string(page).expect("page readable");
            for target in links(&text) {
                let file = target.split('#').next().unwrap_or("");
                if is_external(&target) || !file.ends_with(".md") {
                    continue;
                }
                let path = page.parent().expect("a folder").join(file);
                if path.exists() && reached.insert(canonical(&path)) {
                    next.push(canonical(&path));
                }
            }
        }
        frontier = next;
    }
    let unreached: Vec<_> = pages()
        .into_iter()
        .filter(|p| p.starts_with(root().join("docs")))
        .filter(|p| !reached.contains(&canonical(p)))
        .collect();
    assert!(
        unreached.is_empty(),
        "docs pages not reachable: {unreached:?}"
    );
}

#[test]
fn readme_and_benchmarks_stay_short() {
    for (file, limit) in [("README.md", 16_000), ("BENCHMARKS.md", 40_000)] {
        let size = std::fs::metadata(root().join(file))
            .expect("file exists")
            .len();
        assert!(size <= limit, "{file} is {size} bytes, more than {limit}");
    }
}
