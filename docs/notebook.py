# %% [markdown]
# # sandjumper from Python: a jump, the paper's height vs phi, PIV, the best stroke
#
# Reproduces the paper's `height_vs_phi` figure (Aguilar & Goldman 2016, REPRODUCTION.md
# section 1): the best jump height of the single jump, the stutter jump and the delayed
# stutter (tau = 0.75 s) over forcing frequency, against the packing fraction phi, with the
# eq4 (added-mass) model; then one jump's trajectory, a PIV field, a fit, a campaign, the rig
# tool and the stroke optimiser's answer, each a call of the project's libraries. Open it in
# Jupyter or VS Code (the `# %%` lines are cells), or run it as a script:
#
#     pip install ./sim-host/python matplotlib   # once
#     python docs/notebook.py                     # writes its figures here
#
# Every number comes from the module's calls, the same code as the command line's.

# %%
import os
import shutil
import tempfile

import numpy as np

import sandjumper

OUT = os.environ.get("SANDJUMPER_NOTEBOOK_OUT", ".")
WORK = tempfile.mkdtemp(prefix="sandjumper-notebook-")

import matplotlib

if "MPLBACKEND" not in os.environ and not os.environ.get("DISPLAY"):
    matplotlib.use("Agg")
import matplotlib.pyplot as plt

# %% [markdown]
# ## One jump, in memory
# `jump` returns the trajectory as numpy arrays (the columns of `trajectory.csv`); nothing is
# written unless `out=` names a folder.

# %%
j = sandjumper.jump("delayed", 10.0, tau_s=0.1)
print(j)
fig, ax = plt.subplots(figsize=(6, 3.5))
t = j.series["t_s"]
ax.plot(t, 1e3 * j.series["x_r_m"], label="rod")
ax.plot(t, 1e3 * j.series["x_m_m"], label="motor")
ax.plot(t, 1e3 * j.series["x_f_m"], label="foot")
ax.set_xlabel("t (s)")
ax.set_ylabel("position (mm)")
ax.set_title(f"delayed stutter, 10 Hz, tau 0.1 s: {1e3 * j.summary['jump_height_m']:.1f} mm")
ax.legend()
fig.tight_layout()
fig.savefig(os.path.join(OUT, "jump.png"), dpi=120)

# %% [markdown]
# ## The sweep: 3 kinds x 76 frequencies x 6 packing fractions, in parallel
# The delayed stutter uses tau = 0.75 s; the other kinds have no delay. A range is written
# as on the command line, `"A:B:STEP"` (inclusive).

# %%
sweep = sandjumper.sweep(
    kinds=["single", "stutter", "delayed"],
    freqs_hz="5:20:0.2",
    phis="0.57:0.62:0.01",
    taus_s=[0.75],
    models="eq4",
)
cols = sweep.columns
print(f"{len(cols['phi'])} jumps, {len(sweep.failures)} failed")
try:
    import pandas as pd  # optional: the same columns as a table

    print(pd.DataFrame(cols).head())
except ImportError:
    pass

# %% [markdown]
# ## Best height over frequency, for each kind and phi

# %%
phis = np.unique(cols["phi"])
best = {}
for kind in ["single", "stutter", "delayed"]:
    heights, freqs = [], []
    for phi in phis:
        rows = (cols["kind"] == kind) & (cols["phi"] == phi)
        i = np.argmax(cols["jump_height_m"][rows])
        heights.append(cols["jump_height_m"][rows][i])
        freqs.append(cols["freq_hz"][rows][i])
    best[kind] = (np.array(heights), np.array(freqs))
    for phi, h, f in zip(phis, *best[kind]):
        print(f"{kind:8s} phi = {phi:.2f}: {1e3 * h:6.1f} mm at {f:4.1f} Hz")

# %% [markdown]
# ## The paper's findings, checked
# Height rises steeply with phi; at phi = 0.57 the delayed stutter beats the single jump and
# the plain stutter jumps lower than it (REPRODUCTION.md: single 50.1 mm, delayed x1.39).

# %%
single, delayed, stutter = best["single"][0], best["delayed"][0], best["stutter"][0]
assert single[-1] > 1.8 * single[0], "height rises steeply with phi"
assert delayed[0] > 1.3 * single[0], "the delayed stutter beats the single jump at 0.57"
assert stutter[0] < single[0], "the plain stutter jumps lower at 0.57"
assert abs(single[0] - 0.0501) < 0.001, f"single at 0.57: {single[0]} m"

