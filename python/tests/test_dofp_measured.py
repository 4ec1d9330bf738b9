"""A measured camera dataset (docs/formats.md §6.14 "A measured dataset"): a researcher's frames,
stops.csv and a camera rig.yaml, no truth.exr. `calibrate --method dofp` and `orient` give the
same files as for the same dataset with its truth.exr (neither computation reads the truth),
Python reads it with truth None and computes the CLI's values, and a rig.yaml that does not give
the camera is refused naming the file and the key."""
import shutil

import numpy as np

import polrig
from conftest import ROOT, read_csv, run_cli

INDOOR = str(ROOT / "rigs" / "han2017-indoor.yaml")
OUTDOOR = str(ROOT / "rigs" / "han2017-outdoor.yaml")
SMALL = ["--set", "device.width_px=24", "--set", "device.height_px=20", "--set", "schedule.step_deg=40",
         "--set", "schedule.stop_deg=320", "--set", "schedule.intensities=[1, 0.5]",
         "--set", "schedule.unpolarized_levels=[0, 0.5, 1]", "--set", "device.gain_spread=0.03",
         "--set", "device.misregistration_dx_px=0.05"]
CAL_FILES = ("params.exr", "table1.csv", "errors.csv", "cells.csv", "summary.csv")


def pair(tmp_path, *simulate):
    """The dataset `simulate` writes, and a copy without truth.exr (a measured dataset)."""
    run_cli("simulate", *simulate, "-o", tmp_path / "with", "--quiet")
    shutil.copytree(tmp_path / "with", tmp_path / "without")
    (tmp_path / "without" / "truth.exr").unlink()
    return tmp_path / "with", tmp_path / "without"


def test_calibrate_dofp_without_truth_exr_writes_the_same_files(tmp_path):
    with_, without = pair(tmp_path, INDOOR, *SMALL, "--frames", "mean")
    for d in (with_, without):
        # Beside the dataset: an output inside an input is refused (docs/cli.md, -o).
        run_cli("calibrate", d, "--method", "dofp", "-o", f"{d}-cal", "--quiet", "--no-plots")
    for f in CAL_FILES:
        assert (tmp_path / "with-cal" / f).read_bytes() == (tmp_path / "without-cal" / f).read_bytes(), f
    a, b = polrig.read_dofp_dataset(with_), polrig.read_dofp_dataset(without)
    assert b["truth"] is None and a["truth"] is not None
    for key in ("width", "height", "f_c_px", "cx", "cy", "mosaic_deg", "adc_bits"):
        assert a[key] == b[key], key
    py = polrig.calibrate_dofp_dataset(without, threads=1)
    table = read_csv(tmp_path / "without-cal" / "table1.csv")
    for i, name in enumerate(table["row"]):
        for col in ("max_deg", "mean_deg", "std_deg"):
            assert table[col][i] == py["table1"][name][col], (name, col)


def test_orient_without_truth_exr_writes_the_same_orientation(tmp_path):
    sky = ["--set", "device.width_px=160", "--set", "device.height_px=120", "--set", "device.focal_mm=0.75"]
    with_, without = pair(tmp_path, OUTDOOR, *sky)
    for d in (with_, without):
        run_cli("orient", d, "--heading-prior", "20", "-o", f"{d}-or", "--quiet", "--no-plots")
    text = (tmp_path / "with-or" / "orientation.csv").read_bytes()
    assert (tmp_path / "without-or" / "orientation.csv").read_bytes() == text
    cli = read_csv(tmp_path / "without-or" / "orientation.csv")
    assert np.isfinite(cli["heading_error_deg"]).all()  # every frame has its true heading
    py = polrig.orient_dofp_dataset(without, heading_prior_deg=20)
    eig = [f["estimates"][0].heading_deg for f in py]
    assert list(cli["heading_deg"][cli["method"] == "eigenvector"]) == eig


def test_a_measured_dataset_needs_the_camera_in_its_rig(tmp_path):
    _, without = pair(tmp_path, INDOOR, *SMALL, "--frames", "mean")
    camera = {"width_px": "24", "height_px": "20", "pixel_um": "7.4", "focal_mm": "3",
              "mosaic_deg": "[0, 90, 45, 135]"}

    def rig(skip=None):
        lines = ["device:", "  kind: dofp-camera"] + [f"  {k}: {v}" for k, v in camera.items() if k != skip]
        (without / "rig.yaml").write_text("\n".join(lines) + "\n")

    rig()  # the researcher's own rig.yaml: the camera alone
    run_cli("calibrate", without, "--method", "dofp", "-o", tmp_path / "cal", "--quiet", "--no-plots")
    assert polrig.read_dofp_dataset(without)["adc_bits"] == 0  # not given: nothing left out as clipped
    rig(skip="focal_mm")
    r = run_cli("calibrate", without, "--method", "dofp", "-o", tmp_path / "c2", check=False)
    assert r.returncode == 2, r.stderr
    assert f"{without / 'rig.yaml'}: key 'device.focal_mm' is not given" in r.stderr
    assert not (tmp_path / "c2").exists()
    r = run_cli("orient", without, "-o", tmp_path / "o2", check=False)
    assert r.returncode == 2 and "key 'device.focal_mm' is not given" in r.stderr
    (without / "rig.yaml").unlink()
    r = run_cli("calibrate", without, "--method", "dofp", "-o", tmp_path / "c3", check=False)
    assert r.returncode == 2 and "no truth.exr and no rig.yaml" in r.stderr
