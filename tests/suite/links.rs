//! The README and `docs/` link only to what exists: every relative link names a file of
//! the repository, and every `#anchor` a heading of its page (GitHub's slugs).

use std::collections::BTreeSet;
use std::path::{Path, PathBuf};

/// GitHub's anchor of a heading: lower case, punctuation dropped (letters, digits,
/// `_`, `-` and spaces kept), spaces as `-`.
fn slug(heading: &str) -> String {
    heading
        .trim()
        .to_lowercase()
        .chars()
        .filter(|c| c.is_alphanumeric() || matches!(c, '_' | '-' | ' '))
        .map(|c| if c == ' ' { '-' } else { c })
        .collect()
}

/// The anchors of a Markdown page's headings (code blocks skipped).
fn anchors(text: &str) -> BTreeSet<String> {
    let mut fenced = false;
    let mut out = BTreeSet::new();
    for line in text.lines() {
        if line.trim_start().starts_with("```") {
            fenced = !fenced;
        } else if !fenced && line.starts_with('#') {
            out.insert(slug(line.trim_start_matches('#')));
        }
    }
    out
}

/// The targets of a page's inline links `](target)`.
fn links(text: &str) -> Vec<String> {
    text.match_indices("](")
        .filter_map(|(i, _)| {
            let rest = &text[i + 2..];
            let end = rest.find([')', ' ', '\n'])?;
            (rest.as_bytes().get(end) == Some(&b')')).then(|| rest[..end].to_string())
        })
        .collect()
}

/// The README and every page of `docs/`.
fn pages() -> Vec<PathBuf> {
    let root = Path::new(env!("CARGO_MANIFEST_DIR"));
    let mut pages = vec![root.join("README.md")];
    for e in std::fs::read_dir(root.join("docs")).unwrap() {
        let p = e.unwrap().path();
        if p.extension().is_some_and(|x| x == "md") {
            pages.push(p);
        }
    }
    pages
}

/// Every relative link of the README and the docs names a file or folder that exists,
/// and its anchor a heading of that page.
#[test]
fn every_link_in_the_readme_and_docs_resolves() {
    let mut bad = Vec::new();
    let mut checked = 0;
    for page in pages() {
        let text = std::fs::read_to_string(&page).unwrap();
        for target in links(&text) {
            if target.contains("://") || target.starts_with("mailto:") {
                continue;
            }
            let (path, anchor) = target.split_once('#').unwrap_or((&target, ""));
            let file = match path {
                "" => page.clone(),
                p => page.parent().unwrap().join(p),
            };
            checked += 1;
            if !file.exists() {
                bad.push(format!("{}: {target} (no such file)", page.display()));
            } else if !anchor.is_empty() && file.extension().is_some_and(|x| x == "md") {
                let heads = anchors(&std::fs::read_to_string(&file).unwrap());
                if !heads.contains(anchor) {
                    bad.push(format!("{}: {target} (no such heading)", page.display()));
                }
            }
        }
    }
    assert!(checked > 50, "only {checked} links found: the scan is broken");
    assert!(bad.is_empty(), "links that lead nowhere:\n{}", bad.join("\n"));
}

/// The scan itself: slugs as GitHub makes them, links found, a missing file and a
/// missing heading caught.
#[test]
fn the_link_scan_reads_links_and_headings() {
    assert_eq!(
        slug(" The adaptive hybrid (`hybrid_policy`)"),
        "the-adaptive-hybrid-hybrid_policy"
    );
    assert_eq!(slug("Where the time goes"), "where-the-time-goes");
    let text = "# A page\n```\n# not a heading\n```\nSee [x](docs/a.md#a-page), [y](#b), [z](https://e.org).";
    assert_eq!(links(text), ["docs/a.md#a-page", "#b", "https://e.org"]);
    assert_eq!(anchors(text), BTreeSet::from(["a-page".to_string()]));
}
