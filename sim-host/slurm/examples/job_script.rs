//! A Slurm job from Rust: the script `sandjumper-slurm` writes for a job of two MPI tasks
//! (printed), and, with `--submit OUT`, the job submitted with `sbatch` into `OUT.slurm/`
//! and waited for (needs Slurm's tools on PATH).
//!
//! Run it with `cargo run -p sandjumper-slurm --example job_script [-- --submit OUT]`.

use std::path::PathBuf;

use sandjumper_slurm::{JobScript, QueueOptions, fresh_job_dir, quote, submit};

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let out = match std::env::args().nth(1).as_deref() {
        Some("--submit") => std::env::args().nth(2).map(PathBuf::from),
        _ => None,
    };
    let message = "hello from a Slurm job";
    let script = JobScript {
        name: "example".into(),
        shape: vec!["--ntasks=2".into()],
        log: PathBuf::from("logs/job.out"),
        cwd: std::env::current_dir()?,
        queue: QueueOptions {
            time: "0:05:00".into(),
            ..QueueOptions::default()
        },
        command: format!("exec srun echo {}\n", quote(message)),
    };
    print!("{}", script.text());
    if let Some(out) = out {
        let dir = fresh_job_dir(&out)?;
        let job = submit(
            &dir,
            &JobScript {
                log: dir.join("logs").join("job.out"),
                ..script
            },
        )?;
        job.wait(&sandjumper_output::Silent)?;
        println!("job {} done; its log is in {}", job.id, dir.display());
    }
    Ok(())
}
