//! Round trip of one cache line between two threads pinned to two cores, ns (median of
//! `ROUNDS` batches): what a multi-threaded step pays each time one core waits on another's
//! write. The DEM bench prints it beside its two-thread figures, because a shared or
//! virtual machine can move its cores farther apart for minutes at a time, and a step loop
//! that meets every 40 us feels it where a one-thread run does not.
//!
//!   cargo run --release -p sandjumper-dem --example core_latency [CORE_A CORE_B]
//!
//! Prints one line: `core-to-core round trip: <ns> ns (cores A and B)`. Exit status 2 when
//! the cores are not two distinct ones this process may run on.

use std::sync::atomic::{AtomicU64, Ordering};
use std::time::Instant;

/// Round trips per batch.
const TRIPS: u64 = 20_000;
/// Batches; the median is printed.
const ROUNDS: usize = 9;

/// A counter alone on its cache line.
#[repr(align(128))]
struct Line(AtomicU64);

fn main() {
    let cores = core_affinity::get_core_ids().unwrap_or_default();
    let args: Vec<String> = std::env::args().skip(1).collect();
    let pick = |k: usize, default: usize| -> Result<usize, String> {
        match args.get(k) {
            None => Ok(default),
            Some(a) => a
                .parse::<usize>()
                .map_err(|_| format!("core {a:?} is not a core number")),
        }
    };
    let chosen = pick(0, 0).and_then(|a| Ok((a, pick(1, 1)?)));
    let (a, b) = match chosen {
        Ok((a, b))
            if a != b && cores.iter().any(|c| c.id == a) && cores.iter().any(|c| c.id == b) =>
        {
            (a, b)
        }
        Ok((a, b)) => {
            let ids: Vec<usize> = cores.iter().map(|c| c.id).collect();
            eprintln!(
                "core_latency: cores {a} and {b}: need two distinct cores of this process's {ids:?}"
            );
            std::process::exit(2);
        }
        Err(e) => {
            eprintln!("core_latency: {e} (usage: core_latency [CORE_A CORE_B])");
            std::process::exit(2);
        }
    };
    let line = Line(AtomicU64::new(0));
    let mut batches = Vec::with_capacity(ROUNDS);
    std::thread::scope(|s| {
        let line = &line;
        s.spawn(move || {
            core_affinity::set_for_current(core_affinity::CoreId { id: b });
            // Answer every odd value with the next even one.
            for k in 0..TRIPS * ROUNDS as u64 {
                while line.0.load(Ordering::Acquire) != 2 * k + 1 {
                    std::hint::spin_loop();
                }
                line.0.store(2 * k + 2, Ordering::Release);
            }
        });
        core_affinity::set_for_current(core_affinity::CoreId { id: a });
        for round in 0..ROUNDS as u64 {
            let t0 = Instant::now();
            for k in round * TRIPS..(round + 1) * TRIPS {
                line.0.store(2 * k + 1, Ordering::Release);
                while line.0.load(Ordering::Acquire) != 2 * k + 2 {
                    std::hint::spin_loop();
                }
            }
            batches.push(t0.elapsed().as_secs_f64() * 1e9 / TRIPS as f64);
        }
    });
    batches.sort_by(f64::total_cmp);
    println!(
        "core-to-core round trip: {:.0} ns (cores {a} and {b})",
        batches[ROUNDS / 2]
    );
}
