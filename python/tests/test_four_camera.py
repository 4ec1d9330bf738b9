"""W16's four cameras from Python (docs/python.md §10): frames, fused image, truth and the dataset,
against the CLI's files bit for bit; the fused AoP through the eigenvector method gives the sun."""
import numpy as np
import pytest

import polrig
from conftest import ROOT, run_cli

STATIC = ROOT / "rigs" / "wang2016-static.yaml"
# W16's field at an eighth of its resolution (every size and intrinsic / 8), three stops.
SETS = {"schedule.count": 3, "device.cameras.width_px": 129, "device.cameras.height_px": 97,
        "device.cameras.fx_px": [96.25, 96.4, 96.1125, 96.325], "device.cameras.fy_px": [96.25, 96.4, 96.1125, 96.325],
        "device.cameras.cx_px": [64.5, 64.8, 64.4625, 64.7375], "device.cameras.cy_px": [48.5, 48.35, 48.6625, 48.45],
        "seed": 5}


def cli_sets(sets):
    out = []
    for k, v in sets.items():
        out += ["--set", f"{k}={v if not isinstance(v, list) else '[' + ','.join(map(str, v)) + ']'}"]
    return out


def test_frames_and_fused_layers_equal_the_cli_dataset_bit_for_bit(tmp_path):
    rig = polrig.Rig.load(str(STATIC), set=SETS)
    run_cli("simulate", str(STATIC), *cli_sets(SETS), "--layers", "all", "-o", tmp_path / "cli", "--quiet")
    rig.simulate_four_camera(tmp_path / "py", layers="all", threads=1)
    for stop in range(3):
        cli = polrig.read_four_camera_dataset(tmp_path / "cli", stop=stop, raw=True)
        py = polrig.read_four_camera_dataset(tmp_path / "py", stop=stop, raw=True)
        raw = rig.four_camera_frames(stop)
        assert raw.shape == (4, 97, 129) and raw.dtype == np.uint16
        assert np.array_equal(cli["raw"], raw) and np.array_equal(py["raw"], raw)
        fused = rig.four_camera_fused(stop)
        valid = fused["valid"].astype(bool)
        assert np.array_equal(cli["aop_deg"][valid], fused["AoP"][valid].astype(np.float64))
        assert np.isnan(cli["aop_deg"][~valid]).all()
        assert np.array_equal(cli["dop"], py["dop"], equal_nan=True)
        exr = polrig.read_exr(str(tmp_path / "cli" / "frames" / f"stop_{stop:04}.exr"))
        assert np.array_equal(exr["S0"].reshape(97, 129), fused["S0"])
    assert cli["f_c_px"] == fused["f_c_px"] == 96.25
    assert np.array_equal(cli["stops"]["t_s"], [0, 1, 2])
    assert cli["stops"]["utc"][0] == "2015-12-16T05:37:00Z"


def test_the_fused_aop_gives_the_sun_in_camera_1(tmp_path):
    sets = dict(SETS, **{"device.cameras.noise": False})
    rig = polrig.Rig.load(str(STATIC), set=sets)
    rig.simulate_four_camera(tmp_path / "d", layers="aop")
    ds = polrig.read_four_camera_dataset(tmp_path / "d", stop=0)
    s = polrig.sun_vector(ds["aop_deg"], f_c_px=ds["f_c_px"], principal_point=(ds["cx_px"], ds["cy_px"]),
                          element_px=1)
    truth = ds["stops"]["sun_camera1"][0]
    # Within the bilinear resampling's error at an eighth of W16's resolution (and float AoP).
    assert np.degrees(np.arccos(min(1.0, float(np.dot(s.sun, truth))))) < 0.01


def test_truth_and_refusals():
    rig = polrig.Rig.load(str(STATIC), set=SETS)
    t = rig.four_camera_truth()
    assert np.array_equal(t["polarizer_deg"], [0, 45, 90, 135])
    assert t["R_j1"].shape == (4, 3, 3) and np.array_equal(t["R_j1"][0], np.eye(3))
    # Each camera's principal point (the rig's), and the virtual camera 1's under its own names.
    assert np.array_equal(t["cx_px"], SETS["device.cameras.cx_px"])
    assert np.array_equal(t["cy_px"], SETS["device.cameras.cy_px"])
    assert (t["f_c_px"], t["virtual_cx_px"], t["virtual_cy_px"]) == (t["fx_px"][0], t["cx_px"][0], t["cy_px"][0])
    assert rig.capabilities == ["frames", "camera_array"]
    with pytest.raises(IndexError):
        rig.four_camera_frames(3)
    with pytest.raises(ValueError, match="not a camera array"):
        polrig.Rig.load(str(ROOT / "rigs" / "han2017-outdoor.yaml")).four_camera_fused(0)
    with pytest.raises(ValueError, match="no polarizer mosaic"):
        rig.dofp_frame(0)


def test_dofp_only_commands_refuse_a_four_camera_dataset(tmp_path):
    run_cli("simulate", str(STATIC), *cli_sets(dict(SETS, **{"schedule.count": 1})), "--layers", "aop",
            "-o", tmp_path / "d", "--quiet")
    for command in (["orient"], ["calibrate", "--method", "dofp"]):
        r = run_cli(*command, tmp_path / "d", "-o", tmp_path / "o", check=False)
        assert r.returncode == 2
        assert "needs a polarizer mosaic (device.kind dofp-camera); device.kind four-camera has none" in r.stderr
        assert not (tmp_path / "o").exists()
    r = run_cli("simulate", str(STATIC), "--frames", "mean", "-o", tmp_path / "x", check=False)
    assert r.returncode == 2 and "no polarizer mosaic" in r.stderr and not (tmp_path / "x").exists()
