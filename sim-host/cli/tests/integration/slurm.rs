//! `sweep --slurm` and `dem lammps --slurm` on a real single-node Slurm cluster: Debian's
//! `slurm-wlm` and `munge`, their daemons configured and started by this test in a temporary
//! directory (no mock of `sbatch`). A small sweep goes through a 3-task job array and its
//! merged result must equal the same sweep run here, byte for byte; a task cancelled before
//! it runs must be reported and nothing merged. A small 3-D DEM run goes through a job of two
//! MPI tasks (when LAMMPS is here: `dem_lammps.rs` says where it looks), and a job the
//! scheduler rejects is refused with exit status 2.
//!
//! Needs root (the daemons run as root here) and `munged`, `slurmctld`, `slurmd`, `sbatch`,
//! `squeue`, `scontrol`, `scancel`, `sinfo` on PATH: skipped with a message otherwise, failing
//! under `CI` (`.ci/run` installs them).

use std::io::{BufRead, BufReader};
use std::path::{Path, PathBuf};
use std::process::{Command, Stdio};
use std::time::{Duration, Instant};

use crate::common;
use common::read;

/// Skip (or, under CI, fail) with `why`.
fn skip_or_fail(why: &str) {
    assert!(
        std::env::var_os("CI").is_none(),
        "the Slurm test cannot run under CI: {why}"
    );
    eprintln!("skipped: {why}");
}

fn found(tool: &str) -> bool {
    [
        "/usr/sbin",
        "/usr/bin",
        "/sbin",
        "/bin",
        "/usr/local/bin",
        "/usr/local/sbin",
    ]
    .iter()
    .any(|d| Path::new(d).join(tool).is_file())
}

fn free_port() -> u16 {
    std::net::TcpListener::bind("127.0.0.1:0")
        .unwrap()
        .local_addr()
        .unwrap()
        .port()
}

/// A one-node cluster in a temporary directory; its daemons are stopped when dropped.
struct Cluster {
    dir: tempfile::TempDir,
    conf: PathBuf,
}

