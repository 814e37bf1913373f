//! `sandjumper figures dem`: Supplementary I and Extended Data Fig. 2 from the project's own
//! runs. The push-off episodes of the three jumps (single, stutter, delayed stutter) driven
//! into a free, gravity-free bidisperse bed at area fraction 0.70 with the paper's model
//! (forward Euler, per-grain drag), full scale (76 mm foot, 1.0/1.4 mm grains, the bed four
//! foot widths wide and 1.6 deep); PIV run on the stutter's rendered side-wall frames; the
//! near-jammed 0.80 bed and the full model (gravity, friction, walls) as sensitivity rows.
//! Every run keeps its own folder under `runs/`; the comparison is written beside them.

use std::path::{Path, PathBuf};
use std::time::Instant;

use clap::Args;
use serde::Serialize;

use crate::command::args::parse_number;
use sandjumper_output::plot::lines::{Line, LineFigure, LinePanel};
use sandjumper_output::plot::{palette, save_figure};
use sandjumper_output::{CliError, StagedDir, write_csv};

/// `sandjumper figures dem`.
#[derive(Debug, Clone, Args)]
pub struct DemFiguresArgs {
    /// Output directory (created, or replaced if it holds an earlier sandjumper output).
    #[arg(long, value_name = "DIR")]
    pub out: PathBuf,
    /// Packing fraction of the jumps whose push-offs drive the DEM (eq. 4 model), and the
    /// bulk phi of eq. 6.
    #[arg(long, value_name = "PHI", default_value = "0.57", value_parser = crate::command::args::parse_phi)]
    pub phi: f64,
    /// Forcing frequency of the three jumps, Hz.
    #[arg(long, value_name = "HZ", default_value = "10", value_parser = parse_number)]
    pub freq: f64,
    /// Delay of the delayed stutter, s.
    #[arg(long, value_name = "S", default_value = "0.1", value_parser = parse_number)]
    pub tau: f64,
    /// Foot width, m (the robot's 76 mm; the bed is 4 widths wide and 1.6 deep).
    #[arg(long, value_name = "M", default_value = "0.076", value_parser = parse_number)]
    pub foot_width: f64,
    /// Leave out the full model's row (its bed settles under gravity: about 7 of the 10
    /// minutes at full scale).
    #[arg(long)]
    pub no_full_model: bool,
    /// Threads (0: all cores).
    #[arg(long, default_value = "0")]
    pub threads: usize,
}

/// One DEM run of the comparison.
#[derive(Clone, Debug, Serialize)]
struct Row {
    /// Its folder under `runs/`.
    name: String,
    /// What it is.
    what: String,
    /// DEM added mass over eq. 6 (C scaled with R^2), median over the samples with the foot
    /// at >= 0.3 of its fastest.
    added_mass_vs_eq6_median: f64,
    /// Peak momentum of the column under the foot, kg m/s.
    grain_momentum_under_foot_kg_m_s: f64,
    /// Peak force on the foot, N.
    max_force_n: f64,
    /// Depth reached, m.
    max_depth_m: f64,
    /// Angle of the shear bands' cone, degrees (NaN: no cone: a side does not narrow, or the
    /// sides differ by more than 10 degrees).
    shear_band_cone_deg: f64,
    /// The left side's angle, degrees (NaN: it does not narrow).
    shear_band_left_deg: f64,
    /// The right side's angle, degrees.
    shear_band_right_deg: f64,
    /// Depth below the foot where the fitted sides meet, m.
    shear_band_apex_m: f64,
    /// Rows (2 mm each) below the foot with clear bands.
    shear_band_rows: usize,
    /// Angle of the co-moving region's cone (down speed half the foot's), degrees (NaN:
    /// none, or the sides differ by more than 10 degrees).
    comoving_cone_deg: f64,
    /// Its left side's angle, degrees.
    comoving_left_deg: f64,
    /// Its right side's angle, degrees.
    comoving_right_deg: f64,
    /// Depth below the foot where its sides meet, m.
    comoving_apex_m: f64,
    /// Share of the column's momentum deeper than the 60 degree cone (median).
    momentum_beyond_cone_depth_share: f64,
    /// Share of the column's momentum in the coarse-graining window's bottom tenth.
    momentum_in_window_bottom_tenth_share: f64,
    /// The run's warning that its motion reaches the window's bottom, if it has one.
    window_depth_warning: Option<String>,
    /// Grains.
    grains: u64,
    /// Wall time, s.
    wall_s: f64,
}

