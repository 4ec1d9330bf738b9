"""polrig.calibrate_dofp (calib/dofp.h) against frames made here, in NumPy, from Eq. 18 with a
known per-pixel truth (spec sky-and-compasses.md §2.3-2.4)."""
import numpy as np
import pytest

import polrig


def truth(W, H, seed):
    rng = np.random.default_rng(seed)
    j = (np.arange(H)[:, None] % 2) * 2 + (np.arange(W)[None, :] % 2)
    K = 2000 * np.array([1.0, 1.06, 0.95, 1.03])[j] * (1 + 0.04 * rng.standard_normal((H, W)))
    b = np.array([40.0, 55, 35, 60])[j] + 8 * rng.standard_normal((H, W))
    k = np.where(j == 0, 1.0, np.array([1.0, 0.93, 0.96, 0.90])[j] + 0.02 * rng.standard_normal((H, W)))
    eps = np.where(j == 0, 0.0, np.array([0.0, 1.2, -0.8, 0.6])[j] + 0.5 * rng.standard_normal((H, W)))
    alpha = np.array([0.0, 90, 45, 135])[j]
    return K, b, k, eps, alpha


def eq18(t, I, d, phi_deg):
    K, b, k, eps, alpha = t
    return 0.5 * K * I * (1 + k * d * np.cos(np.radians(2 * phi_deg - 2 * (alpha - eps)))) + b


def dataset(t, psi_deg=23.0, d=0.8, positions=79, sigma=0.0, seed=3):
    rng = np.random.default_rng(seed)
    li = np.arange(30) / 29.0
    lf = np.stack([eq18(t, I, 0.0, 0.0) for I in li])
    th, si, sf = [], [], []
    for I in (1.0, 0.5, 0.25, 0.1, 0.05, 0.025):
        for m in range(positions):
            th.append(4.6036 * m)
            si.append(I)
            sf.append(eq18(t, I, d, psi_deg + 4.6036 * m))
    sf = np.stack(sf)
    if sigma:
        lf = lf + sigma * rng.standard_normal(lf.shape)
        sf = sf + sigma * rng.standard_normal(sf.shape)
    return li, lf, np.array(th), np.array(si), sf


# Exact frames (tests/test_dofp_calibration.cpp derives these): step 1's linear least squares of
# 30 values f ≤ 2200 DN (design condition ≈ 6) leaves rounding of ≈ 6·2.2e-16·2200 ≈ 3e-12 DN;
# step 2 stops when |Δx| < step_tolerance = 1e-10 (rad, unitless), and on exact data Gauss–Newton
# converges quadratically, so that step bounds each unknown's error (5.7e-9° for angles).
STEP1_ROUNDING_DN = 1e-11
STEP_TOL = 1e-10
STEP_TOL_DEG = np.degrees(STEP_TOL)


def test_noise_free_frames_calibrate_back_to_the_truth():
    t = truth(16, 12, 1)
    r = polrig.calibrate_dofp(*dataset(t))
    K, b, k, eps, _ = t
    assert r["usable"].all()
    np.testing.assert_allclose(r["K"] / K, 1.0, rtol=0, atol=STEP1_ROUNDING_DN / 1000)  # K/2 ≥ 950 DN per unit I
    np.testing.assert_allclose(r["b"], b, rtol=0, atol=STEP1_ROUNDING_DN)
    np.testing.assert_allclose(r["k"], k, rtol=0, atol=STEP_TOL)
    np.testing.assert_allclose(r["eps_deg"], eps, rtol=0, atol=STEP_TOL_DEG)
    assert set(r["cells"]["termination"]) == {"converged"}
    assert (r["cells"]["rank"] == 8).all()
    assert r["cells"]["k"].shape == (48, 4)
    assert r["table1"]["step2"]["max_deg"] < STEP_TOL_DEG


def test_table1_ordering_and_threads_do_not_change_results():
    t = truth(32, 24, 2)
    data = dataset(t, sigma=2.0)
    a = polrig.calibrate_dofp(*data, threads=1)
    b = polrig.calibrate_dofp(*data, threads=2)
    rows = [a["table1"][n]["std_deg"] for n in ("raw", "step1", "step2")]
    assert rows[0] > rows[1] > rows[2]
    for key in ("K", "b", "k", "eps_deg"):
        assert np.array_equal(a[key], b[key])
    assert np.array_equal(a["table1"]["step2"]["error_deg"], b["table1"]["step2"]["error_deg"])


def test_h17_cost_alone_is_rank_deficient_and_bad_input_is_said():
    t = truth(4, 2, 3)
    data = dataset(t)
    # H17's AoP residual alone determines too few unknowns: no cell is usable, so no Table 1.
    with pytest.raises(polrig.CalibrationError, match="no cell has a usable step 1 and step 2"):
        polrig.calibrate_dofp(*data, dop_weight=0, fit_weight=0)
    li, lf, th, si, sf = data
    with pytest.raises(ValueError, match="theta_R_deg"):
        polrig.calibrate_dofp(li, lf, th[:-1], si, sf)
    with pytest.raises(ValueError, match="scope 'whole'"):
        polrig.calibrate_dofp(*data, scope="whole")
    sf = sf.copy()
    sf[2, 1, 1] = np.nan
    with pytest.raises(ValueError, match="polarized stop 2: the pixel at column 1, row 1 is nan"):
        polrig.calibrate_dofp(li, lf, th, si, sf)


def test_cell_polarization_is_eq5_on_raw_frames_and_refuses_bad_maps():
    """Nominal parameters: H17 Eq. 5 in closed form for α = (0, 90, 45, 135), in NumPy."""
    rng = np.random.default_rng(3)
    frame = rng.uniform(100.0, 200.0, size=(6, 8))
    got = polrig.dofp_cell_polarization(frame)
    f1, f2, f3, f4 = frame[0::2, 0::2], frame[0::2, 1::2], frame[1::2, 0::2], frame[1::2, 1::2]
    q1, q2, q3 = (f1 - f2) / 2, (f3 - f4) / 2, (f1 + f2 + f3 + f4) / 4
    # The library solves the cell's 4 × 3 least squares (an LDLT of AᵀA, condition ≈ 4 for this
    # mosaic) where Eq. 5 is closed form: the two differ by rounding, a few ε·κ of values of
    # O(100): relative 1e-13 for S0 and the DoP (a ratio: 1e-12), 1e-10° for the AoP of cells
    # whose DoP is at least 0.01 (1e-13/0.01 rad).
    assert (np.hypot(q1, q2) / q3).min() > 0.01
    np.testing.assert_allclose(got["S0"], 2 * q3, rtol=1e-13)
    np.testing.assert_allclose(got["dop"], np.hypot(q1, q2) / q3, rtol=1e-12)
    np.testing.assert_allclose(got["aop_deg"], np.degrees(0.5 * np.arctan2(q2, q1)) % 180.0, atol=1e-10)
    with pytest.raises(ValueError, match="K: a map of 4 × 3 for a frame of 8 × 6"):
        polrig.dofp_cell_polarization(frame, K=np.ones((3, 4)))
    with pytest.raises(ValueError, match=r"pixel \(1, 0\) has K = -1"):
        K = np.ones((6, 8))
        K[0, 1] = -1
        polrig.dofp_cell_polarization(frame, K=K)
