//! The `sandjumper` binary refuses every kind of bad input with exit status 2, one message
//! naming the culprit, no panic, and nothing written.

use std::path::Path;

use crate::common;
use common::{refused, sandjumper};

fn write(dir: &Path, name: &str, text: &str) -> String {
    let p = dir.join(name);
    std::fs::write(&p, text).unwrap();
    p.to_str().unwrap().to_string()
}

#[test]
fn unknown_model() {
    let e = refused(
        &["jump", "--kind", "single", "--freq", "10", "--model", "eq9"],
        &["eq9", "--model"],
    );
    // The allowed names are listed.
    assert!(e.contains("eq1-linear") && e.contains("eq4"), "{e}");
    refused(
        &[
            "sweep",
            "--kind",
            "single",
            "--freq",
            "10",
            "--model",
            "eq4,granite",
            "--out",
            "x",
        ],
        &["granite"],
    );
}

#[test]
fn unknown_kind() {
    refused(
        &["jump", "--kind", "hop", "--freq", "10"],
        &["hop", "--kind"],
    );
}

#[test]
fn non_positive_frequency() {
    refused(
        &["jump", "--kind", "single", "--freq", "0"],
        &["--freq", "0 Hz", "positive"],
    );
    refused(
        &["jump", "--kind", "single", "--freq", "-3"],
        &["--freq", "-3 Hz", "not positive"],
    );
    refused(
        &["jump", "--kind", "single", "--freq", "fast"],
        &["--freq", "fast"],
    );
    refused(
        &["jump", "--kind", "single", "--freq", "400"],
        &["--freq", "400", "40"],
    );
    refused(
        &[
            "sweep", "--kind", "single", "--freq", "-1:5:1", "--out", "x",
        ],
        &["--freq", "-1:5:1", "not positive"],
    );
}

#[test]
fn negative_tau() {
    refused(
        &["jump", "--kind", "delayed", "--freq", "10", "--tau", "-0.1"],
        &["--tau", "-0.1", "negative"],
    );
    refused(
        &[
            "sweep",
            "--kind",
            "delayed",
            "--freq",
            "10",
            "--tau",
            "-0.5:0.5:0.25",
            "--out",
            "x",
        ],
        &["--tau", "-0.5", "negative"],
    );
}

#[test]
fn delayed_stutter_needs_its_delay() {
    refused(&["jump", "--kind", "delayed", "--freq", "10"], &["--tau"]);
}

#[test]
fn phi_outside_presets_without_params_file() {
    refused(
        &["jump", "--kind", "single", "--freq", "10", "--phi", "0.5"],
        &["--phi 0.5", "0.57", "0.62"],
    );
    refused(&["params", "--phi", "0.65"], &["--phi 0.65"]);
    refused(
        &["params", "--phi", "1.5"],
        &["--phi", "1.5", "not a fraction"],
    );
    refused(
        &["params", "--phi", "-0.6"],
        &["--phi", "-0.6", "not a fraction"],
    );
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("out");
    refused(
        &[
            "sweep",
            "--kind",
            "single",
            "--freq",
            "10",
            "--phi",
            "0.55:0.6:0.05",
            "--out",
            out.to_str().unwrap(),
        ],
        &["--phi 0.55"],
    );
    assert!(!out.exists());
    // A params file without sand values does not make an unknown phi acceptable.
    let f = write(dir.path(), "robot.toml", "[robot]\nfoot_mass_kg = 0.03\n");
    refused(
        &["params", "--phi", "0.5", "--params", &f],
        &["--phi 0.5", "[sand]"],
    );
}

#[test]
fn unreadable_params_file() {
    refused(
        &["params", "--params", "/nonexistent/dir/p.toml"],
        &["/nonexistent/dir/p.toml"],
    );
    refused(
        &[
            "jump",
            "--kind",
            "single",
            "--freq",
            "10",
            "--params",
            "/nonexistent/p.toml",
        ],
        &["/nonexistent/p.toml"],
    );
}