/// The resolved parameters, written as `figures_dem.toml`.
#[derive(Serialize)]
struct Resolved<'a> {
    phi: f64,
    freq_hz: f64,
    tau_s: f64,
    foot_width_m: f64,
    bed_width_m: f64,
    bed_height_m: f64,
    area_fraction: f64,
    near_jammed_area_fraction: f64,
    full_model: bool,
    commands: &'a [String],
}

/// Run `figures dem`.
pub fn run(a: &DemFiguresArgs) -> Result<(), CliError> {
    if !(0.005..=0.2).contains(&a.foot_width) {
        return Err(CliError::input(format!(
            "--foot-width {} m (allowed: 0.005..=0.2)",
            a.foot_width
        )));
    }
    if !(0.5..=40.0).contains(&a.freq) || !(0.0..=1.0).contains(&a.tau) {
        return Err(CliError::input(format!(
            "--freq {} Hz, --tau {} s (allowed: 0.5..=40 Hz, as `jump` takes, and 0..=1 s)",
            a.freq, a.tau
        )));
    }
    let started = Instant::now();
    let staged = StagedDir::create(&a.out)?;
    let runs = staged.file("runs");
    std::fs::create_dir_all(&runs)
        .map_err(|e| CliError::internal(format!("cannot create {}: {e}", runs.display())))?;
    let w = a.foot_width;
    let path = |n: &str| runs.join(n).display().to_string();
    let threads = a.threads.to_string();
    let (phi, freq, tau, fw) = (
        a.phi.to_string(),
        a.freq.to_string(),
        a.tau.to_string(),
        w.to_string(),
    );
    let s = |v: &[&str]| v.iter().map(|x| x.to_string()).collect::<Vec<String>>();
    let total = if a.no_full_model { 10 } else { 12 };
    let mut done_commands = Vec::new();
    let mut wall = std::collections::BTreeMap::new();
    let mut stage = 0usize;
    let mut run_stage = |what: &str, cmd: &[String]| -> Result<(), CliError> {
        stage += 1;
        eprintln!(
            "figures dem [{stage}/{total}] {what} ({:.0} s so far)",
            started.elapsed().as_secs_f64()
        );
        let t0 = Instant::now();
        run_quietly(cmd)?;
        if let Some(out) = cmd.iter().position(|c| c == "--out") {
            wall.insert(cmd[out + 1].clone(), t0.elapsed().as_secs_f64());
        }
        done_commands.push(format!("sandjumper {}", cmd.join(" ")));
        Ok(())
    };
    // The jumps first: their depth sizes the bed.
    let mut deepest: f64 = 0.0;
    for kind in ["single", "stutter", "delayed"] {
        let mut c = s(&["jump", "--kind", kind, "--freq", &freq, "--phi", &phi]);
        if kind == "delayed" {
            c.extend(s(&["--tau", &tau]));
        }
        c.extend(s(&["--out", &path(&format!("jump-{kind}"))]));
        run_stage(&format!("the {kind} jump"), &c)?;
        let j = read_json(&runs.join(format!("jump-{kind}")).join("summary.json"))?;
        deepest = deepest.max(j["max_depth_m"].as_f64().unwrap_or(0.0));
    }
    // Four foot widths by 1.6, as the supplement's bed; deeper if the push-off and the cone
    // under it (R tan 60) would reach the bottom (a small foot's bed).
    let cone = 0.5 * w * 60f64.to_radians().tan();
    let (bed_w, bed_h) = (
        4.0 * w + 0.01,
        (1.6 * w + 0.003).max(deepest + cone + 0.005),
    );
    let (bw, bh) = (format!("{bed_w:.4}"), format!("{bed_h:.4}"));
    let mut plan: Vec<(String, Vec<String>)> = Vec::new();
    let bed = |name: &str, model: &str, pack: Option<&str>| {
        let mut c = s(&[
            "dem", "bed", "--model", model, "--width", &bw, "--height", &bh,
        ]);
        if let Some(p) = pack {
            c.extend(s(&["--pack", p]));
        }
        c.extend(s(&["--threads", &threads, "--out", &path(name)]));
        c
    };
    let intrude = |name: &str, bed: &str, kind: &str, model: &str| {
        s(&[
            "dem",
            "intrude",
            "--bed",
            &path(bed),
            "--trajectory",
            &format!("{}/trajectory.csv", path(&format!("jump-{kind}"))),
            "--episode",
            "push-off",
            "--foot-width",
            &fw,
            "--model",
            model,
            "--phi",
            &phi,
            "--threads",
            &threads,
            "--out",
            &path(name),
        ])
    };
    plan.push((
        "the bed at 0.70".into(),
        bed("bed-0.70", "paper", Some("0.70")),
    ));
    for kind in ["single", "stutter", "delayed"] {
        plan.push((
            format!("the {kind} push-off into it"),
            intrude(kind, "bed-0.70", kind, "paper"),
        ));
    }
    plan.push((
        "PIV on the stutter's side-wall frames".into(),
        Vec::new(), // built once the stutter's camera is known
    ));
    plan.push((
        "the near-jammed bed at 0.80".into(),
        bed("bed-0.80", "paper", Some("0.80")),
    ));
    plan.push((
        "the stutter into it".into(),
        intrude("stutter-0.80", "bed-0.80", "stutter", "paper"),
    ));
    if !a.no_full_model {
        plan.push((
            "the full model's bed, settled under gravity".into(),
            bed("bed-full", "full", None),
        ));
        plan.push((
            "the stutter into it (gravity, friction, walls)".into(),
            intrude("stutter-full", "bed-full", "stutter", "full"),
        ));
    }
    for (what, mut cmd) in plan {
        if cmd.is_empty() {
            cmd = piv_command(&runs.join("stutter"), &path("piv-stutter"))?;
        }
        run_stage(&what, &cmd)?;
    }
    // Every path the runs recorded names the staging folder, renamed to --out at the end:
    // recorded as the final paths, so the commands can be run again.
    let staging = staged.path().display().to_string();
    let final_out = a.out.display().to_string();
    for c in &mut done_commands {
        *c = c.replace(&staging, &final_out);
    }
    rewrite_paths(&runs, &staging, &final_out)?;
    // The comparison.
    let mut rows = Vec::new();
    let mut names = vec![
        ("single", "single jump's push-off, paper model, 0.70"),
        ("stutter", "stutter's push-off, paper model, 0.70"),
        ("delayed", "delayed stutter's push-off, paper model, 0.70"),
        (
            "stutter-0.80",
            "stutter's push-off, paper model, 0.80 (near jamming)",
        ),
    ];
    if !a.no_full_model {
        names.push((
            "stutter-full",
            "stutter's push-off, full model (gravity, friction 0.5, walls), settled bed",
        ));
    }
    for (name, what) in &names {
        rows.push(read_row(
            &runs.join(name),
            name,
            what,
            wall.get(&path(name)).copied().unwrap_or(f64::NAN),
        )?);
    }
    let piv = compare_piv(&runs.join("stutter"), &runs.join("piv-stutter"))?;
    write_csv(
        &staged.file("dem_runs.csv"),
        &rows,
        &[
            "name",
            "what",
            "added_mass_vs_eq6_median",
            "grain_momentum_under_foot_kg_m_s",
            "max_force_n",
            "max_depth_m",
            "shear_band_cone_deg",
            "shear_band_left_deg",
            "shear_band_right_deg",
            "shear_band_apex_m",
            "shear_band_rows",
            "comoving_cone_deg",
            "comoving_left_deg",
            "comoving_right_deg",
            "comoving_apex_m",
            "momentum_beyond_cone_depth_share",
            "momentum_in_window_bottom_tenth_share",
            "window_depth_warning",
            "grains",
            "wall_s",
        ],
    )
    .map_err(CliError::internal)?;
    write_csv(
        &staged.file("piv_vs_dem.csv"),
        &piv.points,
        &["t_s", "depth_m", "dem_added_mass_kg", "piv_added_mass_kg"],
    )
    .map_err(CliError::internal)?;
    let series = figures(&staged, &runs, a.phi, 0.5 * w, &rows, &piv)?;
    write_csv(
        &staged.file("momentum_vs_time.csv"),
        &series,
        &[
            "jump",
            "t_s",
            "depth_m",
            "momentum_under_foot_kg_m_s",
            "added_mass_kg",
        ],
    )
    .map_err(CliError::internal)?;
    let resolved = Resolved {
        phi: a.phi,
        freq_hz: a.freq,
        tau_s: a.tau,
        foot_width_m: w,
        bed_width_m: bed_w,
        bed_height_m: bed_h,
        area_fraction: 0.70,
        near_jammed_area_fraction: 0.80,
        full_model: !a.no_full_model,
        commands: &done_commands,
    };
    staged.write_text(
        "figures_dem.toml",
        &toml::to_string(&resolved).map_err(|e| CliError::internal(e.to_string()))?,
    )?;
    #[derive(Serialize)]
    struct Summary<'a> {
        runs: &'a [Row],
        /// Each push-off's peak momentum over the stutter's (the paper's relative scaling).
        momentum_peak_over_stutter: std::collections::BTreeMap<String, f64>,
        piv_over_dem_added_mass_median: f64,
        piv_pairs_compared: usize,
        wall_s: f64,
    }
    let summary = Summary {
        runs: &rows,
        momentum_peak_over_stutter: {
            let stutter = rows
                .iter()
                .find(|r| r.name == "stutter")
                .map_or(f64::NAN, |r| r.grain_momentum_under_foot_kg_m_s);
            rows.iter()
                .take(3)
                .map(|r| (r.name.clone(), r.grain_momentum_under_foot_kg_m_s / stutter))
                .collect()
        },
        piv_over_dem_added_mass_median: piv.ratio_median,
        piv_pairs_compared: piv.points.len(),
        wall_s: started.elapsed().as_secs_f64(),
    };
    staged.write_text(
        "summary.json",
        &serde_json::to_string_pretty(&summary).map_err(|e| CliError::internal(e.to_string()))?,
    )?;
    let dir = staged.commit()?;
    println!(
        "figures dem: wrote {} ({:.0} s)",
        dir.display(),
        started.elapsed().as_secs_f64()
    );
    for r in &rows {
        println!(
            "  {:<13} DEM/eq. 6 {:.2}, peak P under the foot {:.4} kg m/s, shear-band cone {}, co-moving cone {}",
            r.name,
            r.added_mass_vs_eq6_median,
            r.grain_momentum_under_foot_kg_m_s,
            if r.shear_band_cone_deg.is_finite() {
                format!(
                    "{:.0} deg ({} rows)",
                    r.shear_band_cone_deg, r.shear_band_rows
                )
            } else {
                format!("none (bands do not narrow over {} rows)", r.shear_band_rows)
            },
            if r.comoving_cone_deg.is_finite() {
                format!("{:.0} deg", r.comoving_cone_deg)
            } else if r.comoving_left_deg.is_finite() || r.comoving_right_deg.is_finite() {
                format!(
                    "none (sides {:.0} and {:.0} deg)",
                    r.comoving_left_deg, r.comoving_right_deg
                )
            } else {
                "none (the moving region does not narrow below the foot)".to_string()
            }
        );
    }
    println!(
        "  PIV on the stutter's frames / DEM added mass: median {:.3} over {} pairs",
        piv.ratio_median,
        piv.points.len()
    );
    Ok(())
}

