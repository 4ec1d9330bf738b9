#!/usr/bin/env python3
"""A NumPy reference of the CS study over a grid of rigs, written from the paper's equations as
docs/physics.md states them (§1 frames, §2 the cos⁴ source, §3 Eq. 5, §5 the CS method), not from
polrig's C++:

  O_IS = L_IS·(cos α_IS, sin α_IS),  O_S = L_S·(cos α_S, sin α_S)
  P_m(0) = O_S + L_photo·(cos β_m, sin β_m),  P_m(θ_R) = Rot(θ_R)·P_m(0)
  E_m = E_0·[L_o² / (L_o² + |P_m − O_IS|²)]²                                   (cos⁴φ)
  ΔV_br,i(θ_R) = kv_i·v_dec·log10(E_j/E_h),  j = 2i − 1, h = 2i                  (Eq. 5)
  ΔV_mr,i(θ_R) = [ΔV_br,i(θ_R) + ΔV_br,i(θ_R + 180°)]/2                           (CS)
  BSD, ASD: population SDs of ΔV_br, ΔV_mr over the turn; their means; in mV
  Eq. 6: 2·kv_i·v_dec·log10[(L_o² + L_Rh² + L_IS²)/(L_o² + L_Rj² + L_IS²)],  L_Rm = |P_m(0)|

vectorised over batches of grid points. Run as a script it measures grid points per second on
one core (bench/sweep_end_to_end.py compares it with `polrig sweep`); python/tests/
test_numpy_reference.py compares its values with `polrig sweep`'s sweep.csv.

    /usr/bin/python3 bench/numpy_cs_reference.py [--points 20000]
"""
import os

# One core: no threaded BLAS/OpenMP below NumPy (set before NumPy is imported).
for _var in ("OMP_NUM_THREADS", "OPENBLAS_NUM_THREADS", "MKL_NUM_THREADS", "NUMEXPR_NUM_THREADS"):
    os.environ[_var] = "1"

import argparse  # noqa: E402
import pathlib  # noqa: E402
import time  # noqa: E402

import numpy as np  # noqa: E402
import yaml  # noqa: E402

ROOT = pathlib.Path(__file__).resolve().parents[1]
ECCENTRICITY_KEYS = ("L_IS", "alpha_IS", "L_S", "alpha_S")
COLUMNS = ("bsd_mV", "asd_mV", "mean_br_mV", "mean_mr_mV", "eq6_mV")


def load_rig(path):
    """The rig's values the cos⁴ CS study reads, from its YAML file (polrig's defaults where a
    key is absent: docs/formats.md)."""
    with open(path) as f:
        y = yaml.safe_load(f)
    dev, src, ecc = y.get("device", {}), y.get("source", {}), y.get("eccentricity", {})
    return {
        "L_photo": float(dev.get("L_photo", 14.0)),
        "beta_deg": np.array(dev.get("beta_deg", [0, -60, -120, -180, -240, -300]), dtype=float),
        "kv": np.array(dev.get("truth", {}).get("kv", [1.0, 1.0, 1.0]), dtype=float),
        "v_dec": float(y.get("electronics", {}).get("volts_per_decade", 0.5)),
        "L_o": float(src.get("L_o", 20.0)),
        "E_0": float(src.get("E_0", 10.0)),
        **{k: float(ecc.get(k, 0.0)) for k in ECCENTRICITY_KEYS},
    }


