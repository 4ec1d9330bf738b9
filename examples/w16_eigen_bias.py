"""The eigenvector method's noise bias on W16's fused four-camera sky (docs/validation.md).

One stop of rigs/wang2016-static.yaml (14:07 Beijing time, the middle of W16's hour) on the
quarter-resolution sensor (docs/cli.md "polrig locate": 258 × 194 per camera, the same field),
fused by polrig, then the sun vector (W16 Eqs. 9–14, spec §2.5) by each weighting of EEᵀ over
SEEDS noise realisations: the mean sun-vector error, heading bias (α_S − α_S,true) and
zenith-angle bias with their standard errors, against the noise-free image (whose own error is the
fused image's resampling, ≈ 1e-3°) and against the first-order analytic expectation
(docs/physics.md §15, "The noise bias of the eigenvector method"):

    E[EEᵀ] = Σ w (e₀e₀ᵀ + β (t₀t₀ᵀ − e₀e₀ᵀ)),   β = E[sin² δ] ≈ var δ,   t₀ = v × e₀,
    s ≈ s₀ − (M₀)⁺ Σ w β (t₀·s₀) t₀,            M₀ = Σ w e₀e₀ᵀ,

with var δ of each virtual pixel propagated from the cameras' Poisson–Gaussian noise and the ADC
through the bilinear co-registration and Eqs. 3–5 (the same numbers, written here in NumPy).
The estimates are polrig's (polrig.sun_vector: unweighted, dop_weighting, min_dop and
correct_noise_bias); NumPy computes only the expectation. Then the whole hour end to end
(`polrig locate`'s polrig.locate_dataset on 61 stops a minute apart, as docs/cli.md) for LOCATE
seeds: the fix's error and the heading's bias per method, mean ± standard error over seeds.
Writes w16_eigen_bias.png (and prints the tables) to OUT_DIR:
    PYTHONPATH=build/python /usr/bin/python3 examples/w16_eigen_bias.py [OUT_DIR] [SEEDS] [LOCATE]
(defaults 100 and 2; docs/validation.md's numbers: 400 and 10.)
"""
import math
import pathlib
import sys
import tempfile

import numpy as np

import polrig

ROOT = pathlib.Path(__file__).resolve().parents[1]
out = pathlib.Path(sys.argv[1] if len(sys.argv) > 1 else ".")
SEEDS = int(sys.argv[2]) if len(sys.argv) > 2 else 100
LOCATE = int(sys.argv[3]) if len(sys.argv) > 3 else 2
QUARTER = {
    "device.cameras.width_px": 258, "device.cameras.height_px": 194,
    "device.cameras.fx_px": [192.5, 192.8, 192.225, 192.65],
    "device.cameras.fy_px": [192.5, 192.8, 192.225, 192.65],
    "device.cameras.cx_px": [129, 129.6, 128.925, 129.475],
    "device.cameras.cy_px": [97, 96.95, 97.575, 97.15],
    "schedule.count": 1, "sky.first_stop_utc": "2015-12-16T06:07:00Z",
}
# name: polrig.sun_vector's keywords
METHODS = {
    "unweighted": {},
    "dop_weighting": {"dop_weighting": True},
    "min_dop 0.05": {"min_dop": 0.05},
    "min_dop 0.10": {"min_dop": 0.10},
    "correct_noise_bias": {"correct_noise_bias": True},
}


def rig(**extra):
    return polrig.Rig.load(str(ROOT / "rigs" / "wang2016-static.yaml"), set={**QUARTER, **extra})


def views(f):
    """Per virtual pixel: the view v, the frame-i axes, α (meridional conversion, spec §2.5)."""
    H, W = f["AoP"].shape
    x, y = np.meshgrid(np.arange(W) + 0.5, np.arange(H) + 0.5)
    dx, dy, fc = x - f["cx_px"], y - f["cy_px"], f["f_c_px"]
    v = np.stack([dx, dy, np.full_like(dx, fc)], -1)
    v /= np.linalg.norm(v, axis=-1, keepdims=True)
    alpha = np.arctan2(dy, dx)
    # X_i: increasing zenith angle; Y_i: increasing α (Rz(α)·Ry(γ)).
    g = np.arccos(v[..., 2])
    xi = np.stack([np.cos(g) * np.cos(alpha), np.cos(g) * np.sin(alpha), -np.sin(g)], -1)
    yi = np.stack([-np.sin(alpha), np.cos(alpha), np.zeros_like(alpha)], -1)
    return v, xi, yi, alpha


