//! Parameters: presets, interpolation, TOML overrides with key and line, validation.

use sandjumper_model::*;

#[test]
fn preset_rows_and_linear_interpolation() {
    let a = Params::preset(0.57).unwrap();
    let b = Params::preset(0.58).unwrap();
    let mid = Params::preset(0.575).unwrap();
    assert_eq!(a.sand.k1_n_m, 1600.0);
    assert_eq!(Params::preset(0.62).unwrap().sand.k1_n_m, 10_000.0);
    assert!((mid.sand.k1_n_m - 0.5 * (a.sand.k1_n_m + b.sand.k1_n_m)).abs() < 1e-9);
    // eq1's alpha: the fitted table (docs/model.md section 3, "alpha for eq1"), interpolated.
    assert!((a.sand.alpha_kg_m - 90.6).abs() < 1e-9);
    assert!((mid.sand.alpha_kg_m - 0.5 * (90.6 + 109.4)).abs() < 1e-9);
    assert!((mid.sand.sigma_cone_n_m3 - 0.135e6).abs() < 1e-6);
    assert!((Params::preset(0.605).unwrap().sand.k1_n_m - 4600.0).abs() < 1e-9);
    for phi in [0.56, 0.63, f64::NAN] {
        let e = Params::preset(phi).unwrap_err();
        assert!(e.to_string().contains("0.57"), "{e}");
    }
}

#[test]
fn toml_round_trip() {
    let p = Params::preset(0.595).unwrap();
    let back = Params::preset(0.57)
        .unwrap()
        .with_overrides_toml(&p.to_toml(), "params.toml")
        .unwrap();
    assert_eq!(back, p);
}

#[test]
fn overrides_change_only_the_given_keys() {
    let text = "[robot]\nfoot_mass_kg = 0.05\n\n[sand]\nk1_n_m = 2000\n\n[model]\ndrag = \"constant-alpha\"\n";
    let p = Params::preset(0.57)
        .unwrap()
        .with_overrides_toml(text, "x.toml")
        .unwrap();
    let mut expected = Params::preset(0.57).unwrap();
    expected.robot.foot_mass_kg = 0.05;
    expected.sand.k1_n_m = 2000.0;
    expected.model.drag = sandjumper_model::params::DragChoice::ConstantAlpha;
    assert_eq!(p, expected);
}

fn err(text: &str) -> ParamsError {
    Params::preset(0.57)
        .unwrap()
        .with_overrides_toml(text, "my.toml")
        .unwrap_err()
}

#[test]
fn override_errors_name_the_key_and_line() {
    let e = err("[robot]\nfoot_mass_kg = 0.05\nfoot_mas_kg = 1.0\n");
    assert_eq!(
        (e.key.as_deref(), e.line),
        (Some("robot.foot_mas_kg"), Some(3)),
        "{e}"
    );
    assert!(e.to_string().starts_with("my.toml:3:"), "{e}");
    assert!(e.allowed.contains("foot_mass_kg"));

    let e = err("\n[sand]\nk1_n_m = \"stiff\"\n");
    assert_eq!(
        (e.key.as_deref(), e.line),
        (Some("sand.k1_n_m"), Some(3)),
        "{e}"
    );

    let e = err("[model]\n\ndrag = \"quadratic\"\n");
    assert_eq!(
        (e.key.as_deref(), e.line),
        (Some("model.drag"), Some(3)),
        "{e}"
    );

    let e = err("[robot]\nmotor_mass_kg = -1.0\n");
    assert_eq!(
        (e.key.as_deref(), e.line),
        (Some("robot.motor_mass_kg"), Some(2)),
        "{e}"
    );
    assert!(e.to_string().contains("> 0"), "{e}");

    let e = err("[robot\nx = 1\n");
    assert_eq!(e.line, Some(1), "{e}");

    let e = err("bogus = 1\n");
    assert_eq!(e.key.as_deref(), Some("bogus"));
}