def cs_summaries(rig, points, steps=360):
    """The CS summary of each grid point: `points` maps eccentricity keys (L_IS, alpha_IS, L_S,
    alpha_S) to arrays of N values (the others are the rig's); returns {pairI_column: (N,)}."""
    n = len(next(iter(points.values())))
    ecc = {k: np.broadcast_to(np.asarray(points.get(k, rig[k]), dtype=float), (n,)) for k in ECCENTRICITY_KEYS}
    a_IS, a_S = np.radians(ecc["alpha_IS"]), np.radians(ecc["alpha_S"])
    port = np.stack([ecc["L_IS"] * np.cos(a_IS), ecc["L_IS"] * np.sin(a_IS)], axis=-1)   # (N, 2)
    centre = np.stack([ecc["L_S"] * np.cos(a_S), ecc["L_S"] * np.sin(a_S)], axis=-1)     # (N, 2)
    beta = np.radians(rig["beta_deg"])
    ring = rig["L_photo"] * np.stack([np.cos(beta), np.sin(beta)], axis=-1)             # (6, 2)
    p0 = centre[:, None, :] + ring[None, :, :]                                          # (N, 6, 2)
    theta = np.radians(360.0 * np.arange(steps) / steps)
    c, s = np.cos(theta), np.sin(theta)                                                 # (T,)
    x = p0[..., 0, None] * c - p0[..., 1, None] * s - port[:, None, 0, None]             # (N, 6, T)
    y = p0[..., 0, None] * s + p0[..., 1, None] * c - port[:, None, 1, None]
    L_o2 = rig["L_o"] ** 2
    E = rig["E_0"] * (L_o2 / (L_o2 + x * x + y * y)) ** 2
    scale = rig["kv"][None, :, None] * rig["v_dec"]
    dv_br = scale * np.log10(E[:, 0::2, :] / E[:, 1::2, :])                            # (N, 3, T)
    dv_mr = 0.5 * (dv_br + np.roll(dv_br, -steps // 2, axis=-1))
    L_R2 = np.sum(p0 * p0, axis=-1)                                                     # (N, 6)
    L_IS2 = (ecc["L_IS"] ** 2)[:, None]
    eq6 = 2.0 * rig["kv"] * rig["v_dec"] * np.log10((L_o2 + L_R2[:, 1::2] + L_IS2) / (L_o2 + L_R2[:, 0::2] + L_IS2))
    figures = {
        "bsd_mV": dv_br.std(axis=-1), "asd_mV": dv_mr.std(axis=-1),
        "mean_br_mV": dv_br.mean(axis=-1), "mean_mr_mV": dv_mr.mean(axis=-1), "eq6_mV": eq6,
    }
    return {f"pair{i + 1}_{name}": 1e3 * v[:, i] for name, v in figures.items() for i in range(3)}


def grid(axes):
    """Row-major grid points (the last axis fastest, as polrig's sweeps): axes is a list of
    (key, values); returns {key: (N,) values}."""
    mesh = np.meshgrid(*[np.asarray(v, dtype=float) for _, v in axes], indexing="ij")
    return {k: m.ravel() for (k, _), m in zip(axes, mesh)}


def sweep(rig, axes, steps=360, batch=2000, limit=None):
    """cs_summaries over the grid of `axes` in batches of points (bounded memory); the first
    `limit` points when given."""
    points = grid(axes)
    total = len(next(iter(points.values())))
    total = total if limit is None else min(limit, total)
    out = {}
    for b in range(0, total, batch):
        chunk = {k: v[b:min(total, b + batch)] for k, v in points.items()}
        for k, v in cs_summaries(rig, chunk, steps).items():
            out.setdefault(k, []).append(v)
    return {k: np.concatenate(v) for k, v in out.items()}


def points_per_second(points=20000, batch=2000):
    """The rate of the reference on one core over the first `points` of the issue's 10⁶-point grid
    (eccentricity.L_IS=0.001:1:1000 × eccentricity.alpha_S=0:359:1000)."""
    if hasattr(os, "sched_setaffinity"):
        os.sched_setaffinity(0, {min(os.sched_getaffinity(0))})
    rig = load_rig(ROOT / "rigs" / "wang2019-indoor.yaml")
    axes = [("L_IS", np.linspace(0.001, 1, 1000)), ("alpha_S", np.linspace(0, 359, 1000))]
    sweep(rig, axes, batch=batch, limit=batch)  # warm-up
    t0 = time.perf_counter()
    sweep(rig, axes, batch=batch, limit=points)
    return points / (time.perf_counter() - t0)


def main():
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--points", type=int, default=20000)
    ap.add_argument("--batch", type=int, default=2000)
    a = ap.parse_args()
    rate = points_per_second(a.points, a.batch)
    print(f"numpy reference: {rate:,.0f} points/s on one core ({a.points} points, batches of {a.batch})")


if __name__ == "__main__":
    main()