impl Cluster {
    fn start() -> Result<Self, String> {
        let dir = tempfile::tempdir().map_err(|e| e.to_string())?;
        let d = dir.path();
        for sub in ["munge", "state", "spool", "log"] {
            std::fs::create_dir_all(d.join(sub)).map_err(|e| e.to_string())?;
        }
        let key = d.join("munge/munge.key");
        let bytes: Vec<u8> = (0..1024u32)
            .map(|i| (i.wrapping_mul(2654435761) >> 13) as u8)
            .collect();
        std::fs::write(&key, bytes).map_err(|e| e.to_string())?;
        use std::os::unix::fs::PermissionsExt;
        std::fs::set_permissions(&key, std::fs::Permissions::from_mode(0o600))
            .map_err(|e| e.to_string())?;
        let socket = d.join("munge/munge.socket");
        let status = Command::new("munged")
            .arg("-f")
            .arg(format!("--key-file={}", key.display()))
            .arg(format!("--socket={}", socket.display()))
            .arg(format!(
                "--pid-file={}",
                d.join("munge/munged.pid").display()
            ))
            .arg(format!(
                "--log-file={}",
                d.join("munge/munged.log").display()
            ))
            .arg(format!(
                "--seed-file={}",
                d.join("munge/munged.seed").display()
            ))
            .status()
            .map_err(|e| format!("munged: {e}"))?;
        if !status.success() {
            return Err(format!("munged failed: {status}"));
        }
        let host = String::from_utf8(
            Command::new("hostname")
                .arg("-s")
                .output()
                .map_err(|e| e.to_string())?
                .stdout,
        )
        .map_err(|e| e.to_string())?
        .trim()
        .to_string();
        let cpus = std::thread::available_parallelism().map_or(1, |n| n.get());
        let p = |s: &str| d.join(s).display().to_string();
        let conf_text = format!(
            "ClusterName=sandjumper-test\nSlurmctldHost={host}\nSlurmUser=root\nSlurmdUser=root\n\
             SlurmctldPort={}\nSlurmdPort={}\nAuthType=auth/munge\nAuthInfo=socket={}\n\
             CryptoType=crypto/munge\nStateSaveLocation={}\nSlurmdSpoolDir={}\n\
             SlurmctldPidFile={}\nSlurmdPidFile={}\nSlurmctldLogFile={}\nSlurmdLogFile={}\n\
             ProctrackType=proctrack/linuxproc\nTaskPlugin=task/none\n\
             JobAcctGatherType=jobacct_gather/none\nAccountingStorageType=accounting_storage/none\n\
             SchedulerType=sched/builtin\nSelectType=select/cons_tres\nSelectTypeParameters=CR_Core\n\
             MpiDefault=none\nReturnToService=2\nNodeName={host} CPUs={cpus} State=UNKNOWN\n\
             PartitionName=debug Nodes=ALL Default=YES MaxTime=INFINITE State=UP\n",
            free_port(),
            free_port(),
            socket.display(),
            p("state"),
            p("spool"),
            p("slurmctld.pid"),
            p("slurmd.pid"),
            p("log/slurmctld.log"),
            p("log/slurmd.log"),
        );
        let conf = d.join("slurm.conf");
        std::fs::write(&conf, conf_text).map_err(|e| e.to_string())?;
        let cluster = Self { dir, conf };
        for daemon in ["slurmctld", "slurmd"] {
            let status = Command::new(daemon)
                .arg("-f")
                .arg(&cluster.conf)
                .env("SLURM_CONF", &cluster.conf)
                .status()
                .map_err(|e| format!("{daemon}: {e}"))?;
            if !status.success() {
                return Err(format!("{daemon} failed: {status}\n{}", cluster.logs()));
            }
        }
        let start = Instant::now();
        loop {
            let out = cluster
                .command("sinfo")
                .args(["-h", "-o", "%T"])
                .output()
                .map_err(|e| e.to_string())?;
            if String::from_utf8_lossy(&out.stdout).trim() == "idle" {
                return Ok(cluster);
            }
            if start.elapsed() > Duration::from_secs(60) {
                return Err(format!("the node never became idle\n{}", cluster.logs()));
            }
            std::thread::sleep(Duration::from_millis(300));
        }
    }

    fn command(&self, program: &str) -> Command {
        let mut c = Command::new(program);
        c.env("SLURM_CONF", &self.conf);
        c
    }

    fn logs(&self) -> String {
        ["log/slurmctld.log", "log/slurmd.log", "munge/munged.log"]
            .iter()
            .map(|f| {
                format!(
                    "{f}:\n{}",
                    std::fs::read_to_string(self.dir.path().join(f)).unwrap_or_default()
                )
            })
            .collect()
    }
}

impl Drop for Cluster {
    fn drop(&mut self) {
        for pid in ["slurmd.pid", "slurmctld.pid", "munge/munged.pid"] {
            if let Ok(p) = std::fs::read_to_string(self.dir.path().join(pid)) {
                let _ = Command::new("kill").arg(p.trim()).status();
            }
        }
    }
}

/// The sweep, with the parameter overrides `params` (a stiffer spring: a job that lost them
/// would give other heights than the local sweep).
fn sweep_args(out: &Path, params: &Path) -> Vec<String> {
    [
        "sweep",
        "--kind",
        "single,stutter",
        "--freq",
        "8:12:0.5",
        "--phi",
        "0.57:0.58:0.01",
        "--params",
    ]
    .iter()
    .map(|s| s.to_string())
    .chain([params.display().to_string(), "--out".into()])
    .chain([out.display().to_string()])
    .collect()
}

