//! What a run through the loop leaves behind: the acquisition log (the logs' own format and
//! writer, [`sandjumper_acqlog`]: exactly what the rig produces) and a figure of commanded vs
//! actual motor position, spring force and foot depth.

use super::run::{HilOutcome, HilSpec};
use sandjumper_acqlog::{AcqLog, Column, LogMetadata, LogRow};
use sandjumper_output::plot::lines::{Line, LineFigure, LinePanel, grid_size};
use sandjumper_output::plot::palette;

/// The acquisition log of a run: one row per controller sample record, time = tick / rate,
/// the camera's rod height on the rows that started a frame. `firmware` names the controller.
pub fn acquisition_log(
    outcome: &HilOutcome,
    spec: &HilSpec,
    tick_hz: u32,
    metres_per_count: f64,
    amplitude_m: f64,
    phi: f64,
) -> AcqLog {
    let mut meta = LogMetadata::new(f64::from(tick_hz), 1.0 / metres_per_count);
    meta.firmware = Some(match outcome.link_name.as_str() {
        "sil" => format!(
            "sandjumper-core {} (software in the loop)",
            env!("CARGO_PKG_VERSION")
        ),
        other => format!(
            "sandjumper-firmware {} ({other})",
            env!("CARGO_PKG_VERSION")
        ),
    });
    meta.source = Some(format!("sandjumper hil --link {}", outcome.link_name));
    meta.jump = Some(spec.log_jump(amplitude_m));
    meta.phi = Some(phi);
    meta.dropped_samples = outcome.samples_missing();
    let mut log = AcqLog::new(
        meta,
        &[
            Column::PCmdM,
            Column::ForceCmdN,
            Column::CurrentA,
            Column::CameraFrame,
            Column::Flags,
            Column::RodHeightM,
        ],
    );
    let first_tick = outcome.samples.first().map_or(0, |s| s.tick);
    let mut frames = outcome.camera_frames.iter().peekable();
    for s in &outcome.samples {
        let mut row = LogRow::new(
            u64::from(s.tick),
            f64::from(s.tick - first_tick) / f64::from(tick_hz),
            s.encoder_count,
        );
        row.p_cmd_m = Some(f64::from(s.commanded_position_m));
        row.force_cmd_n = Some(f64::from(s.force_n));
        row.current_a = s.current_a.map(f64::from);
        row.camera_frame = s.camera_frame.map(u64::from);
        row.flags = Some(u32::from(s.flags));
        if s.camera_frame.is_some()
            && let Some(f) = frames.next()
        {
            row.rod_height_m = Some(f.rod_height_m);
        }
        log.rows.push(row);
    }
    log
}

/// Commanded vs actual motor position, spring force and foot depth against time.
pub fn figure(outcome: &HilOutcome, title: String) -> LineFigure {
    let by_tick: std::collections::HashMap<u32, f64> = outcome
        .samples
        .iter()
        .map(|s| (s.tick, f64::from(s.commanded_position_m)))
        .collect();
    // At most ~4000 points per line.
    let step = (outcome.trace.len() / 4000).max(1);
    let rows: Vec<_> = outcome.trace.iter().step_by(step).collect();
    let line = |label: &str, i: usize, dashed: bool, points: Vec<(f64, f64)>| Line {
        label: label.into(),
        points,
        color: palette(i),
        dashed,
        markers: false,
    };
    let commanded: Vec<(f64, f64)> = rows
        .iter()
        .filter_map(|r| {
            r.rig_tick
                .and_then(|t| by_tick.get(&t))
                .map(|p| (r.t_s, 1e3 * p))
        })
        .collect();
    let actual = rows.iter().map(|r| (r.t_s, 1e3 * r.p_m)).collect();
    let panels = vec![
        LinePanel {
            caption: "motor position relative to the rod".into(),
            x_desc: "time since the trajectory started (s)".into(),
            y_desc: "p (mm)".into(),
            lines: vec![
                line("commanded", 0, true, commanded),
                line("actual", 1, false, actual),
            ],
            y_from_zero: false,
        },
        LinePanel {
            caption: "spring force".into(),
            x_desc: "time since the trajectory started (s)".into(),
            y_desc: "F_s (N)".into(),
            lines: vec![line(
                "spring",
                2,
                false,
                rows.iter().map(|r| (r.t_s, r.spring_force_n)).collect(),
            )],
            y_from_zero: false,
        },
        LinePanel {
            caption: "foot depth".into(),
            x_desc: "time since the trajectory started (s)".into(),
            y_desc: "depth below the surface (mm)".into(),
            lines: vec![line(
                "foot",
                3,
                false,
                rows.iter().map(|r| (r.t_s, 1e3 * r.depth_m)).collect(),
            )],
            y_from_zero: false,
        },
    ];
    LineFigure {
        title,
        size: grid_size(panels.len()),
        panels,
    }
}
