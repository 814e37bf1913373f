"""The Python module against the CLI: the same inputs give the same JSON and CSV values,
arrays have the right dtypes and lengths, bad input raises with the CLI's message, and a
sweep releases the GIL.

The CLI is ``target/debug/sandjumper`` of this workspace (or ``$SANDJUMPER_BIN``); build it
first with ``cargo build -p sandjumper-cli``.
"""

import csv
import json
import math
import os
import pathlib
import re
import subprocess
import threading
import time

import numpy as np
import pytest

import sandjumper

REPO = pathlib.Path(__file__).resolve().parents[3]
CLI = os.environ.get("SANDJUMPER_BIN", str(REPO / "target" / "debug" / "sandjumper"))


def cli(*args, check=True):
    out = subprocess.run([CLI, *map(str, args)], capture_output=True, text=True)
    if check:
        assert out.returncode == 0, out.stderr
    return out


def cli_json(*args):
    return json.loads(cli(*args, "--json").stdout)


def read_csv(path):
    """A CSV file's columns as lists of text."""
    with open(path, newline="") as f:
        lines = [l for l in f if not l.startswith("#")]
    rows = list(csv.reader(lines))
    return {name: [r[i] for r in rows[1:]] for i, name in enumerate(rows[0])}


def same_numbers(texts, array):
    """Every CSV cell equals the array's value exactly (empty cells are NaN)."""
    assert len(texts) == len(array)
    for t, v in zip(texts, array):
        if t == "":
            assert math.isnan(v)
        else:
            assert float(t) == v, (t, v)


def test_version_and_stubs_ship():
    assert sandjumper.__version__
    pkg = pathlib.Path(sandjumper.__file__).parent
    assert (pkg / "__init__.pyi").exists() or (pkg.parent / "sandjumper.pyi").exists()
    assert "freq_hz" in (sandjumper.jump.__doc__ or "")


def test_jump_equals_the_cli(tmp_path):
    r = sandjumper.jump("delayed", 12.0, tau_s=0.05, phi=0.6)
    cli("jump", "--kind", "delayed", "--freq", 12, "--tau", 0.05, "--phi", 0.6,
        "--out", tmp_path / "j")
    expected = cli_json("jump", "--kind", "delayed", "--freq", 12, "--tau", 0.05, "--phi", 0.6)
    assert r.summary == expected
    assert r.summary == json.loads((tmp_path / "j" / "summary.json").read_text())
    table = read_csv(tmp_path / "j" / "trajectory.csv")
    assert list(r.series) == list(table)
    for name, texts in table.items():
        column = r.series[name]
        if name == "mode":
            assert column.dtype.kind == "U"
            assert list(column) == texts
        else:
            assert column.dtype == np.float64
            same_numbers(texts, column)


def test_jump_with_overrides_equals_the_cli_with_a_params_file(tmp_path):
    overrides = {"robot": {"spring_stiffness_n_m": 2500.0}}
    path = tmp_path / "p.toml"
    path.write_text("[robot]\nspring_stiffness_n_m = 2500.0\n")
    expected = cli_json("jump", "--kind", "single", "--freq", 9, "--params", path)
    assert sandjumper.jump("single", 9, params=overrides).summary == expected
    assert sandjumper.jump("single", 9, params=str(path)).summary == expected
    assert sandjumper.jump("single", 9, params=path).summary == expected
    assert expected != cli_json("jump", "--kind", "single", "--freq", 9)


def test_params_round_trip_and_equal_the_cli():
    p = sandjumper.params(0.6)
    assert set(p) == {"robot", "drive", "sand", "model"}
    assert sandjumper.params(0.6, overrides=p) == p
    changed = sandjumper.params(0.6, overrides={"sand": {"k1_n_m": 1234.0}})
    assert changed["sand"]["k1_n_m"] == 1234.0
    assert sandjumper.params(0.6, overrides=changed) == changed
    try:
        import tomllib
    except ImportError:  # Python < 3.11
        tomllib = pytest.importorskip("tomli")
    assert tomllib.loads(cli("params", "--phi", 0.6).stdout) == p


