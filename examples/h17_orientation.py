"""H17 §4.2 from Python: heading error of the three orientation methods on a simulated sky.

The camera of Han et al. 2017 (640 × 480 pixels, f_c = 405.4 px, 2 × 2 cells: 320 × 240 cells),
level, turned 0 → 359.08° in 9.2072° steps (40 frames) at Changsha on 28 May 2017, under a
single-scattering Rayleigh sky (P_max = 0.65) with Gaussian noise σ on each cell's normalised
Stokes q1 = d·cos 2χ, q2 = d·sin 2χ. For four sun elevations, the max / mean / std of the heading
error of the eigenvector method and the two comparators (H17 Tables 2 and 3: trends only).
Runs as a script (the test suite runs it):
    PYTHONPATH=build/python /usr/bin/python3 examples/h17_orientation.py [OUT_DIR]
and writes h17_orientation.png there (the heading error per frame at the highest sun).
"""
import pathlib
import sys

import matplotlib
matplotlib.use("Agg")  # files only; in Jupyter, drop this line
import matplotlib.pyplot as plt
import numpy as np

import polrig

out = pathlib.Path(sys.argv[1] if len(sys.argv) > 1 else ".")
F_C, SIGMA = 405.4, 0.01
SITE = (28.221, 112.992)  # Changsha
TIMES = ["2017-05-28T01:00:00Z", "2017-05-28T09:30:00Z", "2017-05-28T10:30:00Z",
         "2017-05-28T11:10:00Z"]
METHODS = ["eigenvector", "single-point", "line-detection"]

# %% The cells' views in the camera frame l: azimuth α from X_l (image +x) towards Y_l (image +y),
# anticlockwise seen from above for a level camera; zenith angle γ (H17 Eq. 9).
x = np.arange(320) * 2.0 + 1.0 - 320.0
y = np.arange(240) * 2.0 + 1.0 - 240.0
dx, dy = np.meshgrid(x, y)
alpha = np.degrees(np.arctan2(dy, dx))
gamma = np.degrees(np.arctan(np.hypot(dx, dy) / F_C))


def frame(sky, heading_deg, rng):
    """The image AoP φ_pix and DoP of one noisy frame: χ from the sky (the local meridian frame,
    which is frame i for a level camera), noise on (q1, q2), then φ_pix = φ + α."""
    light = sky.light((heading_deg - alpha) % 360.0, 90.0 - gamma)
    chi = np.radians(light.aop_deg)
    q1 = light.dop * np.cos(2 * chi) + SIGMA * rng.standard_normal(chi.shape)
    q2 = light.dop * np.sin(2 * chi) + SIGMA * rng.standard_normal(chi.shape)
    return np.degrees(0.5 * np.arctan2(q2, q1)) + alpha, np.hypot(q1, q2)


# %% 40 frames per time; the heading error of each method.
rng = np.random.default_rng(2017)
errors = {}
for utc in TIMES:
    sky = polrig.Sky(SITE, utc, 0.65)
    sun = sky.sun()
    e = np.full((40, 3), np.nan)
    for k in range(40):
        H = 9.2072 * k
        aop, dop = frame(sky, H, rng)
        for m, est in enumerate(polrig.orient(aop, dop, sun_azimuth_deg=sun.azimuth_deg, f_c_px=F_C)):
            if est.heading_deg is not None:
                e[k, m] = (est.heading_deg - H + 180.0) % 360.0 - 180.0
    errors[utc] = e
    print(f"{utc}  h_s = {sun.elevation_deg:5.1f}°")
    for m, name in enumerate(METHODS):
        col = e[:, m]
        print(f"  {name:15s} max|e| {np.nanmax(np.abs(col)):.3f}°  mean {np.nanmean(col):+.4f}°  "
              f"std {np.nanstd(col):.3f}°  solved {np.count_nonzero(~np.isnan(col))}/40")

# %% The heading error per frame at the highest sun.
fig, ax = plt.subplots(figsize=(9, 5))
for m, (name, style) in enumerate(zip(METHODS, ["^-", "o", "s"])):
    ax.plot(np.arange(40), errors[TIMES[0]][:, m], style, ms=4, label=name)
ax.set_xlabel("frame (table position, 9.2072° apart)")
ax.set_ylabel("heading error (°)")
ax.set_title(f"H17 camera, Rayleigh sky, σ = {SIGMA} on q1, q2: {TIMES[0]}")
ax.grid(True, alpha=0.3)
ax.legend()
fig.tight_layout()
fig.savefig(out / "h17_orientation.png", dpi=110)
