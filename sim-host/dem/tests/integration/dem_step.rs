//! The DEM's fused step (#23's speed work) against a plain reference. One step, on one
//! thread (one chunk) and on three (several chunks, so that pairs cross chunks), equals a
//! brute-force all-pairs step written out here to rounding, for the paper's model
//! (frictionless, constant dashpot, forward Euler, drag) and the full one (friction with
//! history, restitution damping, velocity Verlet, gravity), with walls and a moving
//! intruder; and many steps, through list rebuilds, give the same bits on one, two and three
//! threads (one chunk against several).

use rand::{RngExt, SeedableRng, rngs::StdRng};
use sandjumper_dem::grains::{FREE, Grains, INTRUDER};
use sandjumper_dem::params::{Choice, Model};
use sandjumper_dem::world::{Integrator, Walls, World};

const WIDTH_M: f64 = 0.08;

/// About 2,000 grains on a jittered triangular lattice (small and large grains mixed, some
/// overlapping each other and the walls), moving at random, and a row of intruder grains
/// on top driven down.
fn world(model: Model, seed: u64) -> World {
    let mut c = Choice::new(model);
    c.overlap = 0.02;
    let p = c.resolve(false).unwrap();
    let d = p.diameter_m;
    let mut rng = StdRng::seed_from_u64(seed);
    let mut g = Grains::default();
    let a = 1.15 * d;
    let cols = (WIDTH_M / a) as usize - 1;
    let rows = 28;
    for r in 0..rows {
        for k in 0..cols {
            let x = (k as f64 + 0.5 + 0.5 * (r % 2) as f64) * a
                + 0.08 * d * (rng.random::<f64>() - 0.5);
            let y = (r as f64 * 0.866 + 0.5) * a + 0.08 * d * (rng.random::<f64>() - 0.5);
            let di = if rng.random::<f64>() < 0.5 {
                d
            } else {
                1.25 * d
            };
            let i = g.push(
                x.clamp(0.45 * d, WIDTH_M - 0.45 * d),
                y.max(0.45 * d),
                di,
                p.density_kg_m3,
                FREE,
            );
            g.vx[i] = 0.3 * (rng.random::<f64>() - 0.5);
            g.vy[i] = 0.3 * (rng.random::<f64>() - 0.5);
            g.w[i] = 200.0 * (rng.random::<f64>() - 0.5);
        }
    }
    let top = (rows as f64 * 0.866 + 0.5) * a;
    for k in 0..12 {
        g.push(0.03 + k as f64 * 0.5 * d, top, d, p.density_kg_m3, INTRUDER);
    }
    let walls = Walls {
        floor_m: Some(0.0),
        left_m: Some(0.0),
        right_m: Some(WIDTH_M),
        lid_m: None,
    };
    let mut w = World::new(p.world(walls), g);
    w.intruder_next = Some((top - 0.5 * d - 0.5 * w.cfg.dt_s, -0.5));
    w
}

/// Each grain's state by id: (x, y, vx, vy, w, ux, uy, uw).
fn by_id(w: &World) -> Vec<[f64; 8]> {
    let g = &w.g;
    let mut out = vec![[0.0; 8]; g.len()];
    for i in 0..g.len() {
        out[g.id[i] as usize] = [
            g.x[i], g.y[i], g.vx[i], g.vy[i], g.w[i], w.u.x[i], w.u.y[i], w.u.w[i],
        ];
    }
    out
}

