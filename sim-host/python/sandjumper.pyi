"""Simulate the spring-mass jumping robot on granular media (Aguilar & Goldman, Nature
Physics 2016) and analyse its measurements, from Python.

Every function is one call of the project's libraries (the code behind the ``sandjumper``
command line; no subprocess, no command line), with the command line's defaults, checks and
messages. Results come back in memory (dicts, numpy arrays); a folder is written only when
``out`` is given (``track``, ``piv``, the DEM, ``optimize``, campaigns and figures always
write theirs). Bad input raises ``ValueError`` with the command line's message (its flag
written as the argument's name); a wrong type raises ``TypeError`` naming the argument; a
failure after the input was accepted raises ``RuntimeError``. Units are SI unless a name
says otherwise (``freq_hz``, ``window_ms``).

Long calls (``sweep``, ``sweep_slurm``, ``hil``, ``track``, ``piv``, the DEM, ``lammps``,
``optimize``, campaigns, figures, the rig programs) run with the GIL released, so other Python threads run
meanwhile; ``progress`` (a callable ``progress(stage, done, total)``, ``total`` None when
unknown) is told as they go, at most about ten times a second; Ctrl-C (or a notebook's
interrupt) stops them between their steps and raises ``KeyboardInterrupt`` (``sweep``,
``piv``, ``dem_intrude``, ``lammps``, ``optimize`` and campaigns stop part-way; the others
finish their current call first). An exception raised by ``progress`` stops the call the same
way and is raised in its place.
"""

import os
from typing import Any, Callable, Dict, List, Optional, Sequence, Union

import numpy as np
import numpy.typing as npt

__version__: str

PathLike = Union[str, "os.PathLike[str]"]
Params = Union[Dict[str, Dict[str, Any]], PathLike]
Axis = Union[float, str, Sequence[float]]
Progress = Callable[[str, int, Optional[int]], None]

class JumpResult:
    """One jump: ``summary`` and ``series``."""

    summary: Dict[str, Any]
    """Request and metrics, the same keys and values as ``sandjumper jump --json``
    (``jump_height_m``, ``final_jump_height_m``, ``max_depth_m``, ``peak_added_mass_kg``,
    ``peak_motor_force_n``, ``liftoff_time_s``, ``events``, ...)."""
    series: Dict[str, npt.NDArray[Any]]
    """The columns of ``trajectory.csv`` (same names): ``t_s`` (s), ``x_m_m`` (motor, m),
    ``x_r_m`` (rod, m), ``x_f_m`` (foot, m), ``p_m`` (m), ``f_s_n`` (spring force, N),
    ``f_gm_n`` (ground force, N), ``m_a_kg`` (added mass, kg) as float64, and ``mode``
    (ground mode, str)."""

class SweepResult:
    """A sweep: ``columns`` and ``failures``."""

    columns: Dict[str, npt.NDArray[Any]]
    """The columns of ``sweep.csv``: ``kind``, ``model``, ``drive`` (str) and ``phi``,
    ``freq_hz`` (Hz), ``tau_s`` (s), ``jump_height_m``, ``final_jump_height_m``,
    ``max_depth_m`` (m), ``peak_added_mass_kg`` (kg), ``peak_motor_force_n`` (N) as float64,
    in combination order. ``pandas.DataFrame(result.columns)`` is the table."""
    failures: List[Dict[str, Any]]
    """The rows of ``failures.csv``: the combinations that failed, with ``error``."""

class HilResult:
    """One jump through the control loop: ``summary``, ``log``, ``log_metadata``."""

    summary: Dict[str, Any]
    """The same keys and values as ``sandjumper hil --json`` (``wall_time_s`` and
    ``realtime_factor`` are this run's timings)."""
    log: Dict[str, npt.NDArray[Any]]
    """The acquisition log's columns: ``tick``, ``encoder_counts``, ``flags`` (int64;
    ``flags`` is -1 where the log has no value), ``t_s`` (s), ``position_m`` (motor relative
    to the rod, m), ``p_cmd_m`` (m), ``force_cmd_n`` (N), ``current_a`` (A),
    ``camera_frame``, ``rod_height_m`` (m) as float64 with NaN where the log has no value."""
    log_metadata: Dict[str, str]
    """The log's ``# key: value`` lines."""
    tables: Dict[str, Dict[str, npt.NDArray[np.float64]]]
    """What a rig program measured besides its log, columns named like its CSV's header:
    ``rig_intrude``'s ``intrusion`` and ``reintrusion`` (``depth_m``, ``force_n``),
    ``rig_replay``'s ``table`` (``t_s``, ``p_m``: what was uploaded); empty for a jump."""

