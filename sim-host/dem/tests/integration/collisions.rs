//! Binary collisions against the analytic spring-dashpot (#23): restitution and contact time
//! for any pair and speed with light damping, the dashpot's first-order separation error at
//! heavy damping, the paper's forward Euler (first order, gaining energy), and `dem collide`
//! as a call (its effective mass and restitution).

use proptest::prelude::*;
use sandjumper_dem::collide::{self, CollideRequest, Collision};
use sandjumper_dem::world::Integrator;
use sandjumper_output::Silent;

fn collision(d1: f64, d2: f64, wall: bool, speed: f64, zeta: f64, steps: f64) -> Collision {
    let mut c = Collision {
        d1_m: d1,
        d2_m: d2,
        wall,
        kn_n_per_m: 2000.0,
        damping_n_s_per_m: 0.0,
        speed_m_s: speed,
        density_kg_m3: 1000.0,
        dt_s: None,
        integrator: Integrator::VelocityVerlet,
    };
    c.damping_n_s_per_m = zeta * c.pair().critical_damping();
    c.dt_s = Some(c.pair().contact_time_s() / steps);
    c
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(48))]
    /// Restitution and contact time within 1 % at t_c/40 and 0.1 % at t_c/200, for disk
    /// pairs of any sizes, disk-wall, any impact speed, and light damping (up to 0.05 of
    /// critical, e >= 0.85), plus, for the restitution, the dashpot's first-order separation
    /// error that the heavy-damping test below measures (under 4 % at t_c/40 and 1 % at
    /// t_c/200 for zeta 0.3, so 0.15 zeta and 0.04 zeta here: at zeta 0.047, t_c/200, the
    /// error reaches 0.15 %).
    #[test]
    fn binary_collisions_match_the_analytic_spring_dashpot(
        d1 in 0.5e-3f64..3e-3,
        d2 in 0.5e-3f64..3e-3,
        wall in any::<bool>(),
        speed in 0.01f64..5.0,
        zeta in 0.0f64..0.05,
    ) {
        for (steps, tol, damping_tol) in [(40.0, 1e-2, 0.15), (200.0, 1e-3, 0.04)] {
            let r = collision(d1, d2, wall, speed, zeta, steps).run(false).unwrap();
            let e_tol = tol + damping_tol * zeta;
            prop_assert!(r.restitution_error.abs() < e_tol, "e {} vs {} at t_c/{steps}", r.restitution, r.restitution_analytic);
            prop_assert!(r.contact_time_error.abs() < tol, "t_c {} vs {} at t_c/{steps}", r.contact_time_s, r.contact_time_analytic_s);
        }
    }
}

#[test]
fn heavy_damping_has_a_first_order_separation_error() {
    // The dashpot pulls at separation (kn delta + gamma v_n < 0 as delta -> 0), and the
    // step that holds the separation applies that pull for a whole step: an error of order
    // gamma dt / m that depends on where in the step the contact ends. Measured, not hidden:
    // at zeta 0.3 (e 0.37) it stays under 4 % at t_c/40 and under 1 % at t_c/200.
    let mut worst: [f64; 2] = [0.0, 0.0];
    for (k, steps) in [40.0, 200.0].into_iter().enumerate() {
        for speed in [0.3, 0.5, 1.0, 2.0, 3.2] {
            let r = collision(0.76e-3, 1e-3, true, speed, 0.3, steps)
                .run(false)
                .unwrap();
            worst[k] = worst[k].max(r.restitution_error.abs());
        }
    }
    eprintln!("zeta 0.3: worst restitution error {worst:?}");
    assert!(worst[0] < 0.04 && worst[1] < 0.01, "{worst:?}");
    assert!(worst[1] < worst[0]);
}

#[test]
fn forward_euler_is_first_order_and_gains_energy() {
    // The paper's integrator: its restitution error halves when the step halves, and it
    // overshoots (explicit Euler feeds energy into a spring). Stated, not hidden.
    let mut c = collision(1e-3, 1e-3, false, 0.5, 0.2, 40.0);
    c.integrator = Integrator::ForwardEuler;
    let e40 = c.run(false).unwrap().restitution_error;
    c.dt_s = Some(c.pair().contact_time_s() / 80.0);
    let e80 = c.run(false).unwrap().restitution_error;
    assert!(e40 > 0.0 && e80 > 0.0, "{e40} {e80}");
    assert!((1.4..2.3).contains(&(e40 / e80)), "order: {e40} / {e80}");
}

/// `dem collide --d1 1e-3 --d2 1.4e-3 --kn 1000 --damping 0.005 --speed 0.3` as a call: the
/// verification numbers are positive, the effective mass is `m1 m2 / (m1 + m2)` of the two
/// spheres' masses, and the restitution is the analytic one within 0.1 % (the keys `--json`
/// prints are checked in `sim-host/cli/tests/integration/dem.rs`).
#[test]
fn collide_gives_the_pairs_effective_mass_and_the_analytic_restitution() {
    let r = collide::run(
        &CollideRequest {
            d1_m: 1e-3,
            d2_m: Some(1.4e-3),
            kn_n_per_m: 1000.0,
            damping_n_s_per_m: 0.005,
            speed_m_s: 0.3,
            ..CollideRequest::default()
        },
        &Silent,
    )
    .unwrap();
    for (k, v) in [
        ("restitution", r.restitution),
        ("contact_time_s", r.contact_time_s),
        ("effective_mass_kg", r.effective_mass_kg),
        ("dt_s", r.dt_s),
    ] {
        assert!(v > 0.0, "{k} in {r}");
    }
    let m1 = 1000.0 * std::f64::consts::PI * 1e-9 / 6.0;
    let m2 = m1 * 1.4f64.powi(3);
    assert!((r.effective_mass_kg / (m1 * m2 / (m1 + m2)) - 1.0).abs() < 1e-12);
    assert!(r.restitution_error.abs() < 1e-3, "{r}");
}