/// One step of `w`, brute force over all pairs, written from the model's equations: the
/// state after it, by id.
fn reference_step(w: &World) -> Vec<[f64; 8]> {
    let (g, cfg) = (&w.g, &w.cfg);
    let n = g.len();
    let law = cfg.law;
    let fr = law.friction;
    let dt = cfg.dt_s;
    let (mut fx, mut fy, mut tq) = (vec![0.0; n], vec![0.0; n], vec![0.0; n]);
    // Tangential force for slip speed vt and normal force fn_ on a fresh contact (history
    // zero before the step: it becomes vt dt).
    let tangential = |vt: f64, fn_: f64, gamma: f64, mu: f64| {
        let f = fr.unwrap();
        let ft = -(f.kt_over_kn * law.kn_n_per_m * vt * dt) - f.gammat_over_gamman * gamma * vt;
        let cap = mu * fn_.max(0.0);
        ft.clamp(-cap, cap)
    };
    for i in 0..n {
        for j in i + 1..n {
            if g.kind[i] != FREE && g.kind[j] != FREE {
                continue;
            }
            let (dx, dy) = (g.x[j] - g.x[i], g.y[j] - g.y[i]);
            let dist = dx.hypot(dy);
            let rsum = g.radius[i] + g.radius[j];
            if dist >= rsum {
                continue;
            }
            let (nx, ny) = (dx / dist, dy / dist);
            let (rvx, rvy) = (w.u.x[i] - w.u.x[j], w.u.y[i] - w.u.y[j]);
            let gamma = law.gamma_n(1.0 / (g.inv_mass[i] + g.inv_mass[j]));
            let fn_ = law.kn_n_per_m * (rsum - dist) + gamma * (rvx * nx + rvy * ny);
            let (mut px, mut py) = (-fn_ * nx, -fn_ * ny);
            if let Some(f) = fr {
                let (tx, ty) = (-ny, nx);
                let vt = rvx * tx + rvy * ty + w.u.w[i] * g.radius[i] + w.u.w[j] * g.radius[j];
                let ft = tangential(vt, fn_, gamma, f.mu);
                px += ft * tx;
                py += ft * ty;
                tq[i] += g.radius[i] * ft;
                tq[j] += g.radius[j] * ft;
            }
            fx[i] += px;
            fy[i] += py;
            fx[j] -= px;
            fy[j] -= py;
        }
    }
    let mut out = by_id(w);
    for i in 0..n {
        let s = &mut out[g.id[i] as usize];
        if g.kind[i] != FREE {
            let (bottom, v) = w.intruder_next.unwrap();
            *s = [g.x[i], bottom + g.radius[i], 0.0, v, 0.0, 0.0, v, 0.0];
            continue;
        }
        let (r, m) = (g.radius[i], 1.0 / g.inv_mass[i]);
        let (ux, uy, uw) = (w.u.x[i], w.u.y[i], w.u.w[i]);
        let wall = cfg.walls;
        // (overlap, outward normal).
        for (delta, nx, ny) in [
            (r - (g.y[i] - wall.floor_m.unwrap()), 0.0, -1.0),
            (r - (g.x[i] - wall.left_m.unwrap()), -1.0, 0.0),
            (r - (wall.right_m.unwrap() - g.x[i]), 1.0, 0.0),
        ] {
            if delta <= 0.0 {
                continue;
            }
            let gamma = law.gamma_n(m);
            let fn_ = law.kn_n_per_m * delta + gamma * (ux * nx + uy * ny);
            fx[i] -= fn_ * nx;
            fy[i] -= fn_ * ny;
            if let Some(f) = fr {
                let (tx, ty) = (-ny, nx);
                let ft = tangential(ux * tx + uy * ty + uw * r, fn_, gamma, f.mu_wall);
                fx[i] += ft * tx;
                fy[i] += ft * ty;
                tq[i] += r * ft;
            }
        }
        let ax = fx[i] / m - cfg.drag_per_s * ux;
        let ay = fy[i] / m - cfg.gravity_m_s2 - cfg.drag_per_s * uy;
        let al = if fr.is_some() {
            tq[i] * g.inv_inertia[i]
        } else {
            0.0
        };
        let (vx, vy, sw) = (g.vx[i] + ax * dt, g.vy[i] + ay * dt, g.w[i] + al * dt);
        *s = match cfg.integrator {
            Integrator::ForwardEuler => [
                g.x[i] + g.vx[i] * dt,
                g.y[i] + g.vy[i] * dt,
                vx,
                vy,
                sw,
                vx,
                vy,
                if fr.is_some() { sw } else { uw },
            ],
            Integrator::VelocityVerlet => [
                g.x[i] + vx * dt,
                g.y[i] + vy * dt,
                vx,
                vy,
                sw,
                vx + 0.5 * ax * dt,
                vy + 0.5 * ay * dt,
                if fr.is_some() { sw + 0.5 * al * dt } else { uw },
            ],
        };
    }
    out
}

/// `f` on a pool of `threads` threads.
fn on_threads<T: Send>(threads: usize, f: impl FnOnce() -> T + Send) -> T {
    rayon::ThreadPoolBuilder::new()
        .num_threads(threads)
        .build()
        .unwrap()
        .install(f)
}

#[test]
fn one_step_equals_a_brute_force_step_for_both_models_on_one_and_three_threads() {
    for (model, threads) in [
        (Model::Paper, 1),
        (Model::Paper, 3),
        (Model::Full, 1),
        (Model::Full, 3),
    ] {
        on_threads(threads, || check_one_step(model, threads));
    }
}