def test_sweep_equals_the_cli_csv(tmp_path):
    r = sandjumper.sweep(["single", "stutter"], "8:12:2", phis=[0.57, 0.6], models=["eq1", "eq4"])
    cli("sweep", "--kind", "single,stutter", "--freq", "8:12:2", "--phi", "0.57:0.6:0.03",
        "--model", "eq1,eq4", "--out", tmp_path / "s")
    table = read_csv(tmp_path / "s" / "sweep.csv")
    assert list(r.columns) == list(table)
    n = 2 * 3 * 2 * 2
    for name, texts in table.items():
        column = r.columns[name]
        assert len(column) == n
        if name in ("kind", "model", "drive"):
            assert column.dtype.kind == "U"
            assert list(column) == texts
        else:
            assert column.dtype == np.float64
            same_numbers(texts, column)
    assert r.failures == []


def test_sweep_through_sil_names_its_drive():
    r = sandjumper.sweep("single", [10.0], link="sil")
    assert list(r.columns["drive"]) == ["sil"]
    assert r.columns["jump_height_m"][0] > 0.01


def test_sweep_releases_the_gil():
    """While a sweep runs in one Python thread, another keeps running Python code."""
    window = {}

    def work():
        window["start"] = time.perf_counter()
        sandjumper.sweep(["single", "stutter", "delayed"], "0.5:40:0.02",
                         taus_s=[0.0, 0.02, 0.05], threads=1)
        window["end"] = time.perf_counter()

    t = threading.Thread(target=work)
    ticks = []
    t.start()
    while t.is_alive():
        ticks.append(time.perf_counter())
        time.sleep(0.001)
    t.join()
    start, end = window["start"], window["end"]
    duration = end - start
    assert duration > 0.2, f"the sweep took {duration:.3f} s: too short to tell"
    inside = [x for x in ticks if start + 0.25 * duration < x < end - 0.25 * duration]
    # Held GIL: no tick at all in the middle half; released: one every ~1 ms.
    assert len(inside) > 20, f"{len(inside)} ticks in {duration / 2:.3f} s"


def test_hil_equals_the_cli(tmp_path):
    r = sandjumper.hil("stutter", 11.0, gain_lowering=0.5, camera_fps=200)
    out = tmp_path / "h"
    cli("hil", "--kind", "stutter", "--freq", 11, "--gain-lowering", 0.5, "--out", out)
    expected = json.loads((out / "summary.json").read_text())
    timings = {"wall_time_s", "realtime_factor"}
    assert {k: v for k, v in r.summary.items() if k not in timings} == {
        k: v for k, v in expected.items() if k not in timings
    }
    table = read_csv(out / "acquisition.csv")
    for name, texts in table.items():
        column = r.log[name]
        assert len(column) == r.summary["ticks"] or len(column) == len(texts)
        if name in ("tick", "encoder_counts", "flags"):
            assert column.dtype == np.int64
            assert [int(t) for t in texts] == list(column)
        else:
            assert column.dtype == np.float64
            same_numbers(texts, column)
    assert r.log_metadata["phi"] == "0.57"
    positions = r.log["encoder_counts"] / float(r.log_metadata["counts_per_m"])
    np.testing.assert_allclose(r.log["position_m"], positions, rtol=0, atol=1e-12)