def e_vectors(aop_deg, xi, yi, alpha):
    phi = np.deg2rad(aop_deg) - alpha
    return np.cos(phi)[..., None] * xi + np.sin(phi)[..., None] * yi


def smallest(M, prior):
    lam, U = np.linalg.eigh(M)
    s = U[:, 0]
    return s if s @ prior > 0 else -s


def weights(name, dop, valid):
    """The weights of EEᵀ each method uses (the expectation's side)."""
    ok = valid & np.isfinite(dop)
    if name == "unweighted":
        return ok * 1.0
    if name == "dop_weighting":
        return ok * dop
    if name == "correct_noise_bias":
        return ok * dop * dop
    return (ok & (dop >= METHODS[name]["min_dop"])) * 1.0


def outer_sum(a, w, b):
    """Σ_k w_k a_k b_kᵀ over the pixels with w_k ≠ 0."""
    m = (w != 0) & np.isfinite(w)
    return np.einsum("ki,kj->ij", a[m] * w[m][:, None], b[m])


def library_sun(f, name, prior):
    aop = np.where(f["valid"] == 1, f["AoP"].astype(float), np.nan)
    dop = np.where(f["valid"] == 1, f["DoP"].astype(float), np.nan)
    r = polrig.sun_vector(aop, dop, f_c_px=f["f_c_px"], principal_point=(f["cx_px"], f["cy_px"]),
                          element_px=1.0, prior_sun=list(prior), **METHODS[name])
    assert r.status == "ok", r
    return np.asarray(r.sun), r.stokes_noise_sd


def angles(s):
    return math.degrees(math.atan2(s[1], s[0])), math.degrees(math.acos(s[2]))


def aop_variance(f, truth, rig_values):
    """var δ (rad²) per virtual pixel: the cameras' noise through co-registration and Eqs. 3–5."""
    e_per_DN, read, = rig_values
    H, W = f["AoP"].shape
    x, y = np.meshgrid(np.arange(W) + 0.5, np.arange(H) + 0.5)
    v1 = np.stack([x - f["cx_px"], y - f["cy_px"], np.full(x.shape, f["f_c_px"])], -1)
    v1 /= np.linalg.norm(v1, axis=-1, keepdims=True)
    axis = np.deg2rad(truth["axis_deg"])
    D = np.stack([np.cos(2 * axis), np.sin(2 * axis), np.ones(4)], 1)
    Wm = np.linalg.pinv(D)  # (DᵀD)⁻¹Dᵀ, 3 × 4
    S0, S1, S2 = (f[k].astype(float) for k in ("S0", "S1", "S2"))
    varF = []
    for j in range(4):
        vj = v1 @ truth["R_j1"][j].T
        th = np.arccos(np.clip(vj[..., 2], -1, 1))
        al = np.arctan2(vj[..., 1], vj[..., 0])
        u = truth["fx_px"][j] * th * np.cos(al) + truth["cx_px"][j] - 0.5
        w = truth["fy_px"][j] * th * np.sin(al) + truth["cy_px"][j] - 0.5
        a, b = u - np.floor(u), w - np.floor(w)
        sw2 = ((1 - a) ** 2 + a ** 2) * ((1 - b) ** 2 + b ** 2)
        K = truth["K"][j]
        signal = K * (S0 + np.cos(2 * axis[j]) * S1 + np.sin(2 * axis[j]) * S2)  # DN above the offset
        var_DN = signal / e_per_DN + read ** 2 + 1.0 / 12.0
        varF.append(sw2 * var_DN / K ** 2)
    varF = np.stack(varF, -1)
    v1s = (varF * Wm[0] ** 2).sum(-1)
    v2s = (varF * Wm[1] ** 2).sum(-1)
    c12 = (varF * Wm[0] * Wm[1]).sum(-1)
    p2 = S1 ** 2 + S2 ** 2
    c, s = S1 / np.sqrt(p2), S2 / np.sqrt(p2)
    var2d = (s * s * v1s + c * c * v2s - 2 * s * c * c12) / p2
    return var2d / 4.0