/// Replace `from` by `to` in the JSON and TOML files of every run folder under `runs`.
fn rewrite_paths(runs: &Path, from: &str, to: &str) -> Result<(), CliError> {
    let io = |p: &Path, e: std::io::Error| CliError::internal(format!("{}: {e}", p.display()));
    for dir in std::fs::read_dir(runs).map_err(|e| io(runs, e))? {
        let dir = dir.map_err(|e| io(runs, e))?.path();
        if !dir.is_dir() {
            continue;
        }
        for f in std::fs::read_dir(&dir).map_err(|e| io(&dir, e))? {
            let f = f.map_err(|e| io(&dir, e))?.path();
            let ext = f.extension().and_then(|e| e.to_str()).unwrap_or("");
            if ext == "json" || ext == "toml" {
                let text = std::fs::read_to_string(&f).map_err(|e| io(&f, e))?;
                if text.contains(from) {
                    std::fs::write(&f, text.replace(from, to)).map_err(|e| io(&f, e))?;
                }
            }
        }
    }
    Ok(())
}

/// Run one `sandjumper` command in this process; its errors keep their exit status.
fn run_quietly(cmd: &[String]) -> Result<(), CliError> {
    let cli = <crate::cli::Cli as clap::Parser>::try_parse_from(
        std::iter::once("sandjumper".to_string()).chain(cmd.iter().cloned()),
    )
    .map_err(|e| CliError::input(format!("sandjumper {}: {e}", cmd.join(" "))))?;
    crate::cli::execute(cli).map_err(|e| CliError {
        message: format!("sandjumper {}: {}", cmd.join(" "), e.message),
        exit: e.exit,
    })
}

