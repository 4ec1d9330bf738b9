"""The four cameras' geometric calibration from Python (docs/python.md §10.1): the checkerboard views
of `polrig simulate` and of Rig.simulate_four_camera equal bit for bit; polrig.fit_four_camera_geometry
on them gives what geometry.csv says and the dataset's truth within the calibration's accuracy."""
import csv

import numpy as np
import pytest

import polrig
from conftest import ROOT, run_cli

STATIC = ROOT / "rigs" / "wang2016-static.yaml"
# W16's field at a third of its resolution, one stop, eight checkerboard views of 45 mm squares.
F = 770 / 3
SETS = {"schedule.count": 1, "device.cameras.width_px": 344, "device.cameras.height_px": 259,
        "device.cameras.fx_px": [F, F * 1.0015, F * 0.9986, F * 1.0008],
        "device.cameras.fy_px": [F, F * 1.0015, F * 0.9986, F * 1.0008],
        "device.cameras.cx_px": [172.3, 172.8, 171.9, 172.6], "device.cameras.cy_px": [129.7, 129.3, 130.1, 129.5],
        "checkerboard.views": 8, "checkerboard.square_mm": 45, "checkerboard.margin_mm": 35,
        "checkerboard.distance_mm": [600, 900], "seed": 11}


def cli_sets(sets):
    out = []
    for k, v in sets.items():
        out += ["--set", f"{k}={v if not isinstance(v, list) else '[' + ','.join(map(str, v)) + ']'}"]
    return out


@pytest.fixture(scope="module")
def dataset(tmp_path_factory):
    tmp = tmp_path_factory.mktemp("geom")
    run_cli("simulate", str(STATIC), *cli_sets(SETS), "--layers", "all", "-o", tmp / "cli", "--quiet")
    return tmp


def test_checkerboard_views_equal_the_cli_dataset_bit_for_bit(dataset):
    rig = polrig.Rig.load(str(STATIC), set=SETS)
    rig.simulate_four_camera(dataset / "py", layers="all", threads=1)
    for v in (1, 8):
        name = f"checkerboard/view_{v:04}.exr"
        cli, py = polrig.read_exr(str(dataset / "cli" / name)), polrig.read_exr(str(dataset / "py" / name))
        for j in range(1, 5):
            assert np.array_equal(cli[f"cam{j}"], py[f"cam{j}"])
    assert (dataset / "cli" / "checkerboard" / "poses.csv").read_text() == \
        (dataset / "py" / "checkerboard" / "poses.csv").read_text()


def test_the_fit_gives_geometry_csv_and_the_truth(dataset):
    try:
        fit = polrig.fit_four_camera_geometry(dataset / "cli", out=dataset / "fit", threads=1)
    except RuntimeError as e:
        assert "-DPOLRIG_OPENCV=ON" in str(e)
        pytest.skip(str(e))
    assert fit["usable"], fit["report"]
    rows = list(csv.DictReader(open(dataset / "fit" / "geometry.csv")))
    assert len(rows) == 4
    for j, (cam, row, truth) in enumerate(zip(fit["cameras"], rows, fit["truth"])):
        assert cam["termination"] == "converged" and cam["views_detected"] == 8
        for key in ("fx_px", "fy_px", "cx_px", "cy_px", "rms_px", "stereo_rms_px"):
            assert float(row[key]) == cam[key]
        assert float(row["fx_true_px"]) == truth["fx_px"]
        # The tests' derived bounds at this size (tests/test_four_camera_geometry.cpp) are far
        # wider; these are what OpenCV's corners (~0.07 px RMS) give in practice.
        assert cam["rms_px"] < 0.15
        assert abs(cam["fx_px"] - truth["fx_px"]) < 0.02 * truth["fx_px"]
        assert abs(cam["cx_px"] - truth["cx_px"]) < 3
        if j > 0:
            assert float(row["rotation_error_deg"]) < 1.0
            assert np.linalg.norm(cam["position_mm"] - truth["position_mm"]) < 20
    # An existing folder is refused before anything is fitted; force replaces it.
    with pytest.raises(ValueError, match="exists"):
        polrig.fit_four_camera_geometry(dataset / "cli", out=dataset / "fit")
    polrig.fit_four_camera_geometry(dataset / "cli", out=dataset / "fit", force=True, threads=1)


def test_a_dataset_without_views_is_refused(dataset, tmp_path):
    rig = polrig.Rig.load(str(STATIC), set={**SETS, "checkerboard.views": 0})
    rig.simulate_four_camera(tmp_path / "none", threads=1)
    with pytest.raises((ValueError, RuntimeError), match="no checkerboard views|POLRIG_OPENCV"):
        polrig.fit_four_camera_geometry(tmp_path / "none")