def frame_study():
    clean = rig(**{"device.cameras.noise": False}).four_camera_fused(0)
    valid = clean["valid"].astype(bool)
    v, xi, yi, alpha = views(clean)
    e0 = e_vectors(clean["AoP"].astype(float), xi, yi, alpha)
    t0 = np.cross(v, e0)
    d0 = clean["DoP"].astype(float)
    truth = rig().four_camera_truth()
    # The true sun: polrig's ephemeris in camera 1 (level, X towards the south: α_S = 180° − A_s).
    sun = polrig.sun_position(QUARTER["sky.first_stop_utc"], (28.221, 112.992, 50.0))
    A, h = float(np.ravel(sun.azimuth_deg)[0]), math.radians(90.0 - float(np.ravel(sun.zenith_deg)[0]))
    aS = math.radians(180.0 - A)
    s_true = np.array([math.cos(h) * math.cos(aS), math.cos(h) * math.sin(aS), math.sin(h)])
    az_t, zen_t = angles(s_true)
    print(f"14:07 Beijing time: A_s {A:.4f}°, zenith {zen_t:.4f}°, α_S {az_t:.4f}° in camera 1")
    floor = {}
    for name in METHODS:
        s0, _ = library_sun(clean, name, s_true)
        floor[name] = s0
        print(f"  noise-free {name:19s}: {math.degrees(math.acos(min(1, s0 @ s_true))):.5f}° from the ephemeris' sun")

    beta = aop_variance(clean, truth, (10.0, 1.0))
    m = valid & (d0 > 0)
    sigma_model = math.sqrt(np.mean(4 * d0[m] ** 2 * beta[m]))  # the σ with w·β = σ²/4 on average
    est = {n: [] for n in METHODS}
    sig = []
    var_emp = np.zeros(valid.shape)
    for seed in range(SEEDS):
        f = rig(seed=1000 + seed).four_camera_fused(0)
        dd = np.deg2rad(((f["AoP"].astype(float) - clean["AoP"] + 90) % 180) - 90)
        var_emp += np.where(valid, dd * dd, 0)
        for name in METHODS:
            s, sd = library_sun(f, name, s_true)
            est[name].append(s)
            if name == "correct_noise_bias":
                sig.append(sd)
    var_emp /= SEEDS
    print(f"AoP variance per pixel: the noise model's mean {beta[m].mean():.4e} rad², the Monte-Carlo's "
          f"{var_emp[m].mean():.4e} (ratio {beta[m].mean() / var_emp[m].mean():.4f})")
    print(f"correct_noise_bias's σ = 2√c: {np.mean(sig):.5f} ± {np.std(sig, ddof=1) / math.sqrt(len(sig)):.5f}; "
          f"the noise model's √mean(4·d²·var δ) = {sigma_model:.5f}")
    se = lambda a: a.std(ddof=1) / math.sqrt(len(a))
    print(f"\n{SEEDS} noise realisations of one stop; bias = mean(estimate − ephemeris) ± standard error; "
          f"expectation: first order, from the noise model")
    print(f"{'method':19s} {'zenith bias (°)':>22s} {'heading bias (°)':>22s} {'|error| (°)':>20s} "
          f"{'SD zen, head (°)':>18s} {'expected zen, head (°)':>24s}")
    rows = []
    for name in METHODS:
        S = np.array(est[name])
        daz = np.array([(angles(s)[0] - az_t + 180) % 360 - 180 for s in S])
        dzen = np.array([angles(s)[1] - zen_t for s in S])
        err = np.degrees(np.arccos(np.clip(S @ s_true, -1, 1)))
        if name == "correct_noise_bias":
            pz = ph = 0.0  # zero to first order by construction (docs/physics.md §15)
        else:
            w = weights(name, d0, valid)
            sp = smallest(outer_sum(e0, w, e0) + outer_sum(t0, w * beta, t0) - outer_sum(e0, w * beta, e0), s_true)
            ph = (angles(sp)[0] - az_t + 180) % 360 - 180
            pz = angles(sp)[1] - zen_t
        row = (name, dzen.mean(), se(dzen), daz.mean(), se(daz), err.mean(), se(err), dzen.std(ddof=1),
               daz.std(ddof=1), pz, ph)
        rows.append(row)
        print(f"{name:19s} {row[1]:+10.5f} ± {row[2]:.5f} {row[3]:+10.5f} ± {row[4]:.5f} {row[5]:9.5f} ± {row[6]:.5f}"
              f" {row[7]:8.4f}, {row[8]:.4f} {pz:+11.5f}, {ph:+.5f}")
    return rows, beta, d0, valid