/// `sandjumper piv` on an intrusion's frames, as its camera.toml says.
fn piv_command(run: &Path, out: &str) -> Result<Vec<String>, CliError> {
    let text = std::fs::read_to_string(run.join("camera.toml"))
        .map_err(|e| CliError::internal(format!("{}/camera.toml: {e}", run.display())))?;
    let line = text
        .lines()
        .find_map(|l| l.strip_prefix("# sandjumper "))
        .ok_or_else(|| CliError::internal("camera.toml has no piv command line"))?;
    let mut cmd: Vec<String> = line.split_whitespace().map(str::to_string).collect();
    for c in cmd.iter_mut() {
        if c == "frames" {
            *c = run.join("frames").display().to_string();
        } else if c == "foot.csv" {
            *c = run.join("foot.csv").display().to_string();
        }
    }
    cmd.extend(["--out".to_string(), out.to_string()]);
    Ok(cmd)
}

fn read_json(path: &Path) -> Result<serde_json::Value, CliError> {
    let text = std::fs::read_to_string(path)
        .map_err(|e| CliError::internal(format!("{}: {e}", path.display())))?;
    serde_json::from_str(&text).map_err(|e| CliError::internal(format!("{}: {e}", path.display())))
}

fn read_row(dir: &Path, name: &str, what: &str, wall_s: f64) -> Result<Row, CliError> {
    let j = read_json(&dir.join("summary.json"))?;
    let s = &j["summary"];
    let f = |k: &str| s[k].as_f64().unwrap_or(f64::NAN);
    let cone = &s["shear_band_cone"];
    let moving = &s["comoving_cone"];
    Ok(Row {
        name: name.into(),
        what: what.into(),
        added_mass_vs_eq6_median: f("added_mass_vs_eq6_median"),
        grain_momentum_under_foot_kg_m_s: f("grain_momentum_under_foot_kg_m_s"),
        max_force_n: f("max_force_n"),
        max_depth_m: f("max_depth_m"),
        shear_band_cone_deg: cone["angle_deg"].as_f64().unwrap_or(f64::NAN),
        shear_band_left_deg: cone["left_deg"].as_f64().unwrap_or(f64::NAN),
        shear_band_right_deg: cone["right_deg"].as_f64().unwrap_or(f64::NAN),
        shear_band_apex_m: cone["apex_depth_m"].as_f64().unwrap_or(f64::NAN),
        shear_band_rows: cone["rows"].as_array().map_or(0, Vec::len),
        comoving_cone_deg: moving["angle_deg"].as_f64().unwrap_or(f64::NAN),
        comoving_left_deg: moving["left_deg"].as_f64().unwrap_or(f64::NAN),
        comoving_right_deg: moving["right_deg"].as_f64().unwrap_or(f64::NAN),
        comoving_apex_m: moving["apex_depth_m"].as_f64().unwrap_or(f64::NAN),
        momentum_beyond_cone_depth_share: f("momentum_beyond_cone_depth_share"),
        momentum_in_window_bottom_tenth_share: f("momentum_in_window_bottom_tenth_share"),
        window_depth_warning: s["window_depth_warning"].as_str().map(str::to_string),
        grains: s["grains"].as_u64().unwrap_or(0),
        wall_s,
    })
}