#[test]
fn a_sweep_through_a_slurm_job_array_equals_the_local_sweep_and_a_failed_task_is_reported() {
    let is_root = Command::new("id")
        .arg("-u")
        .output()
        .map(|o| String::from_utf8_lossy(&o.stdout).trim() == "0")
        .unwrap_or(false);
    if !is_root {
        return skip_or_fail("the test cluster's daemons need root");
    }
    let missing: Vec<&str> = [
        "munged",
        "slurmctld",
        "slurmd",
        "sbatch",
        "squeue",
        "scontrol",
        "scancel",
        "sinfo",
    ]
    .into_iter()
    .filter(|t| !found(t))
    .collect();
    if !missing.is_empty() {
        return skip_or_fail(&format!(
            "Slurm is not installed ({} missing; Debian: apt-get install slurm-wlm munge)",
            missing.join(", ")
        ));
    }
    let cluster = Cluster::start().unwrap_or_else(|e| panic!("cannot start the test cluster: {e}"));
    let work = tempfile::tempdir().unwrap();
    let exe = env!("CARGO_BIN_EXE_sandjumper");
    let params = work.path().join("stiffer.toml");
    std::fs::write(&params, "[robot]\nspring_stiffness_n_m = 3900.0\n").unwrap();

    // The same sweep, here and through a 3-task job array.
    let local = work.path().join("local");
    let out = Command::new(exe)
        .args(sweep_args(&local, &params))
        .output()
        .unwrap();
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    let slurm = work.path().join("slurm");
    let out = cluster
        .command(exe)
        .args(sweep_args(&slurm, &params))
        .args(["--slurm", "3"])
        .output()
        .unwrap();
    let stderr = String::from_utf8_lossy(&out.stderr);
    assert!(out.status.success(), "{stderr}\n{}", cluster.logs());
    assert!(stderr.contains("submitted Slurm job"), "{stderr}");
    assert_eq!(
        read(&local.join("sweep.csv")),
        read(&slurm.join("sweep.csv"))
    );
    assert_eq!(
        read(&local.join("failures.csv")),
        read(&slurm.join("failures.csv"))
    );
    let job_dir = work.path().join("slurm.slurm");
    for i in 1..=3 {
        assert!(
            job_dir.join(format!("shard-{i}/sweep.toml")).is_file(),
            "shard {i}"
        );
    }
    assert!(read(&job_dir.join("job.sbatch")).contains("#SBATCH --array=1-3"));
    // The tasks read the job folder's copy of the overrides; the merged sweep names the file
    // the user gave, as the local one does.
    assert_eq!(
        read(&job_dir.join("params.toml")),
        read(&params),
        "the overrides' copy"
    );
    let meta = read(&slurm.join("sweep.toml"));
    assert!(
        meta.contains("stiffer.toml") && !meta.contains(".slurm"),
        "{meta}"
    );

    // A task cancelled before it starts: tasks take the whole node (one at a time), so the
    // third is still pending when it is cancelled.
    let failed = work.path().join("failed");
    let mut child = cluster
        .command(exe)
        .args(sweep_args(&failed, &params))
        .args(["--slurm", "3", "--slurm-cpus"])
        .arg(
            std::thread::available_parallelism()
                .map_or(1, |n| n.get())
                .to_string(),
        )
        .stderr(Stdio::piped())
        .stdout(Stdio::null())
        .spawn()
        .unwrap();
    let mut lines = BufReader::new(child.stderr.take().unwrap()).lines();
    let first = lines.next().unwrap().unwrap();
    let job = first
        .split_whitespace()
        .nth(3)
        .unwrap_or_else(|| panic!("no job id in `{first}`"))
        .to_string();
    let cancel = cluster
        .command("scancel")
        .arg(format!("{job}_3"))
        .status()
        .unwrap();
    assert!(cancel.success());
    let rest: Vec<String> = lines.map_while(Result::ok).collect();
    let status = child.wait().unwrap();
    let rest = rest.join("\n");
    assert_eq!(status.code(), Some(1), "{rest}");
    assert!(rest.contains("1 of 3 task(s) did not succeed"), "{rest}");
    assert!(
        rest.contains("task 3:") && rest.contains("nothing merged"),
        "{rest}"
    );
    assert!(!failed.exists(), "nothing merged");

    // A job Slurm rejects (no such partition): refused, exit 2, nothing written.
    let rejected = work.path().join("rejected");
    let out = cluster
        .command(exe)
        .args(sweep_args(&rejected, &params))
        .args(["--slurm", "2", "--slurm-partition", "no-such-partition"])
        .output()
        .unwrap();
    let stderr = String::from_utf8_lossy(&out.stderr);
    assert_eq!(out.status.code(), Some(2), "{stderr}");
    assert!(stderr.contains("Slurm refused the job"), "{stderr}");
    assert!(!rejected.exists());
    assert!(
        !work.path().join("rejected.slurm").exists(),
        "nothing left of it"
    );

    // The 3-D DEM as one job of two MPI tasks: a jump's push-off (a table trajectory) into
    // a small bed.
    let Some(lmp) = common::lammps() else {
        return;
    };
    let jump = work.path().join("jump");
    let out = Command::new(exe)
        .args([
            "jump", "--kind", "stutter", "--freq", "10", "--model", "eq4", "--phi", "0.57", "--out",
        ])
        .arg(&jump)
        .output()
        .unwrap();
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    // The small preset in a 40 x 40 x 30 mm bed on 2 ranks through Slurm into `out`.
    let small_dem = |out: &Path| {
        let mut c = cluster.command(exe);
        c.args(["dem", "lammps", "--preset", "small", "--bed-width", "0.04"])
            .args(["--bed-depth", "0.03", "--ranks", "2", "--slurm", "--lmp"])
            .arg(&lmp)
            .arg("--out")
            .arg(out);
        c
    };
    let dem = work.path().join("dem");
    let out = small_dem(&dem)
        .args(["--episode", "push-off"])
        .arg("--trajectory")
        .arg(jump.join("trajectory.csv"))
        .arg("--json")
        .output()
        .unwrap();
    let stderr = String::from_utf8_lossy(&out.stderr);
    let log = read_or_empty(&work.path().join("dem.slurm/logs/job.out"));
    assert!(out.status.success(), "{stderr}\n{log}\n{}", cluster.logs());
    assert!(stderr.contains("submitted Slurm job"), "{stderr}");
    let sbatch = read(&work.path().join("dem.slurm/job.sbatch"));
    assert!(sbatch.contains("#SBATCH --ntasks=2"));
    // --json prints the job's summary once it is done.
    let summary: serde_json::Value = serde_json::from_slice(&out.stdout).unwrap();
    assert_eq!(
        summary,
        serde_json::from_str::<serde_json::Value>(&read(&dem.join("summary.json"))).unwrap()
    );
    // The stutter's push-off (its table, from the surface): its length at 500 frames/s and
    // its deepest sample.
    let push_off =
        sandjumper_dem::intruder::Trajectory::push_off_from_csv(&jump.join("trajectory.csv"))
            .unwrap();
    let sandjumper_dem::intruder::Trajectory::Table { depth_m, .. } = &push_off else {
        panic!("a table")
    };
    let deepest = depth_m.iter().copied().fold(f64::MIN, f64::max);
    let frames = summary["frames"].as_u64().unwrap() as f64;
    let expected = (push_off.duration_s() * 500.0).ceil() + 1.0;
    assert!(
        (frames - expected).abs() <= 1.0,
        "{frames} frames, {expected} expected"
    );
    let depth = summary["max_depth_m"].as_f64().unwrap();
    assert!(
        (depth - deepest).abs() < 1e-6,
        "{depth} m, the table {deepest} m"
    );
    assert!(read(&dem.join("lammps/log.intrude")).contains("on 2 procs"));
    // Its ranks started by MPICH's mpiexec, whose Hydra found the allocation and launched its
    // proxies as Slurm job steps through srun, as one MPI world of two.
    let manifest = read(&dem.join("lammps/run.toml"));
    assert!(manifest.contains("launcher = \"mpiexec\""), "{manifest}");
    let grid: u64 = read(&dem.join("lammps/log.intrude"))
        .lines()
        .find(|l| l.contains("MPI processor grid"))
        .unwrap_or("")
        .split_whitespace()
        .filter_map(|w| w.parse::<u64>().ok())
        .product();
    assert_eq!(grid, 2, "one world of two ranks");
    let job: String = stderr
        .split("submitted Slurm job ")
        .nth(1)
        .and_then(|r| r.split_whitespace().next())
        .unwrap()
        .into();
    assert!(
        cluster
            .logs()
            .contains(&format!("launch task StepId={job}.0 request")),
        "no job step through srun in job {job}: {}",
        cluster.logs()
    );

    // A run longer than its job's time limit (1 minute): killed by Slurm, it keeps its
    // unfinished folder; the same command submitted again resumes it from its newest restart
    // file and finishes. On the first run's bed (no settle: the minute goes to the
    // intrusion), restart files every 3 s of wall time (a quarter of the limit would be 15 s).
    let long = work.path().join("long");
    let submit_long = |time: &str| {
        small_dem(&long)
            .args([
                "--speed",
                "0.01",
                "--depth",
                "0.008",
                "--restart-every",
                "0.05",
            ])
            .arg("--bed")
            .arg(&dem)
            .args(["--slurm-time", time])
            .output()
            .unwrap()
    };
    let started = Instant::now();
    let out = submit_long("1");
    let took = started.elapsed();
    let stderr = String::from_utf8_lossy(&out.stderr);
    let intrude_log = read_or_empty(&work.path().join("long.unfinished/lammps/log.intrude"));
    let intrude_tail: Vec<&str> = intrude_log.lines().rev().take(5).collect();
    let first_log = read_or_empty(&work.path().join("long.slurm/logs/job.out"));
    let first_restarts: Vec<String> =
        std::fs::read_dir(work.path().join("long.unfinished/lammps/restart"))
            .map(|d| {
                d.filter_map(Result::ok)
                    .map(|e| e.file_name().to_string_lossy().into_owned())
                    .collect()
            })
            .unwrap_or_default();
    assert!(
        first_restarts.iter().any(|f| f.starts_with("intrude.")),
        "no restart file of the intrusion within the limit ({took:?}): {first_restarts:?}\n\
         {first_log}\n{intrude_tail:?}\n{}",
        cluster.logs()
    );
    assert_eq!(out.status.code(), Some(1), "{stderr}");
    // Slurm stops the LAMMPS step and then the job: the job ends TIMEOUT, or FAILED when
    // sandjumper saw its LAMMPS stopped and exited first.
    assert!(
        stderr.contains("TIMEOUT") || stderr.contains("Force Terminated"),
        "{stderr}"
    );
    assert!(
        stderr.contains("long.unfinished") && stderr.contains("the same command resumes it"),
        "{stderr}"
    );
    assert!(!long.exists());
    let out = submit_long("10");
    let stderr = String::from_utf8_lossy(&out.stderr);
    let log = read_or_empty(&work.path().join("long.slurm/logs/job.out"));
    assert!(out.status.success(), "{stderr}\n{log}");
    assert!(log.contains("resuming the unfinished run"), "{log}");
    assert!(
        log.contains("resumed from its restart file of step"),
        "{log}"
    );
    assert!(long.join("summary.json").is_file());
    assert!(!work.path().join("long.unfinished").exists());
}

fn read_or_empty(p: &Path) -> String {
    std::fs::read_to_string(p).unwrap_or_default()
}
