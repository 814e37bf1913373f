//! REPRODUCTION.md's numbers in bold against the saved runs that gave them: every number in
//! bold in sections 1-8 must be, at the precision it is quoted with, a number of the saved
//! output of the run its section names (sections 1-6: the full `figures` set's
//! `summary.txt`, which `sim-host/cli/tests/integration/figures.rs` regenerates; 7: the
//! `figures dem` run's `summary.json` and `dem_runs.csv`; 8: the optimiser's searches'
//! summaries, heights also in mm; 7b: the small-preset LAMMPS run's
//! `summary.json`, the sidewall seeds' 3-D summaries and the sidewall table, which
//! `sim-host/lammps/tests/integration/reproduction.rs` checks against all their files). Bold
//! verdicts (`**... — reproduced**`) are words, not numbers. Each section has its own pool of
//! numbers, but a pool is a pool: a number its run did give under another name passes (the
//! check catches a mistyped or stale number, not one quoted for the wrong quantity).
//! A number quoted that its run did not give fails here, so the prose cannot drift from the
//! runs; regenerating a run means replacing its saved files and the prose together.

use std::path::Path;

fn root() -> &'static Path {
    Path::new(env!("CARGO_MANIFEST_DIR"))
}

fn read(rel: &str) -> String {
    std::fs::read_to_string(root().join(rel)).unwrap_or_else(|e| panic!("{rel}: {e}"))
}

/// Every number written in `text` (words such as `1.534`, `-0.02`, `8.18`, `2.5e-3`).
fn numbers_in_text(text: &str) -> Vec<f64> {
    text.split(|c: char| !(c.is_ascii_digit() || matches!(c, '.' | '-' | '+' | 'e' | 'E')))
        .filter_map(|w| w.trim_matches(['.', '+']).parse::<f64>().ok())
        .filter(|v| v.is_finite())
        .collect()
}

/// Every number of a JSON document, at any depth.
fn numbers_in_json(v: &serde_json::Value, out: &mut Vec<f64>) {
    match v {
        serde_json::Value::Number(n) => out.extend(n.as_f64()),
        serde_json::Value::Array(a) => a.iter().for_each(|x| numbers_in_json(x, out)),
        serde_json::Value::Object(m) => m.values().for_each(|x| numbers_in_json(x, out)),
        _ => {}
    }
}

fn json_numbers(rel: &str) -> Vec<f64> {
    let v: serde_json::Value =
        serde_json::from_str(&read(rel)).unwrap_or_else(|e| panic!("{rel}: {e}"));
    let mut out = Vec::new();
    numbers_in_json(&v, &mut out);
    out
}

/// The sections of REPRODUCTION.md by their number (`1.` ... `7b.`), with their text.
fn sections() -> Vec<(String, String)> {
    read("REPRODUCTION.md")
        .split("\n## ")
        .skip(1)
        .map(|s| {
            let number = s.split_whitespace().next().unwrap_or("").to_string();
            (number, s.to_string())
        })
        .collect()
}

/// The numbers quoted in bold in `section`, each as written and whether a `%` follows it;
/// verdicts in bold (with ` — `) are skipped.
fn bold_numbers(section: &str) -> Vec<(String, bool)> {
    let mut out = Vec::new();
    for (k, span) in section.split("**").enumerate() {
        if k % 2 == 0 || span.contains(" — ") || span.contains('\n') && span.len() > 200 {
            continue;
        }
        let chars: Vec<char> = span.chars().collect();
        let mut i = 0;
        while i < chars.len() {
            let starts = chars[i].is_ascii_digit()
                && (i == 0 || !(chars[i - 1].is_alphanumeric() || chars[i - 1] == '.'));
            if !starts {
                i += 1;
                continue;
            }
            let mut j = i;
            while j < chars.len()
                && (chars[j].is_ascii_digit()
                    || chars[j] == '.' && chars.get(j + 1).is_some_and(char::is_ascii_digit))
            {
                j += 1;
            }
            let word: String = chars[i..j].iter().collect();
            let percent = chars[j..]
                .iter()
                .collect::<String>()
                .trim_start()
                .starts_with('%');
            // `m_f`, `Hz`, `degrees` and `%` may follow; a letter glued on (`4a`) is a name.
            if !chars.get(j).is_some_and(|c| c.is_alphabetic()) {
                out.push((word, percent));
            }
            i = j;
        }
    }
    out
}

/// Whether `quoted` (as written, with its decimals) is one of `values` at that precision; a
/// percentage (`percent`: `%` follows it) is 100 times one of them.
fn given(quoted: &str, percent: bool, values: &[f64]) -> bool {
    let decimals = quoted.split_once('.').map_or(0, |(_, d)| d.len());
    let shown = |v: f64| format!("{v:.decimals$}") == quoted;
    values
        .iter()
        .any(|&v| if percent { shown(100.0 * v) } else { shown(v) })
}

