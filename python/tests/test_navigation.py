"""Z21's unit-array compass with a strapdown INS from Python (docs/python.md): the dataset, the three
modes and the installation calibration give the CLI's files and numbers, bit for bit."""
import numpy as np
import pytest

import polrig
from conftest import ROOT, read_csv, run_cli

RIG = ROOT / "rigs" / "zhang2021-static.yaml"
SHORT = {"trajectory.duration_s": 120}


def short_rig():
    return polrig.Rig.load(str(RIG), set=SHORT)


def test_simulate_writes_the_cli_dataset_and_its_arrays(tmp_path):
    rig = short_rig()
    d = rig.simulate_navigation(tmp_path / "py")
    run_cli("simulate", RIG, "--set", "trajectory.duration_s=120", "-o", tmp_path / "cli", "--quiet")
    for f in ("imu.csv", "units.csv", "truth.csv", "truth.yaml"):
        assert (tmp_path / "py" / f).read_bytes() == (tmp_path / "cli" / f).read_bytes(), f
    assert d["dtheta_rad"].shape == (12000, 3)
    assert d["aop_deg"].shape == (120, 9)
    imu = read_csv(tmp_path / "cli" / "imu.csv")
    np.testing.assert_array_equal(d["dv_mps"][:, 2], imu["dv_z_mps"])
    np.testing.assert_array_equal(d["truth"]["lat_deg"], read_csv(tmp_path / "cli" / "truth.csv")["lat_deg"])
    # The dataset read back: the files' numbers.
    back = polrig.read_navigation_dataset(tmp_path / "py")
    np.testing.assert_array_equal(back["dtheta_rad"], d["dtheta_rad"])


def test_navigate_equals_the_cli(tmp_path):
    run_cli("simulate", RIG, "--set", "trajectory.duration_s=120", "-o", tmp_path / "d", "--quiet")
    r = polrig.navigate(tmp_path / "d", out=tmp_path / "py")
    run_cli("navigate", tmp_path / "d", "-o", tmp_path / "cli", "--no-plots", "--quiet")
    for f in ("solution.csv", "filter.csv", "summary.csv", "filter_summary.yaml"):
        assert (tmp_path / "py" / f).read_bytes() == (tmp_path / "cli" / f).read_bytes(), f
    sol = read_csv(tmp_path / "cli" / "solution.csv")
    sins = sol["mode"] == "sins"
    np.testing.assert_array_equal(r["sins"]["lat_deg"], sol["lat_deg"][sins])
    np.testing.assert_array_equal(r["integrated"]["err_north_m"], sol["err_north_m"][sol["mode"] == "integrated"])
    assert r["filter"]["summary"]["updates"] == 120
    assert set(r["summary"]) == {"sins", "pns", "integrated"}
    assert r["pns"]["status"][0] == "window_filling"
    with pytest.raises(ValueError, match="mode 'best': expected sins, pns, integrated, smoothed or all"):
        polrig.navigate(tmp_path / "d", mode="best")
    # The smoother, asked for by name; the last reading is the filter's own.
    s = polrig.navigate(tmp_path / "d", mode="integrated,smoothed")
    assert set(s) >= {"integrated", "smoothed"} and "sins" not in s
    assert s["smoothed"]["lat_deg"][-1] == s["integrated"]["lat_deg"][-1]
    np.testing.assert_array_equal(s["integrated"]["lat_deg"], r["integrated"]["lat_deg"])
    with pytest.raises(ValueError, match="no rig.yaml"):
        polrig.navigate(tmp_path)
    # The third review's finding 3: out= over the input is refused, and the dataset kept.
    for out in (tmp_path / "d", tmp_path):
        with pytest.raises(ValueError, match="out: the output folder .* (is|contains) the input"):
            polrig.navigate(tmp_path / "d", out=out, force=True)
        with pytest.raises(ValueError, match="out: the output folder .* (is|contains) the input"):
            polrig.calibrate_unit_array(tmp_path / "d", out=out, force=True)
    assert (tmp_path / "d" / "imu.csv").exists()
    # Finding 18: plots= without out=, an empty calibration name, a NUL in a cell (quoted whole).
    with pytest.raises(ValueError, match="plots=True: the plots are written into out="):
        polrig.navigate(tmp_path / "d", plots=True)
    with pytest.raises(ValueError, match="calibration='': expected a file name"):
        polrig.navigate(tmp_path / "d", calibration="")
    bad = tmp_path / "bad"
    bad.mkdir()
    for f in ("imu.csv", "units.csv", "rig.yaml"):
        (bad / f).write_bytes((tmp_path / "d" / f).read_bytes())
    text = (bad / "units.csv").read_text().split("\n")
    cells = text[1].split(",")
    cells[2] = "12\x003"
    text[1] = ",".join(cells)
    (bad / "units.csv").write_text("\n".join(text))
    with pytest.raises(Exception, match=r"units.csv:2: column 'aop_deg': expected a finite number, got '12\\x003'"):
        polrig.navigate(bad)


