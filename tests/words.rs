//! The repository's own words stand alone: no code, test, script or
//! document outside the CHANGELOG refers to an issue by number or to a
//! guide a reader of the repository does not have. (The CHANGELOG keeps
//! its history as it was written.)

use std::fs;
use std::path::{Path, PathBuf};

/// Folders and files read (from the repository root).
const ROOTS: &[&str] = &[
    "src",
    "tests",
    "benches",
    "docs",
    "boards",
    "python",
    "scripts",
    "fuzz/src",
    "fuzz/fuzz_targets",
    "fuzz/README.md",
    "fuzz/Cargo.toml",
    "README.md",
    "ARCHITECTURE.md",
    "Cargo.toml",
    ".ci",
];

/// Folders never read: build output, caches, generated corpora.
const SKIP: &[&str] = &[
    "target",
    "__pycache__",
    "corpus",
    "node_modules",
    ".pytest_cache",
];

fn walk(p: &Path, out: &mut Vec<PathBuf>) {
    if p.is_dir() {
        let name = p.file_name().and_then(|n| n.to_str()).unwrap_or("");
        if SKIP.contains(&name) || name.ends_with(".egg-info") {
            return;
        }
        let mut entries: Vec<_> = fs::read_dir(p).unwrap().flatten().collect();
        entries.sort_by_key(|e| e.path());
        for e in entries {
            walk(&e.path(), out);
        }
    } else if p.is_file() {
        out.push(p.to_path_buf());
    }
}

/// Where `text` names a tracker entry by its number (the word, an optional
/// plural `s`, a space or hyphen, a digit) or the developers' handbook by
/// its short name; the line numbers.
fn offending_lines(text: &str) -> Vec<usize> {
    // Spelled in pieces so this file does not match itself.
    let issue = ["iss", "ue "].concat();
    let guide = ["the ", "guide"].concat();
    let guides = ["guide", "'s"].concat();
    let mut bad = Vec::new();
    for (n, line) in text.lines().enumerate() {
        let l = line.to_lowercase();
        // The word, an optional plural, a space or a hyphen, then a digit.
        let numbered = l.match_indices(&issue[..5]).any(|(i, _)| {
            let rest = l[i + 5..].trim_start_matches('s');
            let rest = rest.strip_prefix([' ', '-']).unwrap_or("");
            rest.chars().next().is_some_and(|c| c.is_ascii_digit())
        });
        let guide_word = |w: &str| {
            l.match_indices(w).any(|(i, _)| {
                !l[i + w.len()..]
                    .chars()
                    .next()
                    .is_some_and(|c| c.is_alphanumeric())
            })
        };
        if numbered || guide_word(&guide) || guide_word(&guides) {
            bad.push(n + 1);
        }
    }
    bad
}

#[test]
fn no_issue_numbers_or_guide_references_outside_the_changelog() {
    let root = Path::new(env!("CARGO_MANIFEST_DIR"));
    let mut files = Vec::new();
    for r in ROOTS {
        walk(&root.join(r), &mut files);
    }
    assert!(files.len() > 100, "the walk found the repository");
    let mut found = Vec::new();
    for f in files {
        // This file spells what it looks for.
        if f.ends_with("tests/words.rs") {
            continue;
        }
        // Binary files (images, flash images) are not words.
        let Ok(text) = fs::read_to_string(&f) else {
            continue;
        };
        for n in offending_lines(&text) {
            found.push(format!("{}:{n}", f.strip_prefix(root).unwrap().display()));
        }
    }
    assert!(
        found.is_empty(),
        "issue numbers or guide references at:\n{}",
        found.join("\n")
    );
}

#[test]
fn the_check_finds_what_it_looks_for() {
    let issue = ["Iss", "ue ", "22 item 2: a flood"].concat();
    assert_eq!(offending_lines(&issue), vec![1]);
    let plural = ["## After iss", "ues ", "17–22\nthe iss", "ue-", "16 main"].concat();
    assert_eq!(offending_lines(&plural), vec![1, 2]);
    let guide = ["ok\nwithin the ", "gui", "de's budget"].concat();
    assert_eq!(offending_lines(&guide), vec![2]);
    // Words that only look alike pass.
    assert!(offending_lines("the issue left a choice; guidelines; two issues remain").is_empty());
}
