"""The DoFP camera from Python (docs/python.md §9): frames, truth and the dataset, against the CLI.

Camera rigs are named by the rig key device.kind, in rigs/han2017-*.yaml (the seam lane's); until
they are in the tree, these tests skip."""
import shutil

import numpy as np
import pytest

import polrig
from conftest import ROOT, run_cli

WANG = str(ROOT / "rigs" / "wang2019-indoor.yaml")
INDOOR = ROOT / "rigs" / "han2017-indoor.yaml"
OUTDOOR = ROOT / "rigs" / "han2017-outdoor.yaml"
# A short run: one unpolarized level, two table angles, two frames per stop.
CAMERA = {"schedule.angles_deg": [0, 45], "schedule.unpolarized_levels": [0.5], "schedule.intensities": [1],
          "schedule.frames_per_stop": 2, "seed": 11}


def camera_rig(path=INDOOR, sets=CAMERA):
    if not path.exists():
        pytest.skip(f"{path.name} is not in the tree yet")
    return polrig.Rig.load(str(path), set=sets)


def cli_sets(sets):
    out = []
    for k, v in sets.items():
        out += ["--set", f"{k}={v if not isinstance(v, list) else '[' + ','.join(map(str, v)) + ']'}"]
    return out


def test_frames_equal_the_cli_dataset_bit_for_bit(tmp_path):
    rig = camera_rig()
    stops = rig.dofp_stops()
    run_cli("simulate", str(INDOOR), *cli_sets(CAMERA), "--truth-layers", "-o", tmp_path / "cli", "--quiet")
    rig.simulate_frames(tmp_path / "py", truth_layers=True, threads=1)
    ds_cli = polrig.read_dofp_dataset(tmp_path / "cli", mean_frames=True)
    ds_py = polrig.read_dofp_dataset(tmp_path / "py", mean_frames=True)
    assert np.array_equal(ds_cli["mean_frames"], ds_py["mean_frames"])
    assert np.array_equal(ds_cli["stops"]["theta_R_deg"], stops["theta_R_deg"])
    assert list(stops["polarized"]) == [False, True, True]
    for i in range(len(stops["stop"])):
        raw, layers = rig.dofp_frame(i, 0, truth_layers=True, threads=2)
        raw1 = rig.dofp_frame(i, 1, threads=1)
        assert raw.dtype == np.uint16 and raw.shape == (ds_cli["height"], ds_cli["width"])
        assert np.array_equal((raw.astype(np.float64) + raw1) / 2, ds_cli["mean_frames"][i])
        exr = polrig.read_exr(str(tmp_path / "cli" / ds_cli["stops"]["file"][i]))
        assert np.array_equal(exr["AoP"], layers["AoP"])
        assert np.array_equal(exr["raw.000"], raw.astype(np.float32))
        assert np.array_equal(exr["raw.001"], raw1.astype(np.float32))
    truth = rig.dofp_truth()
    for name in ("K", "b", "k", "eps_deg", "alpha_deg"):
        assert np.array_equal(truth[name].astype(np.float32), ds_cli["truth"][name])
    assert ds_cli["f_c_px"] == pytest.approx(405.405, abs=1e-3)
    # The CLI draws the previews (formats.md §6.14d); Python with plots=True, the same data bit for bit.
    assert not (tmp_path / "py" / "previews").exists()
    if shutil.which("gnuplot"):
        rig.simulate_frames(tmp_path / "pyplots", truth_layers=True, plots=True, threads=1)
        for name in ("stop_0000.csv", "stop_0002.csv", "previews.gp"):
            assert (tmp_path / "pyplots" / "previews" / name).read_bytes() == \
                (tmp_path / "cli" / "previews" / name).read_bytes(), name
        for name in ("stop_0000_aop.png", "stop_0002_dop.png", "stop_0002_s0.png"):
            assert (tmp_path / "pyplots" / "previews" / name).stat().st_size > 1000, name


def test_thread_counts_give_the_same_frame_and_bad_arguments_are_refused():
    rig = camera_rig()
    assert np.array_equal(rig.dofp_frame(1, 2, threads=1), rig.dofp_frame(1, 2, threads=2))
    with pytest.raises(IndexError):
        rig.dofp_frame(99)
    with pytest.raises(ValueError):
        rig.dofp_frame(0, analyzer="behind")
    with pytest.raises(ValueError):
        polrig.Rig.load(WANG).dofp_frame(0)  # the six-photodiode sensor takes no frames



def test_traced_sphere_frames_equal_the_cli_bit_for_bit(tmp_path):
    # A camera under the traced sphere (docs/physics.md §13): the small theory sphere, its port
    # film at 30° in the scene; the same frames from Python (any thread count) as from the CLI.
    (tmp_path / "scene.yaml").write_text(
        "port: {diameter: 100, polarizer: {axis_deg: 30, tau_M: 0.62, tau_m: 0.18}}\n"
        "lamps:\n  - {position: [0, 0, 0], radius: 0, power: 100}\nbaffles: []\n"
        "trace: {photons: 20000, plane_samples: 64}\n")
    path = tmp_path / "rig.yaml"
    path.write_text("device: {kind: dofp-camera, width_px: 32, height_px: 24, gain_DN: 4}\n"
                    "source: {model: traced, scene: scene.yaml}\n"
                    "schedule: {angles_deg: [0, 40], frames_per_stop: 2}\n")
    run_cli("simulate", path, "--truth-layers", "-o", tmp_path / "cli", "--quiet")
    ds = polrig.read_dofp_dataset(tmp_path / "cli", mean_frames=True)
    rig = polrig.Rig.load(str(path))
    for i in range(len(rig.dofp_stops()["stop"])):
        raw, layers = rig.dofp_frame(i, 0, truth_layers=True, threads=2)
        raw1 = rig.dofp_frame(i, 1, threads=1)
        assert np.array_equal((raw.astype(np.float64) + raw1) / 2, ds["mean_frames"][i])
        exr = polrig.read_exr(str(tmp_path / "cli" / ds["stops"]["file"][i]))
        assert np.array_equal(exr["AoP"], layers["AoP"])
        assert np.all(layers["DoP"] == np.float32(0.55))
        # On the axis the camera sees θ_R − ψ_P, ψ_P = −30° the film's axis in the rig frame.
        theta_R = rig.dofp_stops()["theta_R_deg"][i]
        assert abs((layers["AoP"][12, 16] - (theta_R + 30) + 90) % 180 - 90) < 1e-3

def test_sky_rig_carries_the_true_heading(tmp_path):
    rig = camera_rig(OUTDOOR, {"schedule.angles_deg": [0, 10]})
    rig.simulate_frames(tmp_path / "sky", frames="mean")
    ds = polrig.read_dofp_dataset(tmp_path / "sky")
    h = ds["stops"]["heading_deg"]
    assert np.all(np.isfinite(h))
    assert (h[1] - h[0]) % 360 == pytest.approx(10.0, abs=1e-9)  # the table turns X_l clockwise from above
    assert ds["stops"]["utc"][0].endswith("Z")
