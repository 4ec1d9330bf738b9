"""W16's radiometric and polarizer-angle calibration from Python (docs/python.md): calibrate_four_camera
against `polrig calibrate --method four-camera`'s files bit for bit, and locate_dataset(calibration=...)
against `polrig locate --calibration`'s."""
import numpy as np
import pytest

import polrig
from conftest import ROOT, read_csv, run_cli

CALIBRATION = ROOT / "rigs" / "wang2016-calibration.yaml"
STATIC = ROOT / "rigs" / "wang2016-static.yaml"
# W16's field at an eighth of its resolution.
EIGHTH = ["--set", "device.cameras.width_px=130", "--set", "device.cameras.height_px=98",
          "--set", "device.cameras.cx_px=[65,65.2,64.8,65.1]", "--set", "device.cameras.cy_px=[49,48.9,49.2,48.8]",
          "--set", "device.cameras.fx_px=[96.25,96.4,96.1,96.3]", "--set", "device.cameras.fy_px=[96.25,96.4,96.1,96.3]"]


@pytest.fixture(scope="module")
def calibrated(tmp_path_factory):
    d = tmp_path_factory.mktemp("fcal")
    run_cli("simulate", CALIBRATION, *EIGHTH, "--set", "checkerboard.views=0", "--layers", "all", "-o", d / "cal",
            "--quiet")
    run_cli("calibrate", d / "cal", "--method", "four-camera", "-o", d / "out", "--quiet", "--no-plots")
    return d


def test_calibrate_four_camera_equals_the_cli_bit_for_bit(calibrated):
    d = calibrated
    py = polrig.calibrate_four_camera(d / "cal", threads=1)
    assert py["calibration_yaml"] == (d / "out" / "calibration.yaml").read_text()
    err = read_csv(d / "out" / "errors.csv")
    for j in range(4):
        k = np.flatnonzero((err["quantity"] == "K_DN") & (err["camera"] == j + 1))[0]
        assert err["fitted"][k] == py["K"][j] and err["standard_error"][k] == py["K_se"][j]
    eps = err["fitted"][err["quantity"] == "eps_deg"]
    assert list(eps) == list(py["eps_deg"][1:]) and py["eps_deg"][0] == 0.0
    pol = read_csv(d / "out" / "polarizer.csv")
    for col in ("theta_R_deg", "aop_before_deg", "aop_after_deg", "residual_before_deg", "residual_after_deg"):
        assert np.array_equal(pol[col], py[col]), col
    assert py["polarizer"]["termination"] == "converged" and py["polarizer"]["rank"] == 5
    assert "truth.yaml" in py["geometry_from"] and py["geometry"] is None  # no checkerboard views: no geometric fit
    # --geometry: the same calibration from the truth file given explicitly, which the file then names.
    g = polrig.calibrate_four_camera(d / "cal", d / "cal" / "truth.yaml")
    assert np.array_equal(g["eps_deg"], py["eps_deg"]) and str(d / "cal" / "truth.yaml") in g["geometry_from"]


def test_locate_dataset_with_a_calibration_equals_the_cli(calibrated, tmp_path):
    d = calibrated
    run_cli("simulate", STATIC, *EIGHTH, "--set", "schedule.count=4", "--set", "schedule.dwell_s=600", "--layers", "all",
            "-o", tmp_path / "sky", "--quiet")
    cal = str(d / "out" / "calibration.yaml")
    run_cli("locate", tmp_path / "sky", "--prior", "28,113", "--calibration", cal, "-o", tmp_path / "loc", "--quiet")
    py = polrig.locate_dataset(str(tmp_path / "sky"), (28, 113), calibration=cal)
    fix = read_csv(tmp_path / "loc" / "fix.csv")
    assert fix["lat_deg"][0] == py.fix.lat_deg[0] and fix["lon_deg"][0] == py.fix.lon_deg[0]
    heading = read_csv(tmp_path / "loc" / "heading.csv")
    assert np.array_equal(heading["heading_deg"], py.heading_deg)
    with pytest.raises(polrig.DataError, match="--layers all"):
        run_cli("simulate", STATIC, *EIGHTH, "--set", "schedule.count=2", "--layers", "aop", "-o", tmp_path / "aop",
                "--quiet")
        polrig.locate_dataset(str(tmp_path / "aop"), (28, 113), calibration=cal)


