"""The DoFP camera end to end: simulate → calibrate --method dofp → orient, the CLI against Python
(calibrate_dofp_dataset, orient_dofp_dataset) value for value, and the orderings of H17's Tables 1
and 2 (spec sky-and-compasses.md §2.7 items 3 and 5) on small simulated datasets."""
import csv
import math

import numpy as np
import pytest

import polrig
from conftest import ROOT, run_cli
from eigen_response import heading_and_elevation_gains

INDOOR = str(ROOT / "rigs" / "han2017-indoor.yaml")
OUTDOOR = str(ROOT / "rigs" / "han2017-outdoor.yaml")
# A 64 × 48 camera (768 cells) with the truth errors of spec §2.3: gains, offsets and a
# mis-registered mosaic (k and ε from the overlap formula); E_0 below saturation.
CAMERA = ["--set", "device.width_px=64", "--set", "device.height_px=48", "--set", "source.E_0=1.8",
          "--set", "device.gain_spread=0.03", "--set", "device.offset_DN=20", "--set", "device.offset_spread_DN=3",
          "--set", "device.misregistration_dx_px=0.05", "--set", "device.misregistration_rotation_deg=0.5"]
# The outdoor rig at sunset (h_s ≈ −0.5°), a 160 × 120 camera with the same field of view.
SKY = ["--set", "device.width_px=160", "--set", "device.height_px=120", "--set", "device.focal_mm=0.75"]


def rows(path):
    with open(path, newline="") as f:
        return list(csv.DictReader(f))


@pytest.fixture(scope="module")
def indoor(tmp_path_factory):
    d = tmp_path_factory.mktemp("indoor")
    run_cli("simulate", INDOOR, *CAMERA, "--frames", "mean", "-o", d / "data", "--quiet")
    run_cli("calibrate", d / "data", "--method", "dofp", "-o", d / "cal", "--quiet")
    return d


def test_calibrate_dofp_cli_equals_python_and_keeps_table_1s_order(indoor):
    table = {r["row"]: r for r in rows(indoor / "cal" / "table1.csv")}
    py = polrig.calibrate_dofp_dataset(indoor / "data", threads=1)
    for name in ("raw", "step1", "step2"):
        for col in ("max_deg", "mean_deg", "std_deg"):
            assert float(table[name][col]) == py["table1"][name][col], (name, col)
    # H17 Table 1: before > after step 1 > after step 2 (the paper: std 1.84 > 0.99 > 0.06°).
    assert float(table["step2"]["std_deg"]) < 0.1 * float(table["step1"]["std_deg"])
    assert float(table["step2"]["max_deg"]) < 0.1 * float(table["raw"]["max_deg"])
    assert py["usable"].all()


def test_orient_cli_equals_python_and_the_eigenvector_method_is_the_best(tmp_path):
    run_cli("simulate", OUTDOOR, *SKY, "-o", tmp_path / "sky", "--quiet")
    # Near sunset the s_z > 0 rule takes the antisun (spec §2.5): a prior heading chooses.
    run_cli("orient", tmp_path / "sky", "-o", tmp_path / "bare", "--quiet")
    bare = [r for r in rows(tmp_path / "bare" / "orientation.csv") if r["method"] == "eigenvector"]
    assert all(r["status"] == "near-horizon" for r in bare)
    run_cli("orient", tmp_path / "sky", "--heading-prior", "20", "-o", tmp_path / "or", "--quiet")
    cli = rows(tmp_path / "or" / "orientation.csv")
    py = polrig.orient_dofp_dataset(tmp_path / "sky", heading_prior_deg=20)
    assert len(cli) == 3 * len(py) == 3 * 40
    errors = {}
    for frame, r in zip((f for f in py for _ in range(3)), cli):
        e = frame["estimates"][["eigenvector", "single-point", "line-detection"].index(r["method"])]
        assert float(r["heading_deg"]) == e.heading_deg
        err = float(r["heading_error_deg"])
        assert math.isclose(err, (e.heading_deg - frame["true_heading_deg"] + 180) % 360 - 180, abs_tol=1e-9)
        errors.setdefault(r["method"], []).append(abs(err))
    mean = {m: sum(v) / len(v) for m, v in errors.items()}
    # H17 Table 2's order: the eigenvector method below both comparators.
    assert mean["eigenvector"] < mean["single-point"] and mean["eigenvector"] < mean["line-detection"]
    # --correct-noise-bias reaches the eigenvector method alone, the CLI and Python alike.
    run_cli("orient", tmp_path / "sky", "--heading-prior", "20", "--correct-noise-bias", "-o", tmp_path / "cor",
            "--quiet")
    cor = rows(tmp_path / "cor" / "orientation.csv")
    py_cor = polrig.orient_dofp_dataset(tmp_path / "sky", heading_prior_deg=20, correct_noise_bias=True)
    for frame, r, before in zip((f for f in py_cor for _ in range(3)), cor, cli):
        k = ["eigenvector", "single-point", "line-detection"].index(r["method"])
        assert float(r["heading_deg"]) == frame["estimates"][k].heading_deg
        assert (r["heading_deg"] == before["heading_deg"]) == (k != 0), r