class RunNotCompleted(RuntimeError):
    """A rig program the controller did not complete cleanly (a fault, or the program cut
    short): the command line's exit status 1. ``result`` is what the run recorded; its
    folder is written first when ``out`` was given. A lockstep ``hil`` run lists its faults
    in its summary instead."""

    result: HilResult

class FolderResult:
    """What a folder-writing analysis wrote, loaded."""

    summary: Any
    """The JSON summary (what ``--json`` prints or ``summary.json`` holds), or None."""
    tables: Dict[str, Dict[str, npt.NDArray[Any]]]
    """Each CSV file of the folder by stem, as columns (float64, NaN for empty cells, or
    str)."""
    arrays: Dict[str, npt.NDArray[np.float64]]
    """Each ``.npy`` file of the folder by stem."""
    path: Optional[str]
    """The output folder, or None when nothing was written (``out`` not given)."""

def params(phi: float = 0.57, overrides: Optional[Params] = None) -> Dict[str, Dict[str, Any]]:
    """The resolved parameters for packing fraction ``phi`` (presets 0.57..=0.62) with
    ``overrides`` on top: the tables ``robot``, ``drive``, ``sand``, ``model`` as
    ``sandjumper params`` prints them (SI units). Round-trips:
    ``params(phi, overrides=params(phi)) == params(phi)``."""

def jump(
    kind: Optional[str] = None,
    freq_hz: Optional[float] = None,
    model: str = "eq4",
    phi: float = 0.57,
    tau_s: Optional[float] = None,
    params: Optional[Params] = None,
    rtol: float = 1e-8,
    stroke: Optional[PathLike] = None,
    out: Optional[PathLike] = None,
) -> JumpResult:
    """Simulate one jump as ``sandjumper jump`` does.

    kind: ``"single"``, ``"stutter"`` or ``"delayed"``. freq_hz: forcing frequency, Hz.
    model: ``"hard"``, ``"eq1-linear"``, ``"eq1"`` or ``"eq4"``. phi: packing fraction.
    tau_s: the delayed stutter's delay, s (required for ``"delayed"``). params: overrides
    (a dict as ``params()`` returns, or a TOML file). rtol: the integrator's relative
    tolerance. stroke: a stroke file (``t_s,p_m``, e.g. ``optimize``'s stroke.csv) instead
    of kind, freq_hz and tau_s. out: also write ``jump --out``'s folder (trajectory.csv,
    params.toml, summary.json, jump.png, jump.svg)."""

def sweep(
    kinds: Union[str, Sequence[str]],
    freqs_hz: Axis,
    phis: Optional[Axis] = None,
    taus_s: Optional[Axis] = None,
    models: Optional[Union[str, Sequence[str]]] = None,
    params: Optional[Params] = None,
    rtol: float = 1e-8,
    link: Optional[str] = None,
    gain_lowering: Optional[float] = None,
    threads: Optional[int] = None,
    out: Optional[PathLike] = None,
    progress: Optional[Progress] = None,
) -> SweepResult:
    """Every combination of kinds, models, packing fractions (default 0.57), delays (s,
    default 0) and frequencies (Hz), in parallel with the GIL released, as
    ``sandjumper sweep`` does. An axis is a number, a sequence, or a range ``"A:B:STEP"``
    (inclusive). link: None (the stroke imposed) or ``"sil"`` (through the controller);
    gain_lowering: with ``"sil"``, the position gain factor during a delay, (0, 1];
    threads: default one per core. out: also write ``sweep --out``'s folder. progress:
    ``("jumps", done, total)``; Ctrl-C stops the sweep between jumps."""