def test_a_dataset_without_its_truth_locates_as_the_simulated_one(calibrated, tmp_path):
    """A measured dataset keeps no truth.yaml and no truth columns: the virtual camera comes from the
    frames' attributes, the fix is the simulated dataset's (C++: raw frames alone, no rig.yaml)."""
    import shutil
    d = calibrated
    run_cli("simulate", STATIC, *EIGHTH, "--set", "schedule.count=3", "--set", "schedule.dwell_s=900", "--layers", "all",
            "-o", tmp_path / "sky", "--quiet")
    shutil.copytree(tmp_path / "sky", tmp_path / "measured")
    (tmp_path / "measured" / "truth.yaml").unlink()
    lines = (tmp_path / "sky" / "stops.csv").read_text().splitlines()
    rows = [lines[0]] + [",".join(c[:6] + [""] * 6 + c[12:]) for c in (line.split(",") for line in lines[1:])]
    (tmp_path / "measured" / "stops.csv").write_text("\n".join(rows) + "\n")
    sim = polrig.read_four_camera_dataset(str(tmp_path / "sky"))
    measured = polrig.read_four_camera_dataset(str(tmp_path / "measured"))
    assert (measured["width"], measured["height"]) == (sim["width"], sim["height"])
    assert (measured["f_c_px"], measured["cx_px"], measured["cy_px"]) == (sim["f_c_px"], sim["cx_px"], sim["cy_px"])
    assert np.all(np.isnan(measured["stops"]["heading_deg"]))
    cal = str(d / "out" / "calibration.yaml")
    for calibration in (None, cal):
        a = polrig.locate_dataset(str(tmp_path / "sky"), (28, 113), calibration=calibration)
        b = polrig.locate_dataset(str(tmp_path / "measured"), (28, 113), calibration=calibration)
        assert (b.fix.lat_deg[0], b.fix.lon_deg[0]) == (a.fix.lat_deg[0], a.fix.lon_deg[0])
        assert np.array_equal(b.heading_deg, a.heading_deg)


def test_refusals(calibrated, tmp_path):
    with pytest.raises(polrig.DataError, match="no unpolarized stop"):
        run_cli("simulate", STATIC, *EIGHTH, "--set", "schedule.count=2", "--layers", "all", "-o", tmp_path / "sky",
                "--quiet")
        polrig.calibrate_four_camera(tmp_path / "sky")
    bad = tmp_path / "bad.yaml"
    bad.write_text((calibrated / "out" / "calibration.yaml").read_text().replace("K_DN: ", "K_DN: -", 1))
    with pytest.raises(polrig.DataError, match=r"bad.yaml:\d+: key 'cameras\[0\].K_DN'"):
        polrig.locate_dataset(str(tmp_path / "sky"), (28, 113), calibration=str(bad))
    with pytest.raises(ValueError, match=r"distortion_terms=5 \(expected 0 … 4\)"):
        polrig.calibrate_four_camera(calibrated / "cal", distortion_terms=5)
    with pytest.raises(ValueError, match="distortion_terms=2: the geometric calibration's option"):
        polrig.calibrate_four_camera(calibrated / "cal", calibrated / "cal" / "truth.yaml", distortion_terms=2)


def test_with_checkerboard_views_the_geometry_is_the_geometric_fit(tmp_path):
    """A dataset with views: calibrate_four_camera's geometry is the geometric calibration's, the same
    values as the CLI's geometry.csv and calibration.yaml (a third of W16's resolution, where OpenCV
    finds the board)."""
    third = ["--set", "device.cameras.width_px=345", "--set", "device.cameras.height_px=259",
             "--set", "device.cameras.cx_px=[172.5,172.9,172.1,172.8]",
             "--set", "device.cameras.cy_px=[129.8,129.4,130.2,129.6]",
             "--set", "device.cameras.fx_px=[256.7,257.1,256.3,256.9]",
             "--set", "device.cameras.fy_px=[256.7,257.1,256.3,256.9]",
             "--set", "checkerboard.square_mm=45", "--set", "checkerboard.views=12",
             "--set", "schedule.step_deg=60", "--set", "schedule.stop_deg=300"]
    run_cli("simulate", CALIBRATION, *third, "--layers", "all", "-o", tmp_path / "cal", "--quiet")
    try:
        py = polrig.calibrate_four_camera(tmp_path / "cal", distortion_terms=2)
    except polrig.DataError as e:  # views in a build without OpenCV: refused, naming the option
        assert "-DPOLRIG_OPENCV=ON" in str(e)
        pytest.skip("polrig built without OpenCV")
    run_cli("calibrate", tmp_path / "cal", "--method", "four-camera", "-o", tmp_path / "out", "--distortion-terms", "2",
            "--quiet", "--no-plots")
    assert "checkerboard" in py["geometry_from"] and py["geometry"]["usable"]
    geo = read_csv(tmp_path / "out" / "geometry.csv")
    for j, cam in enumerate(py["geometry"]["cameras"]):
        assert cam["fx_px"] == geo["fx_px"][j] and cam["cy_px"] == geo["cy_px"][j]
        assert cam["k"][2] == 0 and cam["k"][3] == 0
    assert py["calibration_yaml"] == (tmp_path / "out" / "calibration.yaml").read_text()
