//! LAMMPS's own measures read back (`sandjumper_lammps::analysis::parse_force`, `force.txt`,
//! and `parse_column`, `column.txt`) on any text: they never panic, and what they accept is
//! one row per data line, every number finite (a diverged run's `nan` is refused).
#![no_main]

use libfuzzer_sys::fuzz_target;
use sandjumper_lammps::analysis::{Geometry, parse_column, parse_force};

fuzz_target!(|data: &[u8]| {
    let Ok(text) = std::str::from_utf8(data) else {
        return;
    };
    let g = Geometry {
        axis_m: (0.03, 0.03),
        foot_radius_m: 0.0095,
        foot_sphere_radius_m: 0.0005,
        surface_m: 0.05,
        grain_density_kg_m3: 1100.0,
        grain_diameter_m: 0.001,
        time_step_s: 1e-6,
        symmetry_factor: 1.0,
    };
    let lines = text
        .lines()
        .filter(|l| !l.trim().is_empty() && !l.trim_start().starts_with('#'))
        .count();
    if let Ok(rows) = parse_force(text, "force.txt", &g, &|d| Ok(2.0 * d)) {
        assert_eq!(rows.len(), lines, "one row per data line");
        for r in &rows {
            assert!(
                r.t_s.is_finite() && r.force_n.is_finite() && r.depth_m.is_finite(),
                "a non-finite row accepted: {r:?}"
            );
        }
    }
    if let Ok(rows) = parse_column(text, "column.txt") {
        assert_eq!(rows.len(), lines, "one row per data line");
        for r in &rows {
            assert!(
                r.momentum_kg_m_s.is_finite() && r.ring_kg_m_s.is_finite(),
                "a non-finite row accepted: {r:?}"
            );
        }
    }
});