def sweep_slurm(
    tasks: int,
    kinds: Union[str, Sequence[str]],
    freqs_hz: Axis,
    out: PathLike,
    phis: Optional[Axis] = None,
    taus_s: Optional[Axis] = None,
    models: Optional[Union[str, Sequence[str]]] = None,
    params: Optional[Params] = None,
    rtol: float = 1e-8,
    link: Optional[str] = None,
    gain_lowering: Optional[float] = None,
    cpus_per_task: int = 1,
    partition: Optional[str] = None,
    time: str = "1:00:00",
    wait: bool = True,
    program: Optional[PathLike] = None,
    progress: Optional[Progress] = None,
) -> Dict[str, Any]:
    """``sweep`` on a Slurm cluster, as ``sandjumper sweep --slurm TASKS --out OUT`` does: a
    job array of ``tasks`` tasks, one shard each with ``cpus_per_task`` threads, run by
    ``program`` (the ``sandjumper`` binary on the cluster's shared file system; default: the
    one on PATH), in ``partition`` with the time limit ``time`` (Slurm's format). With
    ``wait`` the call waits for the job (Ctrl-C stops waiting; the job runs on) and merges
    the shards into ``out``. Returns ``{"job_id", "dir": the job's folder, "result": the
    merged SweepResult, or None without wait}``."""

def hil(
    kind: Optional[str] = None,
    freq_hz: Optional[float] = None,
    link: str = "sil",
    tau_s: Optional[float] = None,
    gain_lowering: Optional[float] = None,
    model: str = "eq4",
    phi: float = 0.57,
    params: Optional[Params] = None,
    rtol: Optional[float] = None,
    camera_fps: int = 200,
    encoder_noise: float = 0.0,
    firmware: Optional[PathLike] = None,
    stroke: Optional[PathLike] = None,
    progress: Optional[Progress] = None,
    camera: Optional[PathLike] = None,
    out: Optional[PathLike] = None,
    mcap: bool = False,
) -> HilResult:
    """One jump through the control loop against the simulated rig, as ``sandjumper hil``
    does, with the GIL released. link: ``"sil"`` (the core in this process), ``"pil"`` (the
    firmware ELF ``firmware`` in QEMU), ``"f407"`` (the F407 binary on the virtual board) or
    ``"serial:PATH"`` (a board). rtol: the plant's tolerance inside each control period
    (default 1e-6). camera_fps: frames/s (0: none); camera: the rod camera's
    ``camera.toml``. encoder_noise: counts (standard deviation, seeded). out: also write
    ``hil --out``'s folder (mcap: ``acquisition.mcap`` too). A setting that does nothing
    (gain_lowering outside a delay) is a warning on the ``sandjumper`` logger. On the virtual
    board a jump with a fault raises ``RunNotCompleted``."""

def replay(
    log: PathLike,
    model: str = "eq4",
    phi: Optional[float] = None,
    params: Optional[Params] = None,
    rtol: float = 1e-8,
    window_ms: Optional[float] = None,
    allow_gaps: bool = False,
    out: Optional[PathLike] = None,
) -> JumpResult:
    """Replay a CSV acquisition log's encoder record in the simulator (the paper's method),
    as ``sandjumper replay`` does. phi defaults to the log's; window_ms: the Savitzky-Golay
    window for p'' (default 1 ms); allow_gaps: interpolate missing samples (reported)."""

def track(
    frames: PathLike,
    m_per_px: float,
    out: Optional[PathLike] = None,
    progress: Optional[Progress] = None,
    **options: Any,
) -> FolderResult:
    """Track the rod's ball through camera frames and measure the jump height, as
    ``sandjumper track`` does. m_per_px: the camera's scale, m/px. options: the CLI's flags
    by name (``fps=200``, ``log="acquisition.csv"``, ``ball_diameter=0.0127`` (m), ...).
    ``tables["track"]`` holds one row per frame."""

def piv(
    frames: PathLike,
    out: Optional[PathLike] = None,
    progress: Optional[Progress] = None,
    **options: Any,
) -> FolderResult:
    """PIV of side-wall grain videos, as ``sandjumper piv`` does. options: the CLI's flags by
    name (``windows=[64, 32, 16]`` (px), ``overlap=0.5``, ``fps=500``, ``m_per_px=...``,
    ``origin=[x_px, y_px]``, ``foot=...``, ...). ``arrays`` holds the fields as stacks of
    2-D arrays (pair, row, column): ``u_px``, ``v_px`` (px per pair), ``flag``, ``s2n`` and,
    when calibrated, SI velocities, vorticity and shear rate; ``tables["flow"]`` the grain
    momentum and added mass per pair."""

