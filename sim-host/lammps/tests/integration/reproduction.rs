//! REPRODUCTION.md's sidewall table against the runs that made it: every number of every
//! seed's row is recomputed from that seed's saved `summary.json` and `sidewall.csv`, and
//! its 2-D DEM's `summary.json` and `bed.toml`
//! (`docs/reproduction/sidewall-regime/`, written by `sim-host/lammps/benches/sidewall_table.sh`)
//! with the table's rules, and the mean and spread row from the seeds' rows. A number quoted
//! there that its run did not give fails here.

use std::path::Path;

fn root() -> std::path::PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("../..")
}

/// The tool's median: the upper middle of an even count.
fn median(mut v: Vec<f64>) -> f64 {
    v.sort_by(f64::total_cmp);
    v[v.len() / 2]
}

/// One seed's row as the table prints it, from its saved files.
fn row_of(seed: usize) -> Vec<String> {
    let dir = root().join("docs/reproduction/sidewall-regime");
    let summary: serde_json::Value = serde_json::from_str(
        &std::fs::read_to_string(dir.join(format!("seed-{seed}.summary.json"))).unwrap(),
    )
    .unwrap();
    let mut reader = csv::Reader::from_path(dir.join(format!("seed-{seed}.sidewall.csv"))).unwrap();
    let header = reader.headers().unwrap().clone();
    let col = |name: &str| header.iter().position(|h| h == name).unwrap();
    let (piv, exact, eq6) = (
        col("piv_added_mass_kg"),
        col("exact_added_mass_kg"),
        col("eq6_added_mass_kg"),
    );
    let pairs: Vec<[f64; 3]> = reader
        .records()
        .map(|r| {
            let r = r.unwrap();
            let v = |i: usize| r[i].parse::<f64>().unwrap_or(f64::NAN);
            [v(piv), v(exact), v(eq6)]
        })
        .filter(|p| p[0].is_finite() && p[1].is_finite())
        .collect();
    let over_eq6 = |i: usize| {
        median(
            pairs
                .iter()
                .filter(|p| p[2] > 0.0)
                .map(|p| p[i] / p[2])
                .collect(),
        )
    };
    let dem2d: serde_json::Value = serde_json::from_str(
        &std::fs::read_to_string(dir.join(format!("seed-{seed}.dem2d.summary.json"))).unwrap(),
    )
    .unwrap();
    let ratio = summary["sidewall_piv_vs_exact_median"].as_f64().unwrap();
    assert!((ratio - median(pairs.iter().map(|p| p[0] / p[1]).collect())).abs() < 1e-12);
    vec![
        seed.to_string(),
        format!(
            "{:.3}",
            summary["settled_packing_fraction"].as_f64().unwrap()
        ),
        format!("{:.1}", 1e3 * summary["max_depth_m"].as_f64().unwrap()),
        pairs.len().to_string(),
        format!("{:.2}", over_eq6(1)),
        format!("{:.2}", over_eq6(0)),
        format!("{ratio:.2}"),
        format!("{:.3}", dem2d_area_fraction(&dir, seed)),
        format!(
            "{:.2}",
            dem2d["summary"]["added_mass_vs_eq6_median"]
                .as_f64()
                .unwrap()
        ),
    ]
}

/// The settled area fraction of the 2-D DEM's bed of `seed` (its saved `bed.toml`).
fn dem2d_area_fraction(dir: &Path, seed: usize) -> f64 {
    let bed: toml::Value = toml::from_str(
        &std::fs::read_to_string(dir.join(format!("seed-{seed}.dem2d-bed.toml"))).unwrap(),
    )
    .unwrap();
    bed["report"]["area_fraction"].as_float().unwrap()
}

#[test]
fn the_sidewall_table_is_its_runs() {
    let text = std::fs::read_to_string(root().join("REPRODUCTION.md")).unwrap();
    let block = text
        .split("<!-- BEGIN sidewall_table.sh -->")
        .nth(1)
        .and_then(|b| b.split("<!-- END sidewall_table.sh -->").next())
        .expect("REPRODUCTION.md has the sidewall table's block");
    assert!(block.contains("Made by `sim-host/lammps/benches/sidewall_table.sh 3 regime`"));
    let rows: Vec<Vec<String>> = block
        .lines()
        .filter(|l| l.starts_with("| ") && !l.starts_with("| seed"))
        .map(|l| {
            l.trim_matches('|')
                .split('|')
                .map(|c| c.trim().to_string())
                .collect()
        })
        .collect();
    let seeds: Vec<&Vec<String>> = rows
        .iter()
        .filter(|r| r[0].parse::<usize>().is_ok())
        .collect();
    assert_eq!(seeds.len(), 3, "{block}");
    let mut computed = Vec::new();
    for r in &seeds {
        let expected = row_of(r[0].parse().unwrap());
        assert_eq!(**r, expected, "seed {}: quoted against its run", r[0]);
        computed.push(expected);
    }
    // The mean (min..max) row, from the seeds' rows.
    let mean = rows
        .iter()
        .find(|r| r[0].starts_with("mean"))
        .expect("a mean row");
    for (column, quoted) in [(4, &mean[4]), (5, &mean[5]), (6, &mean[6]), (8, &mean[8])] {
        let v: Vec<f64> = computed
            .iter()
            .map(|r| r[column].parse().unwrap())
            .collect();
        let (lo, hi) = (
            v.iter().copied().fold(f64::MAX, f64::min),
            v.iter().copied().fold(f64::MIN, f64::max),
        );
        let m = v.iter().sum::<f64>() / v.len() as f64;
        // The script averages the unrounded seeds' values: within a rounding of the rounded.
        let (qm, qrange) = quoted.split_once(' ').unwrap();
        assert!(
            (qm.parse::<f64>().unwrap() - m).abs() <= 0.011,
            "{quoted} against {m}"
        );
        assert_eq!(qrange, format!("({lo:.2}..{hi:.2})"), "column {column}");
    }
}