/// Check the bold numbers of the sections `numbers` against `values`; returns how many.
fn check(numbers: &[&str], values: &[f64], source: &str) -> usize {
    let mut checked = 0;
    for (number, text) in sections() {
        if !numbers.contains(&number.as_str()) {
            continue;
        }
        for (q, percent) in bold_numbers(&text) {
            assert!(
                given(&q, percent, values),
                "REPRODUCTION.md section {number} quotes **{q}{}** in bold, which is not in \
                 {source}",
                if percent { " %" } else { "" }
            );
            checked += 1;
        }
    }
    checked
}

#[test]
fn the_bold_numbers_are_the_saved_runs_numbers() {
    // Sections 1-6: the full figures set's summary.
    let figures = numbers_in_text(&read("docs/reproduction/figures-summary.txt"));
    let n = check(
        &["1.", "2.", "3.", "4.", "5.", "6."],
        &figures,
        "docs/reproduction/figures-summary.txt",
    );
    assert!(n >= 5, "{n} bold numbers in sections 1-6");
    // Section 7: the figures dem run.
    let mut dem = json_numbers("docs/reproduction/figures-dem/summary.json");
    dem.extend(numbers_in_text(&read(
        "docs/reproduction/figures-dem/dem_runs.csv",
    )));
    let n = check(&["7."], &dem, "docs/reproduction/figures-dem/");
    assert!(n >= 10, "{n} bold numbers in section 7");
    // Section 7b: the small preset's LAMMPS run and the sidewall seeds.
    let mut lammps = json_numbers("docs/reproduction/lammps-small/summary.json");
    for seed in 1..=3 {
        lammps.extend(json_numbers(&format!(
            "docs/reproduction/sidewall-regime/seed-{seed}.summary.json"
        )));
    }
    // The sidewall table's cells (each recomputed from those seeds' files by
    // sim-host/lammps/tests/integration/reproduction.rs), for the prose that quotes its means.
    let text = read("REPRODUCTION.md");
    let table = text
        .split("<!-- BEGIN sidewall_table.sh -->")
        .nth(1)
        .and_then(|b| b.split("<!-- END sidewall_table.sh -->").next())
        .expect("the sidewall table's block");
    lammps.extend(numbers_in_text(
        &table
            .lines()
            .filter(|l| l.starts_with('|'))
            .collect::<Vec<_>>()
            .join("\n"),
    ));
    let n = check(
        &["7b."],
        &lammps,
        "docs/reproduction/lammps-small/, sidewall-regime/ or the sidewall table",
    );
    assert!(n >= 3, "{n} bold numbers in section 7b");
    // Section 8: the optimiser's answers (each search's `optimize --json` summary, kept by
    // sim-host/optimize/benches/optimize_results.sh's run), heights also in mm.
    let mut optimize = Vec::new();
    let dir = root().join("docs/reproduction/optimize");
    let mut files: Vec<_> = std::fs::read_dir(&dir)
        .unwrap_or_else(|e| panic!("{}: {e}", dir.display()))
        .map(|e| e.unwrap().path())
        .filter(|p| p.extension().is_some_and(|x| x == "json"))
        .collect();
    files.sort();
    assert!(files.len() >= 10, "{files:?}");
    for f in &files {
        let rel = f
            .strip_prefix(root())
            .unwrap()
            .to_str()
            .unwrap()
            .to_string();
        let values = json_numbers(&rel);
        optimize.extend(values.iter().map(|v| 1e3 * v));
        optimize.extend(values);
    }
    let n = check(&["8."], &optimize, "docs/reproduction/optimize/");
    assert!(n >= 3, "{n} bold numbers in section 8");
}

#[test]
fn a_number_its_run_did_not_give_is_caught() {
    let values = [1.534, 0.9799, 79.38, 8.18, 0.53];
    assert!(given("0.98", false, &values));
    assert!(given("79", false, &values));
    assert!(given("53", true, &values));
    assert!(!given("53", false, &values));
    assert!(!given("154", true, &values));
    assert!(!given("0.97", false, &values));
    assert!(!given("8.2", false, &values[..3]));
    let spans = bold_numbers(
        "a **1.29, 1.27 and 1.45** b **Added mass — partly reproduced** c **4.04 m_f** d \
         **(Fig. 4a inset)** e **53 % higher at 0.57**",
    );
    let words: Vec<&str> = spans.iter().map(|(w, _)| w.as_str()).collect();
    assert_eq!(words, ["1.29", "1.27", "1.45", "4.04", "53", "0.57"]);
    assert!(spans[4].1 && !spans[5].1);
}
