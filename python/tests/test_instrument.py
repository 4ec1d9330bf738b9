"""The instrument seam from Python: Rig.instrument, Rig.can / Rig.capabilities, the keys each
instrument reads, the camera's rig files, and the library's capability errors (the CLI's messages
word for word)."""
import pickle
import re

import pytest

import polrig
from conftest import ROOT, run_cli

INDOOR = str(ROOT / "rigs" / "wang2019-indoor.yaml")
CAMERA = str(ROOT / "rigs" / "han2017-indoor.yaml")
CAMERA_OUTDOOR = str(ROOT / "rigs" / "han2017-outdoor.yaml")


def test_the_default_rig_is_the_six_photodiode_sensor():
    r = polrig.Rig()
    assert r.instrument == "six-photodiode"
    assert r.capabilities == ["pair_voltages"]
    assert r.can("pair_voltages") and not r.can("frames")
    with pytest.raises(ValueError, match="unknown capability 'voltages'"):
        r.can("voltages")


def test_the_camera_rigs_load_with_their_instrument():
    for path, stops in ((CAMERA, 79), (CAMERA_OUTDOOR, 40)):
        r = polrig.Rig.load(path)
        assert r.instrument == "dofp-camera"
        assert r.capabilities == ["frames", "mosaic"] and r.can("frames") and not r.can("pair_voltages")
        assert r["device.kind"] == "dofp-camera"
        assert r["device.width_px"] == 640 and r["device.noise"] is True
        assert "device.focal_mm" in r and "device.L_photo" not in r
        assert "device.L_photo" in polrig.Rig() and "device.focal_mm" not in polrig.Rig()
        assert "schedule.samples_per_stop" not in r.keys() and "schedule.intensities" in r.keys()
        # to_yaml / to_dict / pickle keep the instrument.
        assert polrig.Rig.from_yaml(r.to_yaml()).to_yaml() == r.to_yaml()
        assert polrig.Rig.from_dict(r.to_dict()).instrument == "dofp-camera"
        assert pickle.loads(pickle.dumps(r)).instrument == "dofp-camera"
        assert r.copy().instrument == "dofp-camera"
    assert len(polrig.Rig.load(CAMERA)["schedule.unpolarized_levels"]) == 30


def test_a_key_the_instrument_does_not_read_is_refused():
    with pytest.raises(polrig.RigError, match="key 'device.L_photo': expected no value with "
                       r"device.kind dofp-camera \(only device.kind six-photodiode reads it\)"):
        polrig.Rig.load(CAMERA, set={"device.L_photo": 14})
    r = polrig.Rig()
    with pytest.raises(polrig.RigError, match="key 'device.focal_mm': expected no value with device.kind six-photodiode"):
        r["device.focal_mm"] = 3
    assert r.instrument == "six-photodiode"  # unchanged
    c = polrig.Rig.load(CAMERA)
    c["device.noise"] = False
    assert c["device.noise"] is False
    with pytest.raises(polrig.RigError, match="expected an even integer"):
        c["device.width_px"] = 641


def test_rig_keys_names_the_instruments_as_the_cli_table_does():
    keys = {k["path"]: k for k in polrig.rig_keys()}
    assert keys["device.L_photo"]["instruments"] == "six-photodiode"
    assert keys["device.focal_mm"]["instruments"] == "dofp-camera"
    assert keys["device.d"]["instruments"] == "all"
    assert keys["device.kind"]["default"] == "six-photodiode"
    assert keys["device.noise"]["kind"] == "bool" and keys["device.noise"]["default"] is True
    table = run_cli("rig", "keys").stdout.splitlines()[2:]
    cli = {row.split("|")[1].strip().strip("`"): row.split("|")[9].strip() for row in table}
    assert {p: k["instruments"] for p, k in keys.items()} == cli


def test_the_studies_refuse_a_camera_with_the_clis_message(tmp_path):
    r = polrig.Rig.load(CAMERA)
    tail = "needs pair voltages (device.kind six-photodiode); device.kind dofp-camera has none"
    calls = {
        "simulate": lambda: r.simulate(),
        "study cs": lambda: r.study_cs(),
        "study adc": lambda: r.study_adc(),
        "sweep": lambda: r.sweep(grid=["eccentricity.L_S=0:1:2"]),
        "study calibration": lambda: r.study_calibration(trials=1),
        "light_at_pose": lambda: r.light_at_pose(0.0),
    }
    for what, call in calls.items():
        with pytest.raises(polrig.RigError) as e:
            call()
        assert str(e.value) == f"{CAMERA}: {what} {tail}"
        # (the CLI's simulate takes frames from a camera rig: test_dofp.py; Rig.simulate_frames)
        if what in ("study cs", "study adc", "sweep", "study calibration"):
            out = tmp_path / what.replace(" ", "_")
            cli = run_cli(*what.split(), CAMERA, "-o", out, *(["--grid", "eccentricity.L_S=0:1:2"]
                                                              if what == "sweep" else []), check=False)
            assert cli.returncode == 2
            assert cli.stderr == f"polrig: error: {CAMERA}: {what} {tail}\n"
            assert not out.exists()
    outdoor = polrig.Rig.load(CAMERA_OUTDOOR)
    with pytest.raises(polrig.RigError, match=re.escape(f"study heading {tail}")):
        outdoor.study_heading(trials=1)
    with pytest.raises(polrig.RigError, match=re.escape(f"calibrate method='cs-nc' {tail}")):
        polrig.calibrate([0.0, 180.0], [[0.0, 0.0, 0.0], [0.0, 0.0, 0.0]], rig=r)