def locate_study(tmp):
    hour = {**QUARTER, "schedule.count": 61, "schedule.dwell_s": 60, "sky.first_stop_utc": "2015-12-16T05:37:00Z"}
    res = {n: ([], []) for n in ("unweighted", "dop_weighting", "correct_noise_bias", "noise-free")}
    for k in range(LOCATE):
        for noise in (True, False):
            if not noise and k > 0:
                continue
            r = polrig.Rig.load(str(ROOT / "rigs" / "wang2016-static.yaml"),
                                set={**hour, "seed": 2000 + k, "device.cameras.noise": noise})
            data = r.simulate_four_camera(tmp / f"hour{k}{noise}", layers="aop", force=True)
            for name in (("unweighted", "dop_weighting", "correct_noise_bias") if noise else ("unweighted",)):
                kw = {n: True for n in (name,) if n != "unweighted"}
                loc = polrig.locate_dataset(str(data), (29, 113.5), **kw)
                key = name if noise else "noise-free"
                res[key][0].append(float(loc.fix.error_km[0]))
                res[key][1].append(float(np.mean(loc.heading_error_deg)))
    print(f"\nthe hour (61 stops a minute apart), {LOCATE} seeds: mean ± standard error over seeds")
    rows = []
    for name, (km, hd) in res.items():
        km, hd = np.array(km), np.array(hd)
        sek = km.std(ddof=1) / math.sqrt(len(km)) if len(km) > 1 else float("nan")
        seh = hd.std(ddof=1) / math.sqrt(len(hd)) if len(hd) > 1 else float("nan")
        rows.append((name, km.mean(), sek, hd.mean(), seh))
        print(f"{name:19s} position error {km.mean():8.3f} ± {sek:.3f} km   heading bias {hd.mean():+.4f} ± {seh:.4f}°")
    return rows


def plot(rows, beta, d0, valid, loc_rows):
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    fig, ax = plt.subplots(1, 3, figsize=(15, 4.4))
    im = ax[0].imshow(np.where(valid, np.degrees(np.sqrt(beta)), np.nan), cmap="magma")
    fig.colorbar(im, ax=ax[0], label="AoP noise SD (°), noise model")
    ax[0].contour(np.where(valid, d0, np.nan), levels=[0.05, 0.1, 0.2, 0.3], colors="w", linewidths=0.7)
    ax[0].set_title("fused AoP noise; DoP 0.05, 0.1, 0.2, 0.3 in white", fontsize=10)
    ax[0].set_xlabel("column (px)")
    ax[0].set_ylabel("row (px)")
    x = np.arange(len(rows))
    names = [r[0].replace("_", " ") for r in rows]
    for k, (col, lab, off) in enumerate(((1, "zenith", -0.15), (3, "heading", 0.15))):
        ax[1].errorbar(x + off, [r[col] for r in rows], yerr=[2 * r[col + 1] for r in rows], fmt="o",
                       capsize=3, label=f"{lab} bias, Monte-Carlo (±2 SE)")
        ax[1].plot(x + off, [r[9 + k] for r in rows], "kx", ms=8, label=f"{lab}: first-order expectation" if k == 0 else None)
    ax[1].axhline(0, color="0.5", lw=0.8)
    ax[1].set_xticks(x, names, rotation=20, fontsize=8)
    ax[1].set_ylabel("bias (°)")
    ax[1].set_title(f"one stop, {SEEDS} noise realisations")
    ax[1].legend(fontsize=7)
    lx = np.arange(len(loc_rows))
    ax[2].bar(lx, [r[1] for r in loc_rows], yerr=[2 * (r[2] if np.isfinite(r[2]) else 0) for r in loc_rows],
              capsize=3, color="tab:blue")
    ax[2].set_xticks(lx, [r[0].replace("_", " ") for r in loc_rows], rotation=20, fontsize=8)
    ax[2].set_ylabel("position error (km)")
    ax2 = ax[2].twinx()
    ax2.plot(lx, [r[3] for r in loc_rows], "rs", label="heading bias")
    ax2.set_ylabel("heading bias (°)", color="r")
    ax[2].set_title(f"polrig locate, the hour, {LOCATE} seeds")
    fig.tight_layout()
    fig.savefig(out / "w16_eigen_bias.png", dpi=110)


def main():
    out.mkdir(parents=True, exist_ok=True)
    rows, beta, d0, valid = frame_study()
    with tempfile.TemporaryDirectory() as scratch:  # the datasets: only the plot stays in OUT_DIR
        loc_rows = locate_study(pathlib.Path(scratch))
    plot(rows, beta, d0, valid, loc_rows)


if __name__ == "__main__":
    main()