# %% [markdown]
# ## The figure

# %%
fig, ax = plt.subplots(figsize=(6, 4))
for kind, label in [("single", "single"), ("stutter", "stutter"),
                    ("delayed", "delayed stutter, tau = 0.75 s")]:
    ax.plot(phis, 1e3 * best[kind][0], "o-", label=label)
ax.set_xlabel("packing fraction phi")
ax.set_ylabel("best jump height (mm)")
ax.set_title("Jump height vs packing fraction (eq4)")
ax.legend()
fig.tight_layout()
path = os.path.join(OUT, "height_vs_phi.png")
fig.savefig(path, dpi=120)
print(f"wrote {path}")

# %% [markdown]
# ## PIV on a grain image whose motion is known
# Two frames of random grains drawn here with numpy, the second moved by a swirl of known
# displacement; `piv` measures the field (its `progress` callback is told as pairs finish).
# Pixel (row i, column j) is centred at x = j, y = i, as numpy has it.

# %%
rng = np.random.default_rng(1)
size, grains = 256, 2500
gx, gy = rng.uniform(0, size, grains), rng.uniform(0, size, grains)
yy, xx = np.mgrid[0:size, 0:size].astype(float)


def swirl(x, y):
    """The known displacement, px: a rotation about the centre, 2 px at 100 px."""
    return -(y - size / 2) * 0.02, (x - size / 2) * 0.02


def draw(px, py):
    img = np.zeros((size, size))
    for x, y in zip(px, py):
        near = (abs(xx - x) < 4) & (abs(yy - y) < 4)
        img[near] += np.exp(-((xx[near] - x) ** 2 + (yy[near] - y) ** 2) / 2.0)
    return np.clip(40 + 180 * img, 0, 255).astype(np.uint8)


from PIL import Image

frames = os.path.join(WORK, "grains")
os.makedirs(frames)
du, dv = swirl(gx, gy)
for k, (px, py) in enumerate([(gx, gy), (gx + du, gy + dv)]):
    Image.fromarray(draw(px, py)).save(os.path.join(frames, f"frame_{k:06d}.png"))
pairs = []
field = sandjumper.piv(frames, windows=[64, 32], progress=lambda *a: pairs.append(a))
u, v = field.arrays["u_px"][0], field.arrays["v_px"][0]
x, y = np.meshgrid(field.arrays["x_px"], field.arrays["y_px"])
eu, ev = swirl(x, y)
error = np.nanmedian(np.hypot(u - eu, v - ev))
print(f"PIV: {u.size} vectors, median error {error:.3f} px; progress {pairs[-1]}")
assert error < 0.1, error
fig, ax = plt.subplots(figsize=(4.5, 4.5))
ax.imshow(draw(gx, gy), cmap="gray")
ax.quiver(x, y, u, v, color="tab:orange", angles="xy", scale_units="xy", scale=0.1)
ax.set_title("PIV field (displacements x 10)")
fig.tight_layout()
fig.savefig(os.path.join(OUT, "piv_field.png"), dpi=120)

# %% [markdown]
# ## A fit: the added mass's mu and C from the model's own intrusion curve

# %%
depth, mass = -j.series["x_f_m"], j.series["m_a_kg"]
deepest = int(np.argmax(depth))
first = next(i for i in range(deepest) if mass[i] > 0)
curve = os.path.join(WORK, "added_mass.csv")
with open(curve, "w") as f:
    f.write("depth_m,added_mass_kg\n")
    last = -1.0
    for d, m in zip(depth[first:deepest + 1] - depth[first - 1], mass[first:deepest + 1]):
        if d > last:
            f.write(f"{float(d)!r},{float(m)!r}\n")
            last = d
fitted = sandjumper.fit("added-mass", curve, exclude_deepest=0.0)
print({f["param"]: round(f["value"], 5) for f in fitted["fits"]})

# %% [markdown]
# ## A campaign through the controller, stopped and resumed

# %%
plan = os.path.join(os.path.dirname(os.path.abspath(__file__)), "..", "examples",
                    "campaign-small.toml")
camp = os.path.join(WORK, "campaign")
print(sandjumper.campaign_run(plan, camp, link="sil", stop_after=2))
print(sandjumper.campaign_status(camp)["done"], "points done")
print(sandjumper.campaign_resume(camp))

