//! PIV with its defaults on a real grain image (a photograph of gravel, CC0) moved by exact
//! sub-pixel shifts (`piv_synthetic::run` with an image, a Fourier shift): several shifts,
//! both components, bias and RMS of each. The defaults must be as accurate as no
//! pre-processing at all: the default enhancement (local contrast) is a filter and adds no
//! bias. (CLAHE on fixed tiles, no longer the default, biased OpenPIV's own test image by
//! 0.07 px: `sim-host/flow/benches/piv_vs_openpiv.sh` measures that one, beside OpenPIV; this
//! test does not run CLAHE.)

use std::path::Path;

use sandjumper_flow::piv::VectorField;
use sandjumper_flow::piv_synthetic::{self, SyntheticField, SyntheticRequest};
use sandjumper_flow::preprocess::Preprocess;
use sandjumper_flow::run::{self, PivRequest};
use sandjumper_output::Silent;

const IMAGE: &str = concat!(
    env!("CARGO_MANIFEST_DIR"),
    "/tests/fixtures/real-images/gravel_cc0.png"
);

/// Bias and RMS error of u and v over the vectors more than `margin` px from every edge of
/// the 512 x 512 image.
fn errors(f: &VectorField, (dx, dy): (f64, f64), margin: f64) -> [f64; 4] {
    let (mut eu, mut ev) = (Vec::new(), Vec::new());
    for j in 0..f.ny {
        for i in 0..f.nx {
            let (x, y) = (f.xs[i], f.ys[j]);
            if x < margin || y < margin || x > 511.0 - margin || y > 511.0 - margin {
                continue;
            }
            // A missing vector (NaN) is an error of its own: the test counts it below.
            let k = j * f.nx + i;
            eu.push(f.u[k] - dx);
            ev.push(f.v[k] - dy);
        }
    }
    assert!(eu.len() > 2000, "{} interior vectors", eu.len());
    let mean = |e: &[f64]| e.iter().sum::<f64>() / e.len() as f64;
    let rms = |e: &[f64]| (e.iter().map(|a| a * a).sum::<f64>() / e.len() as f64).sqrt();
    [mean(&eu), mean(&ev), rms(&eu), rms(&ev)]
}

/// The one field PIV measures on the pair in `frames`, with the defaults but `preprocess`.
fn field(frames: &Path, preprocess: Preprocess) -> VectorField {
    let request = PivRequest {
        frames: frames.display().to_string(),
        preprocess,
        ..PivRequest::default()
    };
    let mut outcome = run::run(&request, &Silent).unwrap();
    assert_eq!(outcome.pairs, 1);
    outcome.run.results.remove(0).field
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
        // The pair is written as 16-bit PNGs: `run` reads its frames from files.
        let request = SyntheticRequest {
            field: SyntheticField::Shift,
            image: Some(IMAGE.into()),
            shift_px: Some(shift),
            ..SyntheticRequest::default()
        };
        let pair = piv_synthetic::run(&request, &Silent)
            .unwrap()
            .write(&tmp.path().join(format!("pair{k}")))
            .unwrap();
        let s = format!("{},{}", shift.0, shift.1);
        let default = errors(&field(&pair, Preprocess::default()), shift, 32.0);
        let plain = errors(
            &field(
                &pair,
                Preprocess {
                    local_contrast_sigma_px: 0.0,
                    ..Preprocess::default()
                },
            ),
            shift,
            32.0,
        );
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