def test_zero_velocity_updates_from_python_are_the_clis(tmp_path):
    # navigation.zupt on the static rig: every reading at rest gets its east and north updates.
    run_cli("simulate", RIG, "--set", "trajectory.duration_s=120", "-o", tmp_path / "d", "--quiet")
    rig = polrig.Rig.load(str(RIG), set={"trajectory.duration_s": 120, "navigation.zupt": True}, dataset=True)
    r = polrig.navigate(tmp_path / "d", mode="integrated", rig=rig, out=tmp_path / "py")
    run_cli("navigate", tmp_path / "d", "--mode", "integrated", "--set", "navigation.zupt=true", "-o", tmp_path / "cli",
            "--no-plots", "--quiet")
    assert (tmp_path / "py" / "filter.csv").read_bytes() == (tmp_path / "cli" / "filter.csv").read_bytes()
    f = r["filter"]
    assert np.all(f["rest_statistic"] < 1.3)
    assert np.all(np.isfinite(f["zero_velocity_nis_e"])) and np.all(np.isnan(f["zero_velocity_nis_u"]))
    assert f["summary"]["zero_velocity_updates"] == 240
    assert np.all(np.isnan(f["pns_fix_nis"]))  # no pns-fix


def test_calibrate_unit_array_equals_the_cli(tmp_path):
    # The vehicle run: its turns determine each unit's three errors (a static run leaves them confounded).
    run_cli("simulate", ROOT / "rigs" / "zhang2021-vehicle.yaml", "--set", "device.units.mount_error_sd_deg=1",
            "-o", tmp_path / "d", "--quiet")
    r = polrig.calibrate_unit_array(tmp_path / "d", out=tmp_path / "py")
    run_cli("calibrate", tmp_path / "d", "--method", "unit-array", "-o", tmp_path / "cli", "--no-plots", "--quiet")
    for f in ("calibration.yaml", "installation.csv"):
        assert (tmp_path / "py" / f).read_bytes() == (tmp_path / "cli" / f).read_bytes(), f
    assert r["error_deg"].shape == (9, 3)
    assert r["attitude_from"] == "truth"
    n = polrig.navigate(tmp_path / "d", mode="integrated", calibration=tmp_path / "py" / "calibration.yaml")
    assert n["filter"]["summary"]["updates"] == 1200
    assert np.all(np.abs(r["error_deg"] - polrig.Rig.load(str(ROOT / "rigs" / "zhang2021-vehicle.yaml"),
                                                         set={"device.units.mount_error_sd_deg": 1})
                         .simulate_navigation()["truth"]["mount_error_deg"]) < 4 * r["standard_error_deg"] + 0.01)


def test_study_navigation_equals_the_cli(tmp_path):
    rig = polrig.Rig.load(str(RIG), set={"trajectory.duration_s": 360})
    r = rig.study_navigation(trials=2, p_max=[0.5], out=tmp_path / "py")
    run_cli("study", "navigation", RIG, "--set", "trajectory.duration_s=360", "--trials", "2", "--p-max", "0.5",
            "-o", tmp_path / "cli", "--no-plots", "--quiet")
    for f in ("trials.csv", "summary.csv", "error_vs_time.csv", "tilt.csv", "dop.csv", "consistency.csv", "goal.csv"):
        assert (tmp_path / "py" / f).read_bytes() == (tmp_path / "cli" / f).read_bytes(), f
    goal = read_csv(tmp_path / "cli" / "goal.csv")
    assert [g["both_met"] for g in r["goal"]] == list(goal["both_met"])
    trials = read_csv(tmp_path / "cli" / "trials.csv")
    np.testing.assert_array_equal(r["trials"]["final_heading_error_deg"], trials["final_heading_error_deg"])
    np.testing.assert_array_equal(r["trials"]["final_error_m"], trials["final_error_m"])
    np.testing.assert_array_equal(r["trials"]["nees_position"], trials["nees_position"])
    consistency = read_csv(tmp_path / "cli" / "consistency.csv")
    assert r["consistency"][0]["nees_position"]["mean"] == consistency["mean"][0]
    assert len(r["cells"]) == 2
    with pytest.raises(ValueError):
        rig.study_navigation(trials=0)


def test_a_rig_loaded_for_a_dataset_navigates_a_125_hz_log_and_refuses_to_simulate(tmp_path):
    """The third review's §4 leftover: Rig.load(dataset=True) reads a rig as navigate --rig does."""
    run_cli("simulate", RIG, "--set", "trajectory.duration_s=10", "-o", tmp_path / "d", "--no-plots", "--quiet")
    log = tmp_path / "log"
    log.mkdir()
    rate = 125.057
    lines = ["t_s,dtheta_x_rad,dtheta_y_rad,dtheta_z_rad,dv_x_mps,dv_y_mps,dv_z_mps"]
    lines += [f"{k / rate!r},0,{5.6e-5 / rate!r},{4.7e-5 / rate!r},0,0,{9.8 / rate!r}" for k in range(1, 1251)]
    (log / "imu.csv").write_text("\n".join(lines) + "\n")
    with pytest.raises(polrig.RigError, match="divides imu.rate_hz"):
        polrig.Rig.load(tmp_path / "d" / "rig.yaml", set={"imu.rate_hz": rate})
    r = polrig.Rig.load(tmp_path / "d" / "rig.yaml", set={"imu.rate_hz": rate}, dataset=True)
    n = polrig.navigate(log, mode="sins", rig=r)
    assert len(n["sins"]["t_s"]) == 1250
    with pytest.raises(polrig.RigError, match=r"simulate_navigation simulates a run; the rig was read for a dataset"):
        r.simulate_navigation()