def test_replay_equals_the_cli(tmp_path):
    out = tmp_path / "h"
    cli("hil", "--kind", "single", "--freq", 10, "--out", out, "--camera-fps", 0)
    log = out / "acquisition.csv"
    r = sandjumper.replay(log, model="eq1", window_ms=2.0)
    assert r.summary == cli_json("replay", log, "--model", "eq1", "--window-ms", 2.0)
    assert len(r.series["t_s"]) > 100
    checked = sandjumper.read_log(log)
    assert checked["summary"] == cli_json("log", "check", log)
    assert checked["columns"]["encoder_counts"].dtype == np.int64
    mcap = tmp_path / "run.mcap"
    sandjumper.log_to_mcap(log, mcap)
    assert mcap.read_bytes()[:8] == b"\x89MCAP0\r\n"
    with pytest.raises(ValueError, match="exists"):
        sandjumper.log_to_mcap(log, mcap)


def test_mcap_reads_with_foxglove_s_own_python_reader(tmp_path):
    """An independent reader (the `mcap` package Foxglove publishes) opens the file through
    its summary and indexes, seeks a time window, and finds every value of the CSV."""
    reader_module = pytest.importorskip("mcap.reader")
    out = tmp_path / "h"
    cli("hil", "--kind", "stutter", "--freq", 12, "--out", out, "--mcap")
    table = read_csv(out / "acquisition.csv")
    with open(out / "acquisition.mcap", "rb") as f:
        reader = reader_module.make_reader(f)
        summary = reader.get_summary()
        topics = {c.topic for c in summary.channels.values()}
        assert topics == {"/encoder", "/drive", "/status", "/camera", "/faults"}
        assert len(summary.chunk_indexes) > 1
        assert {s.encoding for s in summary.schemas.values()} == {"jsonschema"}
        encoder = [json.loads(m.data) for _, _, m in reader.iter_messages(topics=["/encoder"])]
        assert [e["encoder_counts"] for e in encoder] == [int(t) for t in table["encoder_counts"]]
        assert [e["t_s"] for e in encoder] == [float(t) for t in table["t_s"]]
        # 0.1 s to 0.2 s: ticks 1000..=1999 at 10 kHz, found through the chunk indexes.
        try:
            window = list(reader.iter_messages(topics=["/encoder"], starting_at=100_000_000,
                                               ending_before=200_000_000))
        except TypeError:  # mcap < 1.3 names them start_time, end_time
            window = list(reader.iter_messages(topics=["/encoder"], start_time=100_000_000,
                                               end_time=200_000_000))
        assert len(window) == 1000
        assert json.loads(window[0][2].data)["tick"] == 1000
        names = [m.name for m in reader.iter_metadata()]
        assert names == ["sandjumper-acqlog", "sandjumper-conversion"]


def test_dem_collide_equals_the_cli():
    args = dict(d1_m=0.001, d2_m=0.0014, kn=2e4, damping=2e-3, speed=0.3)
    r = sandjumper.dem_collide(**args, dt=1e-7)
    assert r == cli_json("dem", "collide", "--d1", 0.001, "--d2", 0.0014, "--kn", 2e4,
                         "--damping", 2e-3, "--speed", 0.3, "--dt", 1e-7)
    assert 0 < r["restitution"] < 1
    wall = sandjumper.dem_collide(0.001, 2e4, 2e-3, 0.3, wall=True)
    assert wall["effective_mass_kg"] > r["effective_mass_kg"]


def test_track_equals_the_cli(tmp_path):
    out = tmp_path / "h"
    cli("hil", "--kind", "single", "--freq", 10, "--out", out)
    frames, log = out / "frames", out / "acquisition.csv"
    r = sandjumper.track(frames, 0.00012, log=log)
    expected = cli_json("track", frames, "--m-per-px", 0.00012, "--log", log)
    assert r.summary == expected
    assert r.path is None
    assert len(r.tables["track"]["t_s"]) == expected["frames"]
    kept = sandjumper.track(frames, 0.00012, out=tmp_path / "t", log=log)
    assert kept.path == str(tmp_path / "t")
    assert (tmp_path / "t" / "track.csv").exists()


