//! The job script of a command run as a Slurm job array of four shards, two CPUs each (printed,
//! not submitted: [`sandjumper_slurm::submit_sharded`] submits it and waits): the program and
//! its words, then each task's shard, threads and folder. `sandjumper sweep --slurm 4
//! --slurm-cpus 2` builds its words from the typed sweep
//! (`sandjumper_study::sweep::cluster::run_on_slurm`), every axis and option written out.
//!
//! Run it with `cargo run --example sharded_sweep -p sandjumper-slurm`.

use std::path::Path;

use sandjumper_slurm::{QueueOptions, ShardedJob};

fn main() {
    let args: Vec<String> = ["sweep", "--kind", "single", "--freq", "8:14:2"]
        .iter()
        .map(|s| s.to_string())
        .collect();
    let job = ShardedJob {
        name: "sweep",
        program: Path::new("/opt/sandjumper/bin/sandjumper"),
        args: &args,
        files: &[],
        tasks: 4,
        cpus: 2,
        out: Path::new("sweep"),
        expect: "sweep.toml",
        queue: QueueOptions::default(),
    };
    match job.script(Path::new("/home/me/sweep.slurm"), Path::new("/home/me")) {
        Ok(script) => print!("{}", script.text()),
        Err(e) => {
            eprintln!("error: {e}");
            std::process::exit(2);
        }
    }
}
