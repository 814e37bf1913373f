# %% [markdown]
# # Jump height vs packing fraction, from Python
#
# Reproduces the paper's `height_vs_phi` figure (Aguilar & Goldman 2016, REPRODUCTION.md
# section 1): the best jump height of the single jump, the stutter jump and the delayed
# stutter (tau = 0.75 s) over forcing frequency, against the packing fraction phi, with the
# eq4 (added-mass) model. Open it in Jupyter or VS Code (the `# %%` lines are cells), or run
# it as a script:
#
#     pip install ./sim-host/python matplotlib   # once
#     python docs/notebook.py                     # writes height_vs_phi.png here
#
# Every number comes from `sandjumper.sweep`, the same code as `sandjumper sweep`.

# %%
import os

import numpy as np

import sandjumper

OUT = os.environ.get("SANDJUMPER_NOTEBOOK_OUT", ".")

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
import matplotlib

if "MPLBACKEND" not in os.environ and not os.environ.get("DISPLAY"):
    matplotlib.use("Agg")
import matplotlib.pyplot as plt

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