def test_piv_fields_are_2d_arrays_equal_to_the_cli(tmp_path):
    frames = tmp_path / "frames"
    cli("piv-synthetic", "--field", "shear", "--size", "256x192", "--frames", 3,
        "--out", frames)
    r = sandjumper.piv(frames, windows=[32, 16], out=tmp_path / "p")
    expected = cli_json("piv", frames, "--windows", "32,16")
    assert r.summary == expected
    nx, ny, _ = expected["grid"]
    for name in ("u_px", "v_px", "flag", "s2n"):
        assert r.arrays[name].shape == (expected["pairs"], ny, nx)
        assert r.arrays[name].dtype == np.float64
    assert r.arrays["x_px"].shape == (nx,)
    # The shear: u grows with y, v is near zero.
    u = np.nanmean(r.arrays["u_px"][0], axis=1)
    assert u[-1] - u[0] > 2.0
    assert np.nanmax(np.abs(r.arrays["v_px"])) < 0.5


def test_dem_bed_and_intrusion_equal_the_cli(tmp_path):
    bed_options = dict(width=0.03, height=0.015, pack=0.8, threads=1, seed=3)
    bed = sandjumper.dem_bed(tmp_path / "bed", **bed_options)
    cli("dem", "bed", "--width", 0.03, "--height", 0.015, "--pack", 0.8, "--threads", 1,
        "--seed", 3, "--out", tmp_path / "bed-cli")
    assert bed.path == str(tmp_path / "bed")
    grains = read_csv(tmp_path / "bed-cli" / "grains.csv")
    assert list(bed.tables["grains"]) == list(grains)
    for name, texts in grains.items():
        same_numbers(texts, bed.tables["grains"][name])
    run = sandjumper.dem_intrude(tmp_path / "bed", tmp_path / "run", speed=0.1, depth=0.004,
                                 foot_width=0.01, no_frames=True, threads=1)
    cli("dem", "intrude", "--bed", tmp_path / "bed", "--speed", 0.1, "--depth", 0.004,
        "--foot-width", 0.01, "--no-frames", "--threads", 1, "--out", tmp_path / "run-cli")
    force = read_csv(tmp_path / "run-cli" / "force_depth.csv")
    for name, texts in force.items():
        same_numbers(texts, run.tables["force_depth"][name])
    expected = json.loads((tmp_path / "run-cli" / "summary.json").read_text())
    assert run.summary["summary"]["grains"] == expected["summary"]["grains"]
    fields = run.arrays["u_m_s"]
    assert fields.ndim == 3 and fields.shape[1:] == (len(run.arrays["h_m"]), len(run.arrays["x_m"]))
    with pytest.raises(ValueError, match="depth"):
        sandjumper.dem_intrude(tmp_path / "bed", tmp_path / "bad", speed=0.1, depth=-1.0)


@pytest.mark.parametrize(
    "call, name, flag, cli_args",
    [
        (lambda: sandjumper.jump("single", 0.0), "freq_hz", "--freq",
         ["jump", "--kind", "single", "--freq", "0"]),
        (lambda: sandjumper.jump("single", 10, phi=1.5), "phi", "--phi",
         ["jump", "--kind", "single", "--freq", "10", "--phi", "1.5"]),
        (lambda: sandjumper.jump("hop", 10), "kind", "--kind",
         ["jump", "--kind", "hop", "--freq", "10"]),
        (lambda: sandjumper.jump("single", 10, rtol=2.0), "rtol", "--rtol",
         ["jump", "--kind", "single", "--freq", "10", "--rtol", "2"]),
        (lambda: sandjumper.hil("single", 10, link="usb"), "link", "--link",
         ["hil", "--kind", "single", "--freq", "10", "--link", "usb"]),
        (lambda: sandjumper.dem_collide(0.001, -1.0, 1e-3, 0.1, wall=True), "kn", "--kn",
         ["dem", "collide", "--d1", "0.001", "--kn=-1", "--damping", "0.001", "--speed", "0.1",
          "--wall"]),
    ],
)
def test_bad_values_raise_value_error_with_the_clis_message(call, name, flag, cli_args):
    with pytest.raises(ValueError) as raised:
        call()
    message = str(raised.value)
    out = cli(*cli_args, check=False)
    assert out.returncode == 2
    # The CLI's message (first paragraph, `error: ` dropped, whitespace collapsed) with its
    # flag written as the Python argument's name.
    paragraph = out.stderr.strip().split("\n\n")[0]
    if paragraph.startswith("error: "):
        paragraph = paragraph[len("error: "):]
    expected = re.sub(re.escape(flag) + r"( <[A-Z_.]+>)?", name, " ".join(paragraph.split()))
    assert message == expected
    assert name in message