def dem_collide(
    d1_m: float,
    kn: float,
    damping: float,
    speed: float,
    d2_m: Optional[float] = None,
    wall: bool = False,
    **options: Any,
) -> Dict[str, Any]:
    """One head-on binary collision (disk-disk, or disk-wall with ``wall=True``) with the
    paper's contact law, as ``sandjumper dem collide --json`` does. d1_m, d2_m: diameters,
    m (d2_m required unless ``wall``); kn: N/m; damping: N s/m; speed: m/s. options: ``dt=...`` (s), ``density=...``
    (kg/m^3), ``force_step=True``. Returns ``restitution``, ``contact_time_s``,
    ``effective_mass_kg``, ``dt_s``, the analytic values and the errors."""

def dem_bed(out: PathLike, progress: Optional[Progress] = None, **options: Any) -> FolderResult:
    """Prepare a DEM bed, as ``sandjumper dem bed --out OUT`` does. options: the CLI's flags
    by name (``width=0.23``, ``height=0.08`` (m), ``pack=0.8``, ``seed=1``, ``threads=2``,
    ...)."""

def dem_intrude(
    bed: Optional[PathLike],
    out: PathLike,
    progress: Optional[Progress] = None,
    **options: Any,
) -> FolderResult:
    """Run a DEM intrusion, as ``sandjumper dem intrude --bed BED --out OUT`` does. options:
    the CLI's flags by name (``speed=0.1`` (m/s) or ``trajectory="trajectory.csv"``,
    ``depth=0.03`` (m), ``scale_from_foot=0.076`` (a jump's trajectory Froude-scaled to
    ``foot_width``), ``no_frames=True``, ``threads=2``, ``resume=True``, ...)."""

def read_log(path: PathLike, allow_gaps: bool = False) -> Dict[str, Any]:
    """Read and check an acquisition log (CSV or binary) as ``sandjumper log check`` does:
    ``columns`` (as ``HilResult.log``), ``metadata`` and ``summary`` (as
    ``log check --json``)."""

def log_to_mcap(
    log: PathLike, out: PathLike, allow_gaps: bool = False, force: bool = False
) -> Dict[str, Any]:
    """Convert an acquisition log (CSV or binary) to MCAP for Foxglove, Lichtblick and
    PlotJuggler, as ``sandjumper log convert IN OUT --to mcap`` does. Returns what was
    written: ``to`` (``"mcap"``), ``output`` and the conversion's counts."""

def lammps(out: PathLike, progress: Optional[Progress] = None, **options: Any) -> FolderResult:
    """The 3-D intrusion through LAMMPS, as ``sandjumper dem lammps --out OUT`` does (LAMMPS
    and, for more than one rank, mpiexec installed; ``lmp=`` and ``mpiexec=`` name them).
    options: the command's options by name (``preset="small"``, ``speed=0.1`` (m/s) or
    ``trajectory=...``, ``depth=0.02`` (m), ``bed_width=...``, ``ranks=2``,
    ``restart_every=15`` (wall minutes between restart files), ``launcher="srun"``,
    ``sidewall=True`` (the paper's PIV geometry: ``sidewall.csv``), ``scale_from_foot=0.076``,
    ``dump_every=5`` (the grains dumped at every 5th frame; 0: none), ``dump_format="text"``
    (default: ``"gzip"`` where LAMMPS has COMPRESS), ...). A run
    killed resumes from its newest restart file when called again the same way. Ctrl-C
    stops LAMMPS. ``summary`` is ``summary.json``; ``tables``: ``flow``, ``force_depth``,
    ``cone``."""

def lammps_slurm(
    out: PathLike,
    partition: Optional[str] = None,
    time: str = "1:00:00",
    nodes: Optional[int] = None,
    wait: bool = True,
    program: Optional[PathLike] = None,
    progress: Optional[Progress] = None,
    **options: Any,
) -> Dict[str, Any]:
    """``lammps`` as one Slurm job of ``ranks`` MPI tasks, as ``sandjumper dem lammps --slurm``
    does: the job runs ``program`` (default: ``sandjumper`` on PATH) with the same options in
    ``partition``, with the time limit ``time`` (restart files every quarter of it at most),
    over ``nodes`` nodes. LAMMPS is looked for here first. With ``wait`` the call waits and
    loads the folder; a job stopped at its limit keeps ``OUT.unfinished/`` and the same call
    resumes it. Returns ``{"job_id", "dir", "result"}`` (``result`` None without wait)."""

