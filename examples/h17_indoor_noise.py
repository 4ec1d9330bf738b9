"""H17 Fig. 7 from Python: the AoP and DoP error of a calibrated unit as the light drops.

The han2017 indoor rig (rigs/han2017-indoor.yaml) on a 64 × 48 camera (768 cells; a 9° field, so
the port polarizer's obliquity plays no part), simulated with the camera's own noise
(Poisson–Gaussian, 12-bit ADC; 5 frames averaged per stop), calibrated by H17's two steps, then
each cell's AoP and DoP at every polarized stop measured with the calibrated parameters
(polrig.dofp_cell_polarization): per intensity, the AoP error's SD over the 79 table angles
(against the cell's fitted ψ_0 + θ_R) and the DoP's RMS error (against the fitted d_0), the
median over the cells. H17 (spec §2.6): 0.17° → 0.77° and 0.5 % → 3.8 % from 100 % to 2.5 %.
Runs as a script (the test suite runs it) and writes h17_indoor_noise.png to OUT_DIR:
    PYTHONPATH=build/python /usr/bin/python3 examples/h17_indoor_noise.py [OUT_DIR]
"""
import pathlib
import sys
import tempfile

import matplotlib
matplotlib.use("Agg")  # files only; in Jupyter, drop this line
import matplotlib.pyplot as plt
import numpy as np

import polrig

ROOT = pathlib.Path(__file__).resolve().parents[1]
out = pathlib.Path(sys.argv[1] if len(sys.argv) > 1 else ".")
scratch = tempfile.TemporaryDirectory()  # the dataset: only the plot stays in OUT_DIR
data = pathlib.Path(scratch.name) / "h17_indoor"
rig = polrig.Rig.load(str(ROOT / "rigs" / "han2017-indoor.yaml"),
                      set={"device.width_px": 64, "device.height_px": 48})
rig.simulate_frames(data, frames="mean", force=True)

cal = polrig.calibrate_dofp_dataset(data)
ds = polrig.read_dofp_dataset(data, mean_frames=True)
stops = ds["stops"]
cells = cal["cells"]
psi0 = np.asarray(cells["psi0_deg"]).reshape(24, 32)
d0 = np.asarray(cells["dop"]).reshape(24, 32)
params = {name: cal[name] for name in ("K", "b", "k", "eps_deg")}

print("intensity  AoP error SD (deg)  DoP RMS error (%)   [median over cells]")
rows = []
for intensity in sorted(set(stops["intensity"][stops["polarized"] == 1]), reverse=True):
    sel = np.flatnonzero((stops["polarized"] == 1) & (stops["intensity"] == intensity))
    aop_err, dop_err = [], []
    for s in sel:
        c = polrig.dofp_cell_polarization(ds["mean_frames"][s], **params)
        aop_err.append((c["aop_deg"] - psi0 - stops["theta_R_deg"][s] + 90.0) % 180.0 - 90.0)
        dop_err.append(c["dop"] - d0)
    aop_sd = np.median(np.std(np.array(aop_err), axis=0, ddof=1))
    dop_rms = np.median(np.sqrt(np.mean(np.array(dop_err) ** 2, axis=0)))
    rows.append((intensity, aop_sd, dop_rms))
    print(f"{intensity:9.3f}  {aop_sd:18.4f}  {100 * dop_rms:17.3f}")
hi, lo = rows[0], rows[-1]
print(f"ratio {hi[0] / lo[0]:.0f}x dimmer: AoP {lo[1] / hi[1]:.2f}x, DoP {lo[2] / hi[2]:.2f}x "
      f"(H17: 4.5x and 7.6x; shot noise alone: {np.sqrt(hi[0] / lo[0]):.2f}x)")

fig, ax = plt.subplots(1, 2, figsize=(9, 3.6))
I = [r[0] * 100 for r in rows]
ax[0].loglog(I, [r[1] for r in rows], "o-", label="polrig (median cell)")
ax[0].loglog([100, 2.5], [0.17, 0.77], "s--", label="H17 Fig. 7")
ax[0].set(xlabel="intensity (% of the largest)", ylabel="AoP error SD (deg)")
ax[1].loglog(I, [100 * r[2] for r in rows], "o-", label="polrig (median cell)")
ax[1].loglog([100, 2.5], [0.5, 3.8], "s--", label="H17 Fig. 7 (largest RMS)")
ax[1].set(xlabel="intensity (% of the largest)", ylabel="DoP RMS error (%)")
for a in ax:
    a.grid(True, which="both", alpha=0.3)
    a.legend()
fig.suptitle("A calibrated unit's AoP and DoP error as the light drops (H17 Fig. 7)")
fig.tight_layout()
fig.savefig(out / "h17_indoor_noise.png", dpi=110)