def test_delayed_needs_tau_and_names_it():
    with pytest.raises(ValueError, match="tau_s"):
        sandjumper.jump("delayed", 10)


def test_bad_params_and_logs_raise_value_error(tmp_path):
    with pytest.raises(ValueError, match="unknown"):
        sandjumper.jump("single", 10, params={"robot": {"no_such_key": 1.0}})
    with pytest.raises(ValueError, match="no-such-file"):
        sandjumper.replay(tmp_path / "no-such-file.csv")
    bad = tmp_path / "bad.csv"
    bad.write_text("# rate_hz: 1000\n# counts_per_m: 1e6\nt_s,encoder_counts\n0,1\n0,2\n")
    with pytest.raises(ValueError) as raised:
        sandjumper.replay(bad, phi=0.57)
    assert "line 5" in str(raised.value)
    assert str(raised.value) in cli("replay", bad, "--phi", 0.57, check=False).stderr
    with pytest.raises(ValueError, match="sweep link"):
        sandjumper.sweep("single", 10, link="pil")
    with pytest.raises(ValueError, match="freqs_hz"):
        sandjumper.sweep("single", "12:8:1")
    with pytest.raises(ValueError, match="gain_lowering"):
        sandjumper.sweep("single", 10, gain_lowering=0.5)


@pytest.mark.parametrize(
    "call, name",
    [
        (lambda: sandjumper.jump("single", "10"), "freq_hz"),
        (lambda: sandjumper.jump(3, 10), "kind"),
        (lambda: sandjumper.jump("single", 10, tau_s="0.1"), "tau_s"),
        (lambda: sandjumper.hil("single", 10, camera_fps=2.5), "camera_fps"),
        (lambda: sandjumper.sweep("single", {"a": 1}), "freqs_hz"),
        (lambda: sandjumper.sweep("single", [10, "x"]), "freqs_hz"),
        (lambda: sandjumper.jump("single", 10, params=[1, 2]), "params"),
        (lambda: sandjumper.replay(12), "log"),
        (lambda: sandjumper.piv("frames", windows={"a": 1}), "windows"),
        (lambda: sandjumper.dem_collide(0.001, 1e4, 1e-3, 0.1, wall="yes"), "wall"),
    ],
)
def test_wrong_types_raise_type_error_naming_the_argument(call, name):
    with pytest.raises(TypeError) as raised:
        call()
    assert str(raised.value).startswith(name + ":"), str(raised.value)


def test_the_notebook_reproduces_height_vs_phi(tmp_path, monkeypatch):
    """docs/notebook.py runs top to bottom (its own asserts check the paper's findings) and
    draws the figure."""
    pytest.importorskip("matplotlib")
    import runpy

    monkeypatch.setenv("SANDJUMPER_NOTEBOOK_OUT", str(tmp_path))
    monkeypatch.setenv("MPLBACKEND", "Agg")
    runpy.run_path(str(REPO / "docs" / "notebook.py"), run_name="__main__")
    assert (tmp_path / "height_vs_phi.png").stat().st_size > 10_000
    for figure in ["jump.png", "piv_field.png", "optimized_stroke.png"]:
        assert (tmp_path / figure).stat().st_size > 10_000, figure