def lammps_read(
    run: PathLike,
    out: PathLike,
    min_speed_ratio: float = 0.3,
    progress: Optional[Progress] = None,
) -> FolderResult:
    """Read a finished LAMMPS run's dumps back into a new folder ``out`` (apart from the
    run), as ``sandjumper dem lammps-read RUN --out OUT`` does: the column's momentum, added
    mass and cone again (min_speed_ratio: the added mass's speed rule). Returns the folder,
    as ``lammps``'s."""

def fit(
    what: str,
    file: PathLike,
    phi: float = 0.57,
    params: Optional[Params] = None,
    out: Optional[PathLike] = None,
    **options: Any,
) -> Dict[str, Any]:
    """Fit model parameters to measurements, as ``sandjumper fit WHAT FILE --json`` does.
    what: ``"intrusion"`` (``depth_m,force_n``: k1, k2, delta, or kappa, l_re),
    ``"added-mass"`` (``depth_m,added_mass_kg``: mu, C), ``"drag"`` (alpha per phi) or
    ``"inertial"`` (b per phi) from a sweep.csv of measured heights. out: also write the
    fitted values as a params TOML file. options: ``reintrusion=True``, ``first=True``,
    ``z_start=...`` (m); ``exclude_deepest=...``; ``model=...``, ``height="jump"`` or
    ``"final"``, ``rtol=...``. Returns ``fits`` (param, value, stderr, phi) and
    ``residual_rms``."""

def optimize(
    out: PathLike,
    objective: str = "height",
    model: str = "eq4",
    phi: Optional[float] = None,
    params: Optional[Params] = None,
    progress: Optional[Progress] = None,
    phi_range: Optional[str] = None,
    phi_points: Optional[int] = None,
    start_from: Sequence[PathLike] = (),
    **options: Any,
) -> FolderResult:
    """Search for the best stroke within the rig's limits, as ``sandjumper optimize --out
    OUT`` does: CMA-ES over the stroke family, beside the best of the paper's strokes, both
    re-run through the controller on ``verify``'s links. objective: ``"height"``,
    ``"final-height"``, ``"com-rise"``, ``"height-per-peak-power"`` or ``"height-per-energy"``. options: the
    command's by name (``max_stroke=0.025`` (m), ``max_rise=1.0`` (m),
    ``max_spring_compression=...`` (m), ``evaluations=192000``, ``moves=4``,
    ``verify="sil"`` or ``["sil", "pil"]`` or ``"none"``, ``threads=...``, ``seed=1``, ...).
    Ctrl-C stops the search after its current generation; the checkpoint beside ``out``
    resumes it. phi: the packing fraction (0.57 when neither it nor ``phi_range`` is given).
    phi_range: ``"0.57:0.62"`` (instead of ``phi``), a bed known to a range: the worst case
    over ``phi_points`` (5) beds is maximised (``tables["beds"]``, ``over_beds``).
    start_from: earlier searches' folders whose answers this search also starts from (and
    keeps as candidates). ``summary`` is ``optimize --json``'s (``validity``: where the
    answer leaves the paper's measured regime); ``tables["stroke"]`` the stroke."""

def campaign_run(
    file: PathLike,
    out: PathLike,
    link: Optional[str] = None,
    firmware: Optional[PathLike] = None,
    stop_after: Optional[int] = None,
    progress: Optional[Progress] = None,
    port: Optional[PathLike] = None,
) -> Dict[str, Any]:
    """Run a campaign file, as ``sandjumper campaign run FILE --out OUT`` does. link:
    the controller with the simulated bed (``"sil"`` or ``"pil"``, the ELF ``firmware`` in
    QEMU); port: instead, the rig's board on a serial port with its bed apparatus.
    stop_after: stop after that many points (resumable); Ctrl-C stops after the current
    point. Returns the session's outcome (``ended``: ``"finished"`` or ``"stopped"``,
    ``done``, ...)."""

