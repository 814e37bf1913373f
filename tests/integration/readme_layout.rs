//! The README tells the truth about the layout: its crate table lists the workspace's members
//! as `cargo metadata` has them (name and path, no more, no fewer), its diagram names every
//! host crate's folder, and its sentence about the library crates holds of the code: no
//! library crate prints, and none depends on clap but through an opt-in `clap` feature (its
//! choice enums as `clap::ValueEnum` and requests as `clap::Args`, for the command line), off
//! by default.

use std::collections::BTreeSet;
use std::path::{Path, PathBuf};

fn root() -> &'static Path {
    Path::new(env!("CARGO_MANIFEST_DIR"))
}

/// The crates that are faces (they parse arguments or bind another language) or test
/// harnesses, not libraries.
const FACES: [&str; 4] = [
    "sandjumper-cli",
    "sandjumper-python",
    "sandjumper",
    "sandjumper-firmware",
];

/// (package name, its folder relative to the root, with a trailing `/`) of every member.
fn members() -> Vec<(String, String)> {
    let cargo = std::env::var("CARGO").unwrap_or_else(|_| "cargo".into());
    let out = std::process::Command::new(cargo)
        .args([
            "metadata",
            "--no-deps",
            "--format-version",
            "1",
            "--offline",
        ])
        .current_dir(root())
        .output()
        .expect("cargo metadata runs");
    assert!(
        out.status.success(),
        "cargo metadata failed: {}",
        String::from_utf8_lossy(&out.stderr)
    );
    let meta: serde_json::Value = serde_json::from_slice(&out.stdout).expect("metadata is JSON");
    let root = root().canonicalize().expect("root");
    let mut v: Vec<(String, String)> = meta["packages"]
        .as_array()
        .expect("packages")
        .iter()
        .map(|p| {
            let manifest = PathBuf::from(p["manifest_path"].as_str().expect("manifest_path"));
            let dir = manifest.parent().expect("manifest's folder").to_path_buf();
            let rel = dir.strip_prefix(&root).expect("a member under the root");
            let rel = if rel.as_os_str().is_empty() {
                "tests/".to_string()
            } else {
                format!("{}/", rel.display())
            };
            (p["name"].as_str().expect("name").to_string(), rel)
        })
        .collect();
    v.sort();
    v
}

fn readme() -> String {
    std::fs::read_to_string(root().join("README.md")).expect("README.md")
}

/// The rows of the README's crate table: `| `name` | `path/` | what |`.
fn table_rows(readme: &str) -> Vec<(String, String)> {
    let mut rows: Vec<(String, String)> = readme
        .lines()
        .filter_map(|l| {
            let cells: Vec<&str> = l.split('|').map(str::trim).collect();
            // "", name, path, what, ""
            if cells.len() < 5 {
                return None;
            }
            let name = cells[1].strip_prefix('`')?.strip_suffix('`')?;
            let path = cells[2].strip_prefix('`')?.strip_suffix('`')?;
            (name.starts_with("sandjumper") && path.ends_with('/'))
                .then(|| (name.to_string(), path.to_string()))
        })
        .collect();
    rows.sort();
    rows
}

#[test]
fn the_crate_table_lists_the_workspace_members_as_cargo_metadata_has_them() {
    let members = members();
    let rows = table_rows(&readme());
    let m: BTreeSet<_> = members.iter().collect();
    let r: BTreeSet<_> = rows.iter().collect();
    let missing: Vec<_> = m.difference(&r).collect();
    let extra: Vec<_> = r.difference(&m).collect();
    assert!(
        missing.is_empty() && extra.is_empty(),
        "README's crate table differs from `cargo metadata`: members missing from the table \
         {missing:?}; rows that are not members {extra:?}"
    );
}

#[test]
fn the_layout_diagram_names_every_host_crate() {
    let readme = readme();
    let diagram: String = readme
        .split("## Layout")
        .nth(1)
        .and_then(|s| s.split("```").nth(1))
        .expect("a diagram in a code block under ## Layout")
        .to_string();
    for (name, path) in members() {
        let Some(folder) = path.strip_prefix("sim-host/") else {
            continue;
        };
        assert!(
            diagram.contains(folder),
            "the README's layout diagram does not show {name} ({path})"
        );
    }
}

/// Source lines of `dir` outside `#[cfg(test)]` items (the project keeps its unit tests in a
/// `mod tests` at the end of a file).
fn non_test_lines(dir: &Path) -> Vec<(PathBuf, usize, String)> {
    let mut out = Vec::new();
    let mut stack = vec![dir.to_path_buf()];
    while let Some(d) = stack.pop() {
        for e in std::fs::read_dir(&d).expect("a source folder") {
            let p = e.expect("entry").path();
            if p.is_dir() {
                stack.push(p);
            } else if p.extension().is_some_and(|x| x == "rs") {
                let text = std::fs::read_to_string(&p).expect("source");
                for (i, line) in text.lines().enumerate() {
                    if line.trim_start().starts_with("#[cfg(test)]") {
                        break;
                    }
                    out.push((p.clone(), i + 1, line.to_string()));
                }
            }
        }
    }
    out
}

#[test]
fn library_crates_neither_parse_arguments_nor_print() {
    let root = root().canonicalize().expect("root");
    for (name, path) in members() {
        if FACES.contains(&name.as_str()) {
            continue;
        }
        let manifest = std::fs::read_to_string(root.join(&path).join("Cargo.toml")).expect("toml");
        let doc: toml::Table = manifest.parse().expect("Cargo.toml parses");
        if let Some(clap) = doc.get("dependencies").and_then(|d| d.get("clap")) {
            let optional = clap.get("optional").and_then(|o| o.as_bool()) == Some(true);
            let features = doc.get("features");
            // `dep:clap`, and the same feature of the crates whose types it uses.
            let gate: Option<Vec<String>> = features
                .and_then(|f| f.get("clap"))
                .and_then(|g| g.as_array())
                .map(|g| g.iter().map(|v| v.to_string()).collect());
            let gated = gate.as_ref().is_some_and(|g| {
                g.contains(&r#""dep:clap""#.to_string())
                    && g.iter()
                        .all(|e| e == r#""dep:clap""# || e.ends_with(r#"/clap""#))
            });
            let default_on = features
                .and_then(|f| f.get("default"))
                .is_some_and(|d| d.to_string().contains("clap"));
            assert!(
                optional && gated && !default_on,
                "{name} ({path}) depends on clap other than through an opt-in feature \
                 `clap = [\"dep:clap\", ...]` (off by default): argument parsing belongs to the \
                 command line"
            );
        }
        for (file, line_no, line) in non_test_lines(&root.join(&path).join("src")) {
            let code = line.split("//").next().unwrap_or("");
            for mac in ["eprintln!", "println!", "eprint!", "print!"] {
                assert!(
                    !code.contains(mac),
                    "{}:{line_no}: {name} prints (`{mac}`); a library returns what it has to \
                     say (its outcome, or a note through its Progress sink)",
                    file.display()
                );
            }
        }
    }
}