fn check_one_step(model: Model, threads: usize) {
    {
        let mut w = world(model, 3);
        // What the test claims to exercise: one chunk on one thread; on three, several
        // chunks and pairs across them; friction only in the full model.
        if threads == 1 {
            assert_eq!(w.nl.chunks(), 1);
        } else {
            assert!(w.nl.chunks() >= 3, "{} chunks", w.nl.chunks());
            assert!(
                w.nl.cross_pairs() > 100,
                "{} cross pairs",
                w.nl.cross_pairs()
            );
        }
        assert_eq!(w.cfg.law.friction.is_some(), model == Model::Full);
        let want = reference_step(&w);
        let before = by_id(&w);
        w.step();
        let got = by_id(&w);
        // Scale of each quantity's change over the step, for a tolerance relative to it.
        let mut scale = [0.0f64; 8];
        for (b, r) in before.iter().zip(&want) {
            for k in 0..8 {
                scale[k] = scale[k].max((r[k] - b[k]).abs());
            }
        }
        let mut contacts_seen = 0;
        for (id, ((g, r), b)) in got.iter().zip(&want).zip(&before).enumerate() {
            for k in 0..8 {
                let tol = 1e-9 * scale[k] + 1e-15 * r[k].abs();
                assert!(
                    (g[k] - r[k]).abs() <= tol,
                    "{model:?}: grain {id} quantity {k}: step {} vs reference {} (scale {})",
                    g[k],
                    r[k],
                    scale[k]
                );
            }
            // A change of velocity beyond gravity and drag: the grain was pushed.
            if (r[3] - b[3]).abs() > 10.0 * w.cfg.gravity_m_s2 * w.cfg.dt_s + 1e-12 {
                contacts_seen += 1;
            }
        }
        assert!(
            contacts_seen > 200,
            "{model:?}: only {contacts_seen} grains pushed"
        );
    }
}

#[test]
fn many_steps_give_the_same_bits_on_one_two_and_three_threads() {
    for model in [Model::Paper, Model::Full] {
        let run = |threads: usize| {
            on_threads(threads, || {
                let mut w = world(model, 7);
                let chunks = w.nl.chunks();
                assert!(
                    (threads == 1) == (chunks == 1),
                    "{chunks} chunks on {threads} threads"
                );
                let d0 = w.nl.builds;
                let mut sums = Vec::new();
                for s in 0..400 {
                    if s == 150 {
                        w.rebuild();
                    }
                    w.step();
                    sums.push((w.last.intruder_fy_n, w.last.floor_n));
                }
                (by_id(&w), sums, w.nl.builds - d0)
            })
        };
        let (one, s1, builds) = run(1);
        assert!(builds >= 2, "{model:?}: {builds} builds");
        for threads in [2, 3] {
            let (other, s, _) = run(threads);
            assert!(
                one == other,
                "{model:?}: grains differ on {threads} threads"
            );
            assert!(s1 == s, "{model:?}: sums differ on {threads} threads");
        }
    }
}

/// A bed of `long` by `short` grains on a jittered triangular lattice, lying (`wide`) or
/// standing, no walls.
fn lattice(wide: bool, long: usize, short: usize) -> World {
    let p = Choice::new(Model::Paper).resolve(false).unwrap();
    let d = p.diameter_m;
    let mut rng = StdRng::seed_from_u64(11);
    let mut g = Grains::default();
    for a in 0..long {
        for b in 0..short {
            let along = (a as f64 + 0.5 * (b % 2) as f64) * d + 0.05 * d * rng.random::<f64>();
            let across = b as f64 * 0.866 * d + 0.05 * d * rng.random::<f64>();
            let (x, y) = if wide {
                (along, across)
            } else {
                (across, along)
            };
            g.push(x, y, d, p.density_kg_m3, FREE);
        }
    }
    World::new(p.world(Walls::default()), g)
}

#[test]
fn chunk_boundaries_cross_the_short_side_of_the_bed() {
    // 160 by 20 grains, lying and standing: cut in two, either way, the boundary crosses
    // the 20 grains, each with a few partners across it; one along the 160 would have
    // several hundred cross pairs.
    let (long, short) = (160, 20);
    let cross = |wide: bool| {
        on_threads(2, || {
            let w = lattice(wide, long, short);
            assert_eq!(w.nl.chunks(), 2, "wide {wide}");
            w.nl.cross_pairs()
        })
    };
    for wide in [true, false] {
        let n = cross(wide);
        assert!(
            n > 0 && n <= 4 * short,
            "wide {wide}: {n} cross pairs for a boundary {short} grains long"
        );
    }
}