#[test]
fn validation_rejects_unphysical_values() {
    let ok = Params::preset(0.6).unwrap();
    ok.validate().unwrap();
    type Breaker = fn(&mut Params);
    let cases: [(&str, Breaker); 5] = [
        ("robot.spring_stiffness_n_m", |p| {
            p.robot.spring_stiffness_n_m = -3300.0
        }),
        ("robot.foot_mass_kg", |p| p.robot.foot_mass_kg = 0.0),
        ("robot.spring_damping_n_s_m", |p| {
            p.robot.spring_damping_n_s_m = -1.0
        }),
        ("sand.packing_fraction", |p| p.sand.packing_fraction = 1.2),
        ("robot.stroke_amplitude_m", |p| {
            p.robot.stroke_amplitude_m = 0.03
        }),
    ];
    for (key, break_it) in cases {
        let mut p = ok.clone();
        break_it(&mut p);
        let e = p.validate().unwrap_err();
        assert_eq!(e.key.as_deref(), Some(key), "{e}");
        let spec = JumpSpec {
            kind: JumpKind::Single,
            freq_hz: 8.0,
            tau_s: 0.0,
            model: ModelName::Eq4,
        };
        assert!(simulate_jump(&p, &spec, &SimOptions::default()).is_err());
    }
}

#[test]
fn model_names_parse_and_print() {
    for m in ModelName::ALL {
        assert_eq!(m.to_string().parse::<ModelName>().unwrap(), m);
    }
    assert!("eq5".parse::<ModelName>().is_err());
}

#[test]
fn bad_jump_requests_are_errors_not_panics() {
    let p = Params::default();
    let o = SimOptions::default();
    for (f, tau) in [
        (0.0, 0.0),
        (-3.0, 0.0),
        (f64::NAN, 0.0),
        (8.0, -1.0),
        (1e6, 0.0),
    ] {
        let spec = JumpSpec {
            kind: JumpKind::DelayedStutter,
            freq_hz: f,
            tau_s: tau,
            model: ModelName::Eq4,
        };
        let e = simulate_jump(&p, &spec, &o).unwrap_err();
        assert!(!e.to_string().is_empty());
    }
    let bad = SimOptions {
        rtol: 0.0,
        ..SimOptions::default()
    };
    let spec = JumpSpec {
        kind: JumpKind::Single,
        freq_hz: 8.0,
        tau_s: 0.0,
        model: ModelName::Eq4,
    };
    assert!(
        simulate_jump(&p, &spec, &bad)
            .unwrap_err()
            .to_string()
            .contains("rtol")
    );
}

/// The starting values of docs/model.md's alpha column stay reachable through the params file
/// shipped in the repository, at every preset row and between rows; a file that sets
/// `sand.alpha_kg_m` itself keeps it.
#[test]
fn the_shipped_params_file_restores_the_starting_alphas() {
    let path = concat!(
        env!("CARGO_MANIFEST_DIR"),
        "/params/eq1-starting-alpha.toml"
    );
    let text = std::fs::read_to_string(path).expect("the shipped params file");
    for (phi, alpha) in [
        (0.57, 50.0),
        (0.575, 55.0),
        (0.58, 60.0),
        (0.59, 75.0),
        (0.60, 90.0),
        (0.61, 150.0),
        (0.62, 250.0),
    ] {
        let p = Params::preset(phi)
            .unwrap()
            .with_overrides_toml(&text, path)
            .unwrap();
        assert!(
            (p.sand.alpha_kg_m - alpha).abs() < 1e-9,
            "phi {phi}: {}",
            p.sand.alpha_kg_m
        );
    }
    let explicit = format!("{text}\n[sand]\nalpha_kg_m = 42.0\n");
    let p = Params::preset(0.57)
        .unwrap()
        .with_overrides_toml(&explicit, "x.toml")
        .unwrap();
    assert_eq!(p.sand.alpha_kg_m, 42.0);
    let fitted = Params::preset(0.6)
        .unwrap()
        .with_overrides_toml("[model]\neq1_alpha = \"fitted\"\n", "y.toml")
        .unwrap();
    assert!((fitted.sand.alpha_kg_m - 171.7).abs() < 1e-9);
}