#[test]
fn ill_typed_toml_names_key_and_line() {
    let dir = tempfile::tempdir().unwrap();
    let f = write(
        dir.path(),
        "typed.toml",
        "# my robot\n[robot]\nmotor_mass_kg = \"heavy\"\n",
    );
    refused(
        &["params", "--params", &f],
        &["typed.toml", "motor_mass_kg", ":3"],
    );
    let f = write(dir.path(), "syntax.toml", "[robot]\nfoot_mass_kg = = 1\n");
    refused(&["params", "--params", &f], &["syntax.toml", ":2"]);
    let f = write(dir.path(), "unknown.toml", "[robot]\nfoot_mas_kg = 0.03\n");
    refused(&["params", "--params", &f], &["foot_mas_kg", ":2"]);
}

#[test]
fn negative_mass_or_stiffness() {
    let dir = tempfile::tempdir().unwrap();
    let f = write(dir.path(), "mass.toml", "[robot]\nfoot_mass_kg = -0.03\n");
    refused(
        &["jump", "--kind", "single", "--freq", "10", "--params", &f],
        &["robot.foot_mass_kg", ":2"],
    );
    let f = write(
        dir.path(),
        "stiff.toml",
        "[robot]\n\n[sand]\nk1_n_m = -1600.0\n",
    );
    refused(&["params", "--params", &f], &["sand.k1_n_m", ":4"]);
    let f = write(
        dir.path(),
        "spring.toml",
        "[robot]\nspring_stiffness_n_m = -3300\n",
    );
    refused(&["params", "--params", &f], &["robot.spring_stiffness_n_m"]);
}

#[test]
fn bad_ranges() {
    for (spec, culprit) in [
        ("5:10:0", "positive"),
        ("5:10:-1", "positive"),
        ("10:5:1", "below its start"),
        ("5:10", "A:B:STEP"),
        ("5:x:1", "`x`"),
    ] {
        let e = refused(
            &[
                "sweep", "--kind", "single", "--freq", spec, "--out", "never",
            ],
            &["--freq", spec],
        );
        assert!(e.contains(culprit), "{spec}: {e}");
    }
    refused(
        &[
            "sweep",
            "--kind",
            "single",
            "--freq",
            "10",
            "--phi",
            "0.57:0.62:0",
            "--out",
            "never",
        ],
        &["--phi", "0.57:0.62:0"],
    );
    assert!(!Path::new("never").exists());
}

#[test]
fn bad_shard_specs() {
    for spec in ["0/4", "5/4", "1/0", "2", "a/4", "1/4/4"] {
        let e = refused(
            &[
                "sweep", "--kind", "single", "--freq", "10", "--out", "never", "--shard", spec,
            ],
            &["--shard", spec],
        );
        assert!(e.contains("1-based"), "{e}");
    }
}

#[test]
fn unwritable_output_directory() {
    let dir = tempfile::tempdir().unwrap();
    // Below a regular file: cannot be created (this holds even for root).
    let file = write(dir.path(), "a-file", "");
    let out = format!("{file}/run");
    refused(
        &[
            "jump", "--kind", "single", "--freq", "10", "--model", "hard", "--out", &out,
        ],
        &[&out],
    );
    refused(
        &[
            "sweep", "--kind", "single", "--freq", "10", "--model", "hard", "--out", &out,
        ],
        &["a-file"],
    );
    // The output path is an existing file.
    refused(
        &[
            "jump", "--kind", "single", "--freq", "10", "--model", "hard", "--out", &file,
        ],
        &["a-file", "not a directory"],
    );
    // A directory with someone else's files is never replaced.
    let foreign = dir.path().join("thesis");
    std::fs::create_dir(&foreign).unwrap();
    write(&foreign, "chapter1.tex", "precious");
    refused(
        &[
            "jump",
            "--kind",
            "single",
            "--freq",
            "10",
            "--model",
            "hard",
            "--out",
            foreign.to_str().unwrap(),
        ],
        &["thesis", "not empty"],
    );
    assert_eq!(
        std::fs::read_to_string(foreign.join("chapter1.tex")).unwrap(),
        "precious"
    );
    // Nothing else appeared: no staging directories left behind.
    let names: Vec<_> = std::fs::read_dir(dir.path())
        .unwrap()
        .map(|e| e.unwrap().file_name().into_string().unwrap())
        .collect();
    let mut names = names;
    names.sort();
    assert_eq!(names, vec!["a-file", "thesis"]);
}