/// A CSV's rows as maps of column to number (text columns and empty cells: NaN).
type Table = Vec<std::collections::HashMap<String, f64>>;

/// A row's value of `key` (NaN when the column is missing).
fn val(row: &std::collections::HashMap<String, f64>, key: &str) -> f64 {
    row.get(key).copied().unwrap_or(f64::NAN)
}

fn read_table(path: &Path) -> Result<Table, CliError> {
    let mut r = csv::Reader::from_path(path)
        .map_err(|e| CliError::internal(format!("{}: {e}", path.display())))?;
    let head: Vec<String> = r
        .headers()
        .map_err(|e| CliError::internal(e.to_string()))?
        .iter()
        .map(str::to_string)
        .collect();
    let mut rows = Vec::new();
    for rec in r.records() {
        let rec = rec.map_err(|e| CliError::internal(format!("{}: {e}", path.display())))?;
        rows.push(
            head.iter()
                .zip(rec.iter())
                .map(|(h, v)| (h.clone(), v.parse::<f64>().unwrap_or(f64::NAN)))
                .collect(),
        );
    }
    Ok(rows)
}

/// PIV's added mass on the DEM's frames against the DEM's own at the pairs' times.
struct PivComparison {
    points: Vec<PivPoint>,
    ratio_median: f64,
}

