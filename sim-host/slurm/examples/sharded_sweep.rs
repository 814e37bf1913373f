//! The job script of a sweep run as a Slurm job array, built with the library as
//! `sandjumper sweep ... --slurm 4 --slurm-cpus 2` builds it (printed, not submitted: a
//! submission runs this very program again, see `submit_sharded`): the sweep's own
//! arguments without the ones each task sets, then one shard per task.
//!
//! Run it with `cargo run --example sharded_sweep -p sandjumper-slurm`.

use sandjumper_slurm::{JobScript, QueueOptions, quote, shard_task_arguments};

fn main() {
    let argv: Vec<String> = [
        "sandjumper",
        "sweep",
        "--kind",
        "single",
        "--freq",
        "8:14:2",
        "--out",
        "sweep",
        "--slurm",
        "4",
        "--slurm-cpus",
        "2",
    ]
    .iter()
    .map(|s| s.to_string())
    .collect();
    let passed: Vec<String> = shard_task_arguments(&argv, &["sweep"])
        .iter()
        .map(|a| quote(a))
        .collect();
    let script = JobScript {
        name: "sweep".into(),
        shape: vec!["--array=1-4".into(), "--cpus-per-task=2".into()],
        log: "sweep.slurm/logs/task-%a.out".into(),
        cwd: ".".into(),
        queue: QueueOptions::default(),
        command: format!(
            "exec sandjumper sweep {} --shard \"$SLURM_ARRAY_TASK_ID/4\" --threads \
             \"${{SLURM_CPUS_PER_TASK:-1}}\" --out sweep.slurm/shard-\"$SLURM_ARRAY_TASK_ID\"\n",
            passed.join(" ")
        ),
    };
    print!("{}", script.text());
}