def eigenvector_heading_sd_deg(frame, f_c, cx, cy, sun_l, electrons_per_DN, read_DN):
    """The SD of the eigenvector method's heading from the camera's noise, to first order;
    `frame` is a noise-free frame (DN, offset 0), `sun_l` the true sun in frame l.

    Noise per pixel (device/dofp_camera.h's Poisson–Gaussian model, in its normal limit: every
    pixel here holds ≫ 32 electrons): var f = f/electrons_per_DN + read_DN², plus 1/6 DN² for the
    two roundings (the noisy and the noise-free frame are each rounded to whole DN). The cell's
    AoP (mosaic 0, 90, 45, 135°: TL, TR, BL, BR) is φ = ½·atan2(U, Q), Q = f0 − f90,
    U = f45 − f135, so var φ = (Q²·var U + U²·var Q) / (4·(Q² + U²)²). The cells' errors are
    independent, so var H = Σ Gᵢ²·var φᵢ with eigen_response's gains Gᵢ."""
    f = frame.astype(float)
    f0, f90, f45, f135 = f[0::2, 0::2], f[0::2, 1::2], f[1::2, 0::2], f[1::2, 1::2]
    assert min(x.min() for x in (f0, f90, f45, f135)) * electrons_per_DN > 32  # the normal limit

    def var(x):
        return x / electrons_per_DN + read_DN ** 2 + 1.0 / 6.0

    Q, U = f0 - f90, f45 - f135
    var_phi = (Q ** 2 * (var(f45) + var(f135)) + U ** 2 * (var(f0) + var(f90))) / (4 * (Q ** 2 + U ** 2) ** 2)
    G, _ = heading_and_elevation_gains(Q.shape[1], Q.shape[0], f_c, cx, cy, sun_l)
    return math.degrees(math.sqrt(np.sum(G ** 2 * var_phi.reshape(-1))))


def test_the_eigenvector_headings_noise_is_the_cameras(tmp_path):
    """An absolute bound from the noise (spec §2.7 item 5 asks for the method's error): the sky rig
    run twice, with the camera's noise and without (device.noise false; the same frames less the
    noise). Per frame, the heading difference noisy − noise-free is the noise's part of the error;
    its SD σ_k follows from the Poisson–Gaussian model (eigenvector_heading_sd_deg). So
    |Δ_k| < 4σ_k for all 40 frames (P(any |z| > 4) = 40·6.3e-5 = 2.5e-3 for Gaussian z), and
    Σ(Δ_k/σ_k)²/40 lies in χ²₄₀'s central 99.8 %: [17.92, 73.40]/40. Too little noise in the
    headings fails this as too much does."""
    runs = {}
    for name, extra in (("noisy", []), ("clean", ["--set", "device.noise=false"])):
        run_cli("simulate", OUTDOOR, *SKY, *extra, "-o", tmp_path / name, "--quiet")
        runs[name] = polrig.orient_dofp_dataset(tmp_path / name, heading_prior_deg=20)
    rig = polrig.Rig.load(OUTDOOR)
    ds = polrig.read_dofp_dataset(tmp_path / "clean", mean_frames=True)
    site = (rig["sky.lat_deg"], rig["sky.lon_deg"])
    z = []
    for k, (noisy, clean) in enumerate(zip(runs["noisy"], runs["clean"])):
        assert noisy["true_heading_deg"] == clean["true_heading_deg"] == ds["stops"]["heading_deg"][k]
        sun = polrig.sun_position(ds["stops"]["utc"][k], site)
        az = math.radians(ds["stops"]["heading_deg"][k] - sun.azimuth_deg)  # the sun's azimuth in frame l
        h = math.radians(sun.elevation_deg)
        sun_l = np.array([math.cos(h) * math.cos(az), math.cos(h) * math.sin(az), math.sin(h)])
        sd = eigenvector_heading_sd_deg(ds["mean_frames"][k], ds["f_c_px"], ds["cx"], ds["cy"], sun_l,
                                        rig["device.electrons_per_DN"], rig["device.read_noise_DN"])
        delta = wrap180(noisy["estimates"][0].heading_deg - clean["estimates"][0].heading_deg)
        z.append(delta / sd)
    z = np.array(z)
    print(f"σ_k {sd:.4f}°, max |z| {np.abs(z).max():.2f}, mean z² {np.mean(z ** 2):.3f}")
    assert np.abs(z).max() < 4.0
    assert 17.92 / 40 < np.mean(z ** 2) < 73.40 / 40