#[derive(Serialize)]
struct PivPoint {
    t_s: f64,
    depth_m: f64,
    dem_added_mass_kg: f64,
    piv_added_mass_kg: f64,
}

fn compare_piv(dem: &Path, piv: &Path) -> Result<PivComparison, CliError> {
    let d = read_table(&dem.join("flow.csv"))?;
    let p = read_table(&piv.join("flow.csv"))?;
    let at = |t: f64, key: &str| {
        // Linear between the DEM's samples around t (a PIV pair sits between two frames).
        d.windows(2)
            .find(|w| val(&w[0], "t_s") <= t && t <= val(&w[1], "t_s"))
            .map_or(f64::NAN, |w| {
                let f = (t - val(&w[0], "t_s")) / (val(&w[1], "t_s") - val(&w[0], "t_s"));
                val(&w[0], key) + f * (val(&w[1], key) - val(&w[0], key))
            })
    };
    let points: Vec<PivPoint> = p
        .iter()
        .filter(|r| val(r, "added_mass_kg").is_finite())
        .map(|r| PivPoint {
            t_s: val(r, "t_s"),
            depth_m: at(val(r, "t_s"), "depth_m"),
            dem_added_mass_kg: at(val(r, "t_s"), "added_mass_kg"),
            piv_added_mass_kg: val(r, "added_mass_kg"),
        })
        .filter(|q| q.dem_added_mass_kg.is_finite())
        .collect();
    let mut ratios: Vec<f64> = points
        .iter()
        .map(|q| q.piv_added_mass_kg / q.dem_added_mass_kg)
        .collect();
    ratios.sort_by(f64::total_cmp);
    let ratio_median = ratios.get(ratios.len() / 2).copied().unwrap_or(f64::NAN);
    Ok(PivComparison {
        points,
        ratio_median,
    })
}

#[derive(Serialize)]
struct SeriesRow {
    jump: String,
    t_s: f64,
    depth_m: f64,
    momentum_under_foot_kg_m_s: f64,
    added_mass_kg: f64,
}

