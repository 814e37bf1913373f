//! PIV with its defaults on a real grain image (a photograph of gravel, CC0) moved by exact
//! sub-pixel shifts (`piv-synthetic --image`, a Fourier shift): several shifts, both
//! components, bias and RMS of each. The defaults must be as accurate as no pre-processing at
//! all: the default enhancement (local contrast) is a filter and adds no bias. (CLAHE on fixed
//! tiles, no longer the default, biased OpenPIV's own test image by 0.07 px:
//! `sim-host/flow/benches/piv_vs_openpiv.sh` measures that one, beside OpenPIV; this test does
//! not run CLAHE.)

mod common;

use common::ok;

const IMAGE: &str = concat!(
    env!("CARGO_MANIFEST_DIR"),
    "/tests/fixtures/real-images/gravel_cc0.png"
);

/// Bias and RMS error of u and v over the vectors more than `margin` px from every edge.
fn errors(dir: &std::path::Path, (dx, dy): (f64, f64), margin: f64) -> [f64; 4] {
    let text = std::fs::read_to_string(dir.join("fields/0000.csv")).unwrap();
    let mut lines = text.lines();
    let head: Vec<&str> = lines.next().unwrap().split(',').collect();
    let col = |name: &str| head.iter().position(|h| *h == name).unwrap();
    let (cx, cy, cu, cv) = (col("x_px"), col("y_px"), col("u_px"), col("v_px"));
    let (mut eu, mut ev) = (Vec::new(), Vec::new());
    for line in lines {
        let f: Vec<&str> = line.split(',').collect();
        let (x, y): (f64, f64) = (f[cx].parse().unwrap(), f[cy].parse().unwrap());
        if x < margin || y < margin || x > 511.0 - margin || y > 511.0 - margin {
            continue;
        }
        // A missing vector is an error of its own: the test counts it below.
        eu.push(f[cu].parse::<f64>().map_or(f64::NAN, |u| u - dx));
        ev.push(f[cv].parse::<f64>().map_or(f64::NAN, |v| v - dy));
    }
    assert!(eu.len() > 2000, "{} interior vectors", eu.len());
    let mean = |e: &[f64]| e.iter().sum::<f64>() / e.len() as f64;
    let rms = |e: &[f64]| (e.iter().map(|a| a * a).sum::<f64>() / e.len() as f64).sqrt();
    [mean(&eu), mean(&ev), rms(&eu), rms(&ev)]
}

#[test]
fn the_defaults_measure_exact_shifts_of_a_real_grain_image_without_bias() {
    let tmp = tempfile::tempdir().unwrap();
    for (k, shift) in [
        (5.25, 3.75),
        (0.5, 0.25),
        (2.3, -1.15),
        (1.75, 0.6),
        (-3.4, 1.3),
    ]
    .into_iter()
    .enumerate()
    {
        let pair = tmp.path().join(format!("pair{k}"));
        let s = format!("{},{}", shift.0, shift.1);
        ok(&[
            "piv-synthetic",
            "--field",
            "shift",
            "--image",
            IMAGE,
            "--shift",
            &s,
            "--out",
            pair.to_str().unwrap(),
        ]);
        let run = |name: &str, extra: &[&str]| {
            let out = tmp.path().join(format!("{name}{k}"));
            let mut args = vec![
                "piv",
                pair.to_str().unwrap(),
                "--out",
                out.to_str().unwrap(),
            ];
            args.extend_from_slice(extra);
            ok(&args);
            errors(&out, shift, 32.0)
        };
        let default = run("default", &[]);
        let plain = run("plain", &["--local-contrast", "0"]);
        eprintln!("shift {s}: defaults bias/RMS (u, v) {default:.4?}, no enhancement {plain:.4?}");
        for (c, name) in ["u", "v"].iter().enumerate() {
            let (bias, rms) = (default[c], default[2 + c]);
            assert!(
                bias.abs() < 0.008 && rms < 0.008,
                "shift {s}, {name}: bias {bias:.4} px, RMS {rms:.4} px (allowed 0.008)"
            );
            assert!(
                rms <= 1.3 * plain[2 + c] + 5e-4,
                "shift {s}, {name}: RMS {rms:.4} px with the defaults, {:.4} px without any enhancement",
                plain[2 + c]
            );
        }
    }
}