# %% [markdown]
# ## The rig tool, the paper's figures, the DEM

# %%
print("controller:", sandjumper.rig_status(link="sil")["status"]["state"])
rig = sandjumper.rig_jump("stutter", 11.0, link="sil", out=os.path.join(WORK, "rig-jump"))
print(f"rig jump through sil: {rig.summary['samples']} samples, "
      f"{1e3 * rig.summary['simulated_jump_height_m']:.1f} mm")
# The jump's motor trajectory replayed at 80 % of its amplitude.
again = sandjumper.rig_replay(log=os.path.join(WORK, "rig-jump", "acquisition.csv"), scale=0.8)
print(f"replayed {again.summary['table_samples']} table samples: "
      f"{1e3 * again.summary['simulated_jump_height_m']:.1f} mm")
# The slow intrusion (the paper's F_p(z)), its curves in memory.
slow = sandjumper.rig_intrude(depth=0.01, reintrusion_depth=0.012, withdraw=0.003, speed=0.02,
                              hold=0.1, start=-0.01)
fig, ax = plt.subplots(figsize=(5, 3))
for name in ["intrusion", "reintrusion"]:
    curve = slow.tables[name]
    ax.plot(1e3 * curve["depth_m"], curve["force_n"], label=name)
ax.set_xlabel("depth (mm)")
ax.set_ylabel("force (N)")
ax.legend()
fig.savefig(os.path.join(WORK, "intrusion.png"), dpi=80)
print(sandjumper.rig_calibrate_drive(2050, 6.8))
print(sandjumper.rig_acknowledge_reset())
print(sandjumper.rig_flash(link="sil")["why"])
try:
    sandjumper.lammps_read(WORK, WORK)
except ValueError as e:  # a LAMMPS run to read back takes minutes: only the check here
    print("lammps_read:", e)
try:
    sandjumper.sweep_slurm(0, "single", 10.0, os.path.join(WORK, "slurm"), program="sandjumper")
except ValueError as e:  # a cluster is not here: only the check
    print("sweep_slurm:", e)
quick = sandjumper.figures(os.path.join(WORK, "figures"), quick=True)
print(sorted(quick.tables)[:4], "...")
hit = sandjumper.dem_collide(0.001, kn=2e4, damping=2e-3, speed=0.3, wall=True)
print(f"DEM collision: restitution {hit['restitution']:.3f}")
try:
    sandjumper.figures_dem(os.path.join(WORK, "dem"), foot_width=-1.0)
except ValueError as e:  # the supplement's DEM figures take minutes: only their check here
    print("figures_dem:", e)
try:
    sandjumper.lammps(os.path.join(WORK, "lammps"), speed=-0.1)
except ValueError as e:  # LAMMPS runs take minutes: only the check here
    print("lammps:", e)

# %% [markdown]
# ## The best stroke (a short search), jumped again
# `optimize` searches the stroke family with CMA-ES beside the best of the paper's strokes;
# its `stroke.csv` runs through `jump(stroke=...)`. A real search uses the defaults (192,000
# evaluations, the controller's links); this one is a small budget for the notebook.

# %%
best = sandjumper.optimize(os.path.join(WORK, "best"), evaluations=600, population=8,
                           random_starts=1, refine=0, verify="none", sweep_freq_step=1.0,
                           sweep_tau_step=0.1)
answer = sandjumper.jump(stroke=os.path.join(WORK, "best", "stroke.csv"))
print(f"optimiser: {1e3 * best.summary['best_height_m']:.1f} mm, best paper stroke "
      f"{1e3 * best.summary['best_paper_stroke_height_m']:.1f} mm; jumped again: "
      f"{1e3 * answer.summary['jump_height_m']:.1f} mm")
stroke = best.tables["stroke"]
fig, (a1, a2) = plt.subplots(2, 1, figsize=(6, 5), sharex=True)
a1.plot(stroke["t_s"], 1e3 * stroke["p_m"])
a1.set_ylabel("stroke p (mm)")
a1.set_title("the optimiser's answer")
a2.plot(answer.series["t_s"], 1e3 * answer.series["x_r_m"])
a2.set_xlabel("t (s)")
a2.set_ylabel("rod (mm)")
fig.tight_layout()
fig.savefig(os.path.join(OUT, "optimized_stroke.png"), dpi=120)
shutil.rmtree(WORK)