def campaign_resume(
    dir: PathLike,
    firmware: Optional[PathLike] = None,
    stop_after: Optional[int] = None,
    progress: Optional[Progress] = None,
) -> Dict[str, Any]:
    """Resume the campaign in ``dir``, as ``sandjumper campaign resume DIR`` does."""

def campaign_status(dir: PathLike) -> Dict[str, Any]:
    """Where the campaign in ``dir`` stands, as ``sandjumper campaign status DIR --json``
    prints it."""

def figures(
    out: PathLike,
    quick: bool = False,
    threads: Optional[int] = None,
    rtol: float = 1e-8,
    progress: Optional[Progress] = None,
) -> FolderResult:
    """The paper's figures from the model, as ``sandjumper figures --out OUT`` does (quick:
    coarser sweeps). ``tables`` holds each figure's data."""

def figures_dem(
    out: PathLike,
    phi: Optional[float] = None,
    freq_hz: Optional[float] = None,
    tau_s: Optional[float] = None,
    foot_width: Optional[float] = None,
    full_model: Optional[bool] = None,
    threads: Optional[int] = None,
    bed_max_time: Optional[float] = None,
    progress: Optional[Progress] = None,
) -> FolderResult:
    """The supplement's DEM figures, as ``sandjumper figures dem --out OUT`` does; foot_width
    (m) scales the comparison down. ``summary`` is ``summary.json``."""

def rig_status(
    link: Optional[str] = None,
    port: Optional[str] = None,
    firmware: Optional[PathLike] = None,
    virtual_board: Optional[PathLike] = None,
    board_pace: Optional[float] = None,
    drive_calibration: Optional[PathLike] = None,
) -> Dict[str, Any]:
    """The controller's state, phase, latched fault and counters, as ``sandjumper rig status
    --json`` prints them. The controller: ``link`` (``"sil"``, the default, ``"pil"``,
    ``"f407"`` or ``"serial:PATH"``) or a board's serial ``port``; firmware: the ELF (pil,
    f407); virtual_board: its program; board_pace: the virtual board's pace (factor of real
    time); drive_calibration: a calibration file loaded at start."""

def rig_jump(
    kind: str,
    freq_hz: float,
    link: Optional[str] = None,
    tau_s: Optional[float] = None,
    model: str = "eq4",
    phi: float = 0.57,
    params: Optional[Params] = None,
    camera_fps: int = 200,
    firmware: Optional[PathLike] = None,
    out: Optional[PathLike] = None,
    progress: Optional[Progress] = None,
    port: Optional[str] = None,
    virtual_board: Optional[PathLike] = None,
    board_pace: Optional[float] = None,
    drive_calibration: Optional[PathLike] = None,
    mcap: bool = False,
    camera: Optional[PathLike] = None,
) -> HilResult:
    """One jump through the rig tool, as ``sandjumper rig jump`` does, on the controller
    ``rig_status`` describes. ``summary`` is ``rig jump --json``'s; ``log`` the acquisition
    log's columns. out: also write the run's folder (mcap: ``acquisition.mcap`` too). A jump
    with a fault raises ``RunNotCompleted``."""

def rig_intrude(
    link: Optional[str] = None,
    start: float = -0.02,
    depth: float = 0.02,
    withdraw: float = 0.005,
    reintrusion_depth: float = 0.03,
    speed: float = 0.01,
    hold: float = 0.5,
    bin: float = 0.00025,
    model: str = "eq4",
    phi: float = 0.57,
    params: Optional[Params] = None,
    out: Optional[PathLike] = None,
    mcap: bool = False,
    progress: Optional[Progress] = None,
    port: Optional[str] = None,
    firmware: Optional[PathLike] = None,
    virtual_board: Optional[PathLike] = None,
    board_pace: Optional[float] = None,
    drive_calibration: Optional[PathLike] = None,
) -> HilResult:
    """The slow-intrusion program (the paper's ``F_p(z)`` measurement), as ``sandjumper rig
    intrude`` does: from ``start`` (m, the surface) down ``depth`` (m), back ``withdraw``
    (m), down to ``reintrusion_depth`` (m), at ``speed`` (m/s), ``hold`` (s) between, force
    binned every ``bin`` (m). ``tables["intrusion"]`` and ``tables["reintrusion"]`` are the
    curves (``depth_m``, ``force_n``). A run with a fault raises ``RunNotCompleted``."""