def test_orient_and_calibrate_dofp_refuse_what_they_cannot_read(tmp_path, indoor):
    run_cli("simulate", str(ROOT / "rigs" / "wang2019-indoor.yaml"), "-o", tmp_path / "six", "--quiet", "--no-plots")
    r = run_cli("orient", tmp_path / "six", "-o", tmp_path / "o", check=False)
    assert r.returncode == 2 and "orient needs a polarizer mosaic (device.kind dofp-camera)" in r.stderr
    r = run_cli("calibrate", tmp_path / "six", "--method", "dofp", "-o", tmp_path / "c", check=False)
    assert r.returncode == 2 and "calibrate --method dofp needs a polarizer mosaic" in r.stderr
    # Options that do not apply to --method dofp are refused by name, not ignored.
    for option, value, reason in (("--rig", INDOOR, "reads the camera from the dataset"),
                                  ("--drift", "angle", "calibrates indoors"),
                                  ("--site", "28.2,112.9", "calibrates indoors"),
                                  ("--d-a", "0.5", "fits the source's DoP itself"),
                                  ("--nc-threshold", "0.2", "has no noncontinuous rule"),
                                  ("--nc-min-points", "12", "has no noncontinuous rule")):
        r = run_cli("calibrate", indoor / "data", "--method", "dofp", option, value, "-o", tmp_path / "c", check=False)
        assert r.returncode == 2 and option in r.stderr and reason in r.stderr, (option, r.stderr)
    r = run_cli("orient", indoor / "data", "--heading-prior", "10", "-o", tmp_path / "o", check=False)
    assert r.returncode == 2 and "has no sky rig" in r.stderr
    assert not (tmp_path / "o").exists() and not (tmp_path / "c").exists()
    with pytest.raises(polrig.RigError, match="orient needs a polarizer mosaic"):
        polrig.orient_dofp_dataset(tmp_path / "six")


def wrap180(x):
    return (x + 180.0) % 360.0 - 180.0


def test_aop_is_90_degrees_from_the_meridian_along_the_solar_meridian():
    """H17 (spec §2.7 item 2): on the solar meridian the E-vector is perpendicular to it, so a
    pixel's AoP less its view azimuth α is 90°. The camera is turned so that the sun's azimuth in
    the image is 45° (the mount at A_s + 45°: H = A_s + α_S); the pixels (c, c − 80) of the
    640 × 480 camera lie exactly on that diagonal through the principal point (320, 240), on both
    sides (solar and antisolar halves). Off the meridian (α_S = 60°) the same pixels are not at 90°,
    so the test can fail."""
    A_s = float(polrig.sun_position("2017-05-28T11:17:00Z", (28.2, 112.9)).azimuth_deg)
    rows = np.arange(480)
    for alpha_s, on_meridian in ((45.0, True), (60.0, False)):
        rig = polrig.Rig.load(OUTDOOR, set={"sky.mount_deg": wrap180(A_s + alpha_s), "schedule.angles_deg": [0]})
        _, layers = rig.dofp_frame(0, truth_layers=True)
        phi = (layers["AoP"].astype(float)[rows, rows + 80] - 45.0) % 180.0
        # float32 layers: 180° · 2⁻²⁴ ≈ 1e-5° of rounding
        assert (np.abs(phi - 90.0).max() < 1e-4) == on_meridian


def test_calibrate_dofp_view_projection_cli_equals_python(indoor, tmp_path):
    # --view-projection (docs/physics.md §14): the same Table 1 from the CLI and Python, the
    # dataset's pinhole in summary.csv; another method refuses the option and writes nothing.
    run_cli("calibrate", indoor / "data", "--method", "dofp", "--view-projection", "-o", tmp_path / "cal", "--quiet")
    table = {r["row"]: r for r in rows(tmp_path / "cal" / "table1.csv")}
    py = polrig.calibrate_dofp_dataset(indoor / "data", view_projection=True, threads=1)
    for name in ("raw", "step1", "step2"):
        for col in ("max_deg", "mean_deg", "std_deg"):
            assert float(table[name][col]) == py["table1"][name][col], (name, col)
    summary = {r["quantity"]: r["value"] for r in rows(tmp_path / "cal" / "summary.csv")}
    assert float(summary["view_projection_focal_px"]) == pytest.approx(3 / 7.4 * 1000, rel=1e-12)
    assert "view_projection_focal_px" not in {r["quantity"] for r in rows(indoor / "cal" / "summary.csv")}
    assert float(table["step2"]["std_deg"]) < 0.1 * float(table["step1"]["std_deg"])
    r = run_cli("calibrate", indoor / "data", "--method", "cs", "--view-projection", "-o", tmp_path / "c", check=False)
    assert r.returncode == 2 and "--view-projection" in r.stderr and not (tmp_path / "c").exists()