#[test]
fn merge_of_non_sweep_directories() {
    let dir = tempfile::tempdir().unwrap();
    let empty = dir.path().join("empty");
    std::fs::create_dir(&empty).unwrap();
    let out = dir.path().join("merged");
    refused(
        &[
            "merge",
            empty.to_str().unwrap(),
            "--out",
            out.to_str().unwrap(),
        ],
        &["empty", "not a sweep directory"],
    );
    refused(&["merge", "--out", out.to_str().unwrap()], &["DIR"]);
    assert!(!out.exists());
}

#[test]
fn usage_errors_exit_2_and_help_exits_0() {
    refused(&[], &["Usage"]);
    refused(&["leap"], &["leap"]);
    refused(&["jump", "--freq", "10"], &["--kind"]);
    let help = sandjumper(&["--help"]);
    assert_eq!(help.status.code(), Some(0));
    let text = String::from_utf8_lossy(&help.stdout);
    for cmd in ["jump", "sweep", "merge", "params"] {
        assert!(text.contains(cmd), "{text}");
    }
}

#[test]
fn params_prints_resolved_toml_that_reads_back() {
    let out = sandjumper(&["params", "--phi", "0.585"]);
    assert_eq!(out.status.code(), Some(0));
    let text = String::from_utf8(out.stdout).unwrap();
    let table: toml::Table = text.parse().expect("params prints TOML");
    let sand = table["sand"].as_table().unwrap();
    assert_eq!(sand["packing_fraction"].as_float(), Some(0.585));
    // Halfway between the 0.58 and 0.59 rows: k1 = (2.0 + 2.5) / 2 kN/m.
    assert!((sand["k1_n_m"].as_float().unwrap() - 2250.0).abs() < 1e-6);
    // Reading the printout back as a params file gives the same parameters.
    let dir = tempfile::tempdir().unwrap();
    let f = write(dir.path(), "p.toml", &text);
    let again = sandjumper(&["params", "--phi", "0.585", "--params", &f]);
    assert_eq!(again.status.code(), Some(0));
    assert_eq!(String::from_utf8(again.stdout).unwrap(), text);
    // An override takes effect.
    let f = write(dir.path(), "o.toml", "[robot]\nfoot_mass_kg = 0.05\n");
    let o = sandjumper(&["params", "--params", &f]);
    let t: toml::Table = String::from_utf8(o.stdout).unwrap().parse().unwrap();
    assert_eq!(t["robot"]["foot_mass_kg"].as_float(), Some(0.05));
}

#[test]
fn phi_outside_presets_with_sand_values_is_accepted() {
    let dir = tempfile::tempdir().unwrap();
    let f = write(dir.path(), "s.toml", "[sand]\nk1_n_m = 1200.0\n");
    let o = sandjumper(&["params", "--phi", "0.55", "--params", &f]);
    assert_eq!(
        o.status.code(),
        Some(0),
        "{}",
        String::from_utf8_lossy(&o.stderr)
    );
    let t: toml::Table = String::from_utf8(o.stdout).unwrap().parse().unwrap();
    assert_eq!(t["sand"]["packing_fraction"].as_float(), Some(0.55));
    assert_eq!(t["sand"]["k1_n_m"].as_float(), Some(1200.0));
}