/// The figures: added mass against depth with eq. 6, momentum against time for the three
/// jumps, PIV against the DEM, the sensitivity rows. Returns the momentum series.
fn figures(
    staged: &StagedDir,
    runs: &Path,
    phi: f64,
    radius_m: f64,
    rows: &[Row],
    piv: &PivComparison,
) -> Result<Vec<SeriesRow>, CliError> {
    let mut series = Vec::new();
    let mut am_lines = Vec::new();
    let mut p_lines = Vec::new();
    let mut zmax: f64 = 1e-4;
    for (k, kind) in ["single", "stutter", "delayed"].iter().enumerate() {
        let t = read_table(&runs.join(kind).join("flow.csv"))?;
        for r in &t {
            series.push(SeriesRow {
                jump: kind.to_string(),
                t_s: val(r, "t_s"),
                depth_m: val(r, "depth_m"),
                momentum_under_foot_kg_m_s: val(r, "momentum_under_foot_kg_m_s"),
                added_mass_kg: val(r, "added_mass_kg"),
            });
        }
        let am: Vec<(f64, f64)> = t
            .iter()
            .filter(|r| val(r, "added_mass_kg").is_finite() && val(r, "depth_m") > 0.0)
            .map(|r| (1e3 * val(r, "depth_m"), val(r, "added_mass_kg")))
            .collect();
        zmax = am.iter().map(|p| p.0 / 1e3).fold(zmax, f64::max);
        am_lines.push(Line {
            label: format!("DEM, {kind}"),
            points: am,
            color: palette(k),
            dashed: false,
            markers: true,
        });
        p_lines.push(Line {
            label: kind.to_string(),
            points: t
                .iter()
                .map(|r| (1e3 * val(r, "t_s"), val(r, "momentum_under_foot_kg_m_s")))
                .collect(),
            color: palette(k),
            dashed: false,
            markers: true,
        });
    }
    // The paper's relative scaling (Fig. 4a inset): each jump's momentum over the stutter's
    // peak.
    let stutter_peak = series
        .iter()
        .filter(|r| r.jump == "stutter")
        .map(|r| r.momentum_under_foot_kg_m_s)
        .fold(f64::NAN, f64::max);
    let rel_lines: Vec<Line> = p_lines
        .iter()
        .map(|l| Line {
            points: l
                .points
                .iter()
                .map(|&(t, p)| (t, p / stutter_peak))
                .collect(),
            ..l.clone()
        })
        .collect();
    let eq6: Vec<(f64, f64)> = (0..=60)
        .filter_map(|i| {
            let z = zmax * f64::from(i) / 60.0;
            crate::dem::outputs::model_added_mass(phi, radius_m, z)
                .ok()
                .map(|m| (1e3 * z, m))
        })
        .collect();
    am_lines.push(Line {
        label: "eq. 6, C scaled by (R / 38 mm)^2".into(),
        points: eq6,
        color: palette(3),
        dashed: true,
        markers: false,
    });
    am_lines.push(Line {
        label: "PIV on the stutter's frames".into(),
        points: piv
            .points
            .iter()
            .map(|q| (1e3 * q.depth_m, q.piv_added_mass_kg))
            .collect(),
        color: palette(4),
        dashed: true,
        markers: true,
    });
    let fig = LineFigure {
        title: "DEM added mass (column under the foot, v >= 0.3 v_max) and eq. 6".into(),
        panels: vec![
            LinePanel {
                caption: format!("three push-offs, paper model, 0.70; phi {phi}"),
                x_desc: "depth (mm)".into(),
                y_desc: "added mass (kg)".into(),
                lines: am_lines,
                y_from_zero: true,
            },
            LinePanel {
                caption: "momentum under the foot".into(),
                x_desc: "time from the push-off's start (ms)".into(),
                y_desc: "P (kg m/s)".into(),
                lines: p_lines,
                y_from_zero: false,
            },
            LinePanel {
                caption: "relative to the stutter's peak (Fig. 4a inset)".into(),
                x_desc: "time from the push-off's start (ms)".into(),
                y_desc: "P / P_max(stutter)".into(),
                lines: rel_lines,
                y_from_zero: false,
            },
        ],
        size: (2000, 600),
    };
    save_figure(
        &fig,
        &staged.file("added_mass_and_momentum.png"),
        Some(&staged.file("added_mass_and_momentum.svg")),
    )?;
    // The shear bands' positions below the foot per run, with the paper's 60 degree cone.
    let mut band_lines = Vec::new();
    for (k, r) in rows.iter().enumerate() {
        let j = read_json(&runs.join(&r.name).join("summary.json"))?;
        let Some(band_rows) = j["summary"]["shear_band_cone"]["rows"].as_array() else {
            continue;
        };
        let pt = |b: &serde_json::Value, key: &str, sign: f64| {
            (
                sign * 1e3 * b[key].as_f64().unwrap_or(f64::NAN),
                -1e3 * b["depth_below_foot_m"].as_f64().unwrap_or(f64::NAN),
            )
        };
        for (side, sign) in [("left_m", -1.0), ("right_m", 1.0)] {
            band_lines.push(Line {
                label: if sign < 0.0 {
                    r.name.clone()
                } else {
                    String::new()
                },
                points: band_rows.iter().map(|b| pt(b, side, sign)).collect(),
                color: palette(k),
                dashed: false,
                markers: true,
            });
        }
    }
    let apex = 1e3 * radius_m * 60f64.to_radians().tan();
    band_lines.push(Line {
        label: "60 deg cone (the paper)".into(),
        points: vec![(-1e3 * radius_m, 0.0), (0.0, -apex), (1e3 * radius_m, 0.0)],
        color: palette(7),
        dashed: true,
        markers: false,
    });
    let cone_fig = LineFigure {
        title: "Shear bands below the foot (strain-rate peaks, foot frame, v >= 0.3 v_max)".into(),
        panels: vec![LinePanel {
            caption: "each run's band positions row by row, down to the first row without bands"
                .into(),
            x_desc: "distance from the foot's axis (mm)".into(),
            y_desc: "height below the foot's bottom (mm)".into(),
            lines: band_lines,
            y_from_zero: false,
        }],
        size: (900, 700),
    };
    save_figure(
        &cone_fig,
        &staged.file("shear_bands.png"),
        Some(&staged.file("shear_bands.svg")),
    )?;
    // The sensitivity rows and the cones as one bar-like figure: ratio per run.
    let sens = LineFigure {
        title: "DEM / eq. 6 and the jammed cone per run".into(),
        panels: vec![
            LinePanel {
                caption: rows
                    .iter()
                    .enumerate()
                    .map(|(i, r)| format!("{}: {}", i + 1, r.name))
                    .collect::<Vec<_>>()
                    .join(", "),
                x_desc: "run".into(),
                y_desc: "DEM / eq. 6 (median)".into(),
                lines: vec![Line {
                    label: "DEM / eq. 6".into(),
                    points: rows
                        .iter()
                        .enumerate()
                        .map(|(i, r)| ((i + 1) as f64, r.added_mass_vs_eq6_median))
                        .collect(),
                    color: palette(0),
                    dashed: false,
                    markers: true,
                }],
                y_from_zero: true,
            },
            LinePanel {
                caption: "cone side from the horizontal (the paper: about 60 deg); missing: none"
                    .into(),
                x_desc: "run".into(),
                y_desc: "angle (deg)".into(),
                lines: vec![
                    Line {
                        label: "shear-band cone".into(),
                        points: rows
                            .iter()
                            .enumerate()
                            .filter(|(_, r)| r.shear_band_cone_deg.is_finite())
                            .map(|(i, r)| ((i + 1) as f64, r.shear_band_cone_deg))
                            .collect(),
                        color: palette(1),
                        dashed: false,
                        markers: true,
                    },
                    Line {
                        label: "co-moving cone".into(),
                        points: rows
                            .iter()
                            .enumerate()
                            .filter(|(_, r)| r.comoving_cone_deg.is_finite())
                            .map(|(i, r)| ((i + 1) as f64, r.comoving_cone_deg))
                            .collect(),
                        color: palette(2),
                        dashed: false,
                        markers: true,
                    },
                ],
                y_from_zero: true,
            },
        ],
        size: (1400, 600),
    };
    save_figure(
        &sens,
        &staged.file("sensitivity.png"),
        Some(&staged.file("sensitivity.svg")),
    )?;
    Ok(series)
}
