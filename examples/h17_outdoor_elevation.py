"""H17 Table 3 from Python: the heading error's SD grows as the sun rises (spec §2.7 item 6).

The han2017 outdoor rig (rigs/han2017-outdoor.yaml: Changsha, 28 May 2017, level, 40 table angles
at 9.2072°, P_max 0.65) on a 160 × 120 camera with H17's field (f = 0.75 mm at 7.4 µm), simulated
with the camera's own noise, for first stops at Table 3's sun elevations; each dataset oriented as
`polrig orient` does (polrig.orient_dofp_dataset, an approximate heading as the prior for the
sun/antisun choice). The heading error is against the dataset's true heading. H17 Table 3
(sunny): 0.15, 0.32, 0.43, 0.61, 0.87° at h_s = −0.5, 5.5, 9.1, 13.5, 18.2°.
Runs as a script (the test suite runs it) and writes h17_outdoor_elevation.png to OUT_DIR:
    PYTHONPATH=build/python /usr/bin/python3 examples/h17_outdoor_elevation.py [OUT_DIR]
"""
import datetime
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
SITE = (28.2, 112.9)  # the rig's sky.site
H17 = {-0.5: 0.15, 5.5: 0.32, 9.1: 0.43, 13.5: 0.61, 18.2: 0.87}
METHODS = ["eigenvector", "single-point", "line-detection"]


def utc_at_elevation(h_deg):
    """The afternoon instant of 28 May 2017 at which the sun stands at h_deg (bisection)."""
    t0 = datetime.datetime(2017, 5, 28, 6, 0, tzinfo=datetime.timezone.utc)
    lo, hi = 0.0, 6 * 3600.0  # 06:00–12:00 UTC: the sun sinks through the afternoon
    for _ in range(60):
        mid = 0.5 * (lo + hi)
        t = (t0 + datetime.timedelta(seconds=mid)).strftime("%Y-%m-%dT%H:%M:%SZ")
        if float(polrig.sun_position(t, SITE).elevation_deg) > h_deg:
            lo = mid
        else:
            hi = mid
    return (t0 + datetime.timedelta(seconds=round(lo))).strftime("%Y-%m-%dT%H:%M:%SZ")


scratch = tempfile.TemporaryDirectory()  # the datasets: only the plot stays in OUT_DIR
rows = []
print("h_s (deg)  UTC                    heading error SD (deg): eigenvector  single-point  line-detection  | H17")
for h in H17:
    utc = utc_at_elevation(h)
    rig = polrig.Rig.load(str(ROOT / "rigs" / "han2017-outdoor.yaml"),
                          set={"device.width_px": 160, "device.height_px": 120, "device.focal_mm": 0.75,
                               "sky.first_stop_utc": utc})
    data = pathlib.Path(scratch.name) / f"h17_sky_{h:+.1f}"
    rig.simulate_frames(data, frames="mean", force=True)
    frames = polrig.orient_dofp_dataset(data, heading_prior_deg=0.0)
    err = {m: [] for m in METHODS}
    for f in frames:
        for e in f["estimates"]:
            err[e.method].append((e.heading_deg - f["true_heading_deg"] + 180.0) % 360.0 - 180.0)
    sd = {m: float(np.std(err[m], ddof=1)) for m in METHODS}
    rows.append((h, sd))
    print(f"{h:9.1f}  {utc}  {sd['eigenvector']:36.3f}  {sd['single-point']:12.3f}  {sd['line-detection']:14.3f}  | {H17[h]:.2f}")

fig, ax = plt.subplots(figsize=(6.4, 4))
hs = [r[0] for r in rows]
for m in METHODS:
    ax.plot(hs, [r[1][m] for r in rows], "o-", label=f"polrig: {m}")
ax.plot(hs, [H17[h] for h in hs], "s--k", label="H17 Table 3 (eigenvector, sunny)")
ax.set(xlabel="sun elevation h_s (deg)", ylabel="heading error SD (deg)", yscale="log")
ax.grid(True, which="both", alpha=0.3)
ax.legend(fontsize=8)
fig.suptitle("Heading error against the sun's elevation (H17 Table 3)")
fig.tight_layout()
fig.savefig(out / "h17_outdoor_elevation.png", dpi=110)
