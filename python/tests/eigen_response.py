"""The first-order response of the eigenvector method's sun vector (H17 Eqs. 10-13) to small
errors in the cells' AoP, for a Rayleigh sky: an independent implementation in NumPy (none of
compass/orientation's code), used by test_dofp_pipeline.py (the noise's heading SD) and
test_orientation.py (the bias of the cells' footprint).

The method takes the sun s as the eigenvector of the smallest eigenvalue of M = Σ eᵢeᵢᵀ over the
cells' E-vectors eᵢ. Under a Rayleigh sky eᵢ ⊥ s: eᵢ = vᵢ × s/nᵢ, nᵢ = |vᵢ × s|, vᵢ the cell's
view. An AoP error δφᵢ turns eᵢ about vᵢ (φ runs from X_i towards Y_i, a right-hand rotation about
Z_i = vᵢ; the image's φ_pix = φ + α moves with it): δeᵢ = δφᵢ·vᵢ × eᵢ, so
δeᵢ·s = δφᵢ·((vᵢ·s)² − 1)/nᵢ = −nᵢ·δφᵢ. First-order perturbation of M's null vector:
δs = −M⁺·δM·s = −M⁺·Σ eᵢ(δeᵢ·s) = M⁺·Σ eᵢ·nᵢ·δφᵢ (M⁺ on the plane ⊥ s).
The heading is A_s + atan2(s_y, s_x) (spec §0, polrig.camera_heading): δH = g·δs with
g = (−s_y, s_x, 0)/(s_x² + s_y²); the elevation asin s_z: δh = δs_z/cos h.
So δH = Σ Gᵢ·δφᵢ and δh = Σ Eᵢ·δφᵢ (radians), returned as (G, E) over the cells, row-major."""
import numpy as np


def cell_views(cells_x, cells_y, f_c, cx, cy):
    """Unit views (cells, 3) of 2 × 2-pixel cells in frame l: centres (2c + 1, 2r + 1) px."""
    X, Y = np.meshgrid(2.0 * np.arange(cells_x) + 1 - cx, 2.0 * np.arange(cells_y) + 1 - cy)
    v = np.stack([X, Y, np.full_like(X, f_c)], axis=-1).reshape(-1, 3)
    return v / np.linalg.norm(v, axis=1)[:, None]


def heading_and_elevation_gains(cells_x, cells_y, f_c, cx, cy, sun_l):
    v = cell_views(cells_x, cells_y, f_c, cx, cy)
    s = np.asarray(sun_l, dtype=float)
    vs = np.cross(v, s)
    n = np.linalg.norm(vs, axis=1)
    e = vs / n[:, None]
    w, V = np.linalg.eigh(e.T @ e)  # w[0] ≈ 0: along s
    Mp = V[:, 1:] @ np.diag(1.0 / w[1:]) @ V[:, 1:].T
    ds = (e @ Mp) * n[:, None]  # ∂s/∂φᵢ, (cells, 3)
    g = np.array([-s[1], s[0], 0.0]) / (s[0] ** 2 + s[1] ** 2)
    return ds @ g, ds[:, 2] / np.sqrt(1.0 - s[2] ** 2)


def raw_cell_aop(frame):
    """The cells' AoP (rad) from a raw frame by H17 Eq. 5, mosaic 0, 90, 45, 135° at TL, TR, BL, BR."""
    f = np.asarray(frame, dtype=float)
    return 0.5 * np.arctan2(f[1::2, 0::2] - f[1::2, 1::2], f[0::2, 0::2] - f[0::2, 1::2])
