//! The documentation holds together: every relative link in `README.md`, `REPRODUCTION.md`
//! and `docs/` points at a file that exists (and, with `#anchor`, at a heading of that file);
//! the README fits on a screen (at most 10,000 characters) and opens with its two commands.

use std::path::{Path, PathBuf};

fn root() -> &'static Path {
    Path::new(env!("CARGO_MANIFEST_DIR"))
}

fn documents() -> Vec<PathBuf> {
    let mut docs = vec![root().join("README.md"), root().join("REPRODUCTION.md")];
    let mut more: Vec<PathBuf> = std::fs::read_dir(root().join("docs"))
        .expect("docs/ exists")
        .map(|e| e.expect("docs entry").path())
        .filter(|p| p.extension().is_some_and(|e| e == "md"))
        .collect();
    more.sort();
    docs.extend(more);
    docs
}

/// Targets of Markdown links `[text](target)` outside code blocks and code spans.
fn link_targets(text: &str) -> Vec<String> {
    let mut targets = Vec::new();
    let mut in_code_block = false;
    for line in text.lines() {
        if line.trim_start().starts_with("```") {
            in_code_block = !in_code_block;
            continue;
        }
        if in_code_block {
            continue;
        }
        // Drop code spans: a link inside backticks is an example, not a link.
        let mut plain = String::new();
        for (i, part) in line.split('`').enumerate() {
            if i % 2 == 0 {
                plain.push_str(part);
            }
        }
        let mut rest = plain.as_str();
        while let Some(i) = rest.find("](") {
            let after = &rest[i + 2..];
            match after.find(')') {
                Some(j) => {
                    targets.push(after[..j].to_string());
                    rest = &after[j + 1..];
                }
                None => break,
            }
        }
    }
    targets
}

/// GitHub's anchor of a heading: lower case, spaces to hyphens, punctuation dropped.
fn slug(heading: &str) -> String {
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

fn anchors(text: &str) -> Vec<String> {
    let mut in_code_block = false;
    let mut out = Vec::new();
    for line in text.lines() {
        if line.trim_start().starts_with("```") {
            in_code_block = !in_code_block;
        } else if !in_code_block && line.starts_with('#') {
            out.push(slug(line.trim_start_matches('#')));
        }
    }
    out
}

/// What is wrong with `target` as a link from `doc`, if anything.
fn broken(doc: &Path, target: &str) -> Option<String> {
    if target.contains("://") || target.starts_with("mailto:") {
        return None;
    }
    let (path, anchor) = match target.split_once('#') {
        Some((p, a)) => (p, Some(a)),
        None => (target, None),
    };
    let file = if path.is_empty() {
        doc.to_path_buf()
    } else {
        doc.parent().expect("a folder").join(path)
    };
    if !file.exists() {
        return Some(format!("`{target}`: {} does not exist", file.display()));
    }
    if let Some(anchor) = anchor {
        let text = std::fs::read_to_string(&file).unwrap_or_default();
        if !anchors(&text).iter().any(|a| a == anchor) {
            return Some(format!(
                "`{target}`: no heading `#{anchor}` in {}",
                file.display()
            ));
        }
    }
    None
}

#[test]
fn every_relative_link_points_somewhere() {
    let mut problems = Vec::new();
    let mut checked = 0;
    for doc in documents() {
        let text = std::fs::read_to_string(&doc).expect("readable");
        for target in link_targets(&text) {
            checked += 1;
            if let Some(p) = broken(&doc, &target) {
                problems.push(format!("{}: {p}", doc.display()));
            }
        }
    }
    assert!(
        checked > 10,
        "only {checked} links found: is the scanner broken?"
    );
    assert!(
        problems.is_empty(),
        "broken links:\n{}",
        problems.join("\n")
    );
}

#[test]
fn the_checker_catches_a_broken_link_and_a_missing_anchor() {
    let readme = root().join("README.md");
    assert!(broken(&readme, "docs/no-such-page.md").is_some());
    assert!(broken(&readme, "docs/hil.md#no-such-heading").is_some());
    assert!(broken(&readme, "docs/hil.md#rig-tool").is_none());
    assert_eq!(
        link_targets("see [a](x.md) and `[b](y.md)`\n```\n[c](z.md)\n```"),
        vec!["x.md"]
    );
}

#[test]
fn the_readme_fits_on_a_screen_and_opens_with_its_two_commands() {
    let text = std::fs::read_to_string(root().join("README.md")).expect("README");
    assert!(
        text.chars().count() <= 10_000,
        "README is {} characters",
        text.chars().count()
    );
    let block = text
        .split("```sh")
        .nth(1)
        .and_then(|b| b.split("```").next())
        .expect("a first sh block");
    let commands: Vec<&str> = block
        .lines()
        .map(str::trim)
        .filter(|l| !l.is_empty() && !l.starts_with('#'))
        .collect();
    assert_eq!(commands.len(), 2, "{commands:?}");
    assert!(commands[0].contains(" jump ") && commands[0].contains("--out"));
    // The test command: nextest runs the test binaries side by side (.config/nextest.toml),
    // `cargo test --doc` the doc tests nextest does not run; CI runs it word for word.
    assert_eq!(
        commands[1],
        "cargo nextest run --workspace && cargo test --workspace --doc"
    );
    // In a subshell there, so that `set -e` also stops at a failure of the first half.
    let ci = std::fs::read_to_string(root().join(".ci/run")).expect(".ci/run");
    let in_ci = format!("( {} )", commands[1]);
    assert!(
        ci.lines().any(|l| l.trim() == in_ci),
        ".ci/run does not run the README's test command: `{in_ci}`"
    );
}