def rig_replay(
    log: Optional[PathLike] = None,
    stroke: Optional[PathLike] = None,
    link: Optional[str] = None,
    scale: float = 1.0,
    time_stretch: float = 1.0,
    clip: Optional[Sequence[float]] = None,
    table_rate: Optional[int] = None,
    allow_gaps: bool = False,
    model: str = "eq4",
    phi: float = 0.57,
    params: Optional[Params] = None,
    out: Optional[PathLike] = None,
    mcap: bool = False,
    progress: Optional[Progress] = None,
    port: Optional[str] = None,
    firmware: Optional[PathLike] = None,
    virtual_board: Optional[PathLike] = None,
    board_pace: Optional[float] = None,
    drive_calibration: Optional[PathLike] = None,
) -> HilResult:
    """A recorded motor trajectory (an acquisition ``log``) or a ``stroke`` file run on the
    rig, as ``sandjumper rig replay`` does: edited by ``scale``, ``time_stretch`` and
    ``clip`` (``(start_s, end_s)``), resampled at ``table_rate`` (Hz, 10..=10000), checked
    against the rig's limits before anything is sent. ``tables["table"]`` is what was
    uploaded (``t_s``, ``p_m``). A run with a fault raises ``RunNotCompleted``."""

def rig_calibrate_drive(
    zero_code: int,
    codes_per_newton: float,
    link: Optional[str] = None,
    port: Optional[str] = None,
    save: Optional[PathLike] = None,
    firmware: Optional[PathLike] = None,
    virtual_board: Optional[PathLike] = None,
    board_pace: Optional[float] = None,
) -> Dict[str, Any]:
    """Set the drive's force calibration on the controller, as ``sandjumper rig
    calibrate-drive`` does (save: also write it as a calibration file). Returns ``{"link",
    "zero_code", "codes_per_newton"}``."""

def rig_acknowledge_reset(
    link: Optional[str] = None,
    port: Optional[str] = None,
    firmware: Optional[PathLike] = None,
    virtual_board: Optional[PathLike] = None,
    board_pace: Optional[float] = None,
) -> Dict[str, Any]:
    """Acknowledge the controller's reset so that it allows Arm again, as ``sandjumper rig
    acknowledge-reset`` does. Returns ``{"link", "reset_cause"}``."""

def rig_flash(
    port: Optional[str] = None,
    link: Optional[str] = None,
    firmware: Optional[PathLike] = None,
    probe_rs: Optional[PathLike] = None,
) -> Dict[str, Any]:
    """Write the F407 firmware (``firmware``, the release ELF by default) to the board on
    ``port`` with probe-rs (``probe_rs``: its path), as ``sandjumper rig flash`` does.
    Returns ``{"flashed", "elf", "port", "why"}``; a simulated link has nothing to flash
    (``why`` says so)."""

def sweep_merge(dirs: List[PathLike], out: PathLike) -> SweepResult:
    """Merge the folders of a sweep's shards (``sweep --shard K/N``) into ``out``, as
    ``sandjumper merge DIR... --out OUT`` does (every combination present once, the shards of
    one sweep only); returns the merged sweep."""

def camera_scale(
    frames: PathLike,
    log: PathLike,
    ball_px: float,
    roi: Optional[Sequence[int]] = None,
    progress: Optional[Progress] = None,
) -> Dict[str, Any]:
    """The camera's scale (m/px) from a slow motor move, as ``sandjumper camera-scale FRAMES
    --log LOG --ball-px PX --json`` does: the ball tracked through the frames against the
    encoder. ball_px: the ball's diameter in the frames, px; roi: ``[x, y, w, h]``."""

def piv_synthetic(out: PathLike, **options: Any) -> str:
    """Grain images with a known motion, as ``sandjumper piv-synthetic --out OUT`` does:
    ``field`` (``"shift"``, ``"shear"``, ``"rotation"``, ``"cone"``), ``magnitude`` (px),
    ``size`` (``"WxH"`` or ``(w, h)``), ``frames``, ``grain_px``, ``noise``, ``seed``; or a
    real ``image`` moved by ``shift=[dx, dy]`` px. Returns the folder written."""
