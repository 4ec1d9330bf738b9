"""polrig.calibrate, CalibrationParams.apply and the readers: the CLI's calibrate and apply outputs,
bit for bit, on data from `polrig simulate`; errors with the CLI's messages."""
import pickle
from pathlib import Path

import numpy as np
import pytest

import polrig
from conftest import ROOT, read_csv, run_cli

INDOOR = str(ROOT / "rigs" / "wang2019-indoor.yaml")
OUTDOOR = str(ROOT / "rigs" / "wang2019-outdoor1.yaml")


@pytest.fixture(scope="module")
def indoor(tmp_path_factory):
    """A `polrig simulate` folder of the indoor rig."""
    out = tmp_path_factory.mktemp("indoor") / "sim"
    run_cli("simulate", INDOOR, "--no-plots", "-o", out)
    return out


@pytest.fixture(scope="module")
def outdoor(tmp_path_factory):
    """A `polrig simulate` folder of an outdoor (sky) rig: stops.csv has t_s."""
    out = tmp_path_factory.mktemp("outdoor") / "sim"
    run_cli("simulate", OUTDOOR, "--no-plots", "-o", out)
    return out


def cli_calibrate(data, out, *args):
    run_cli("calibrate", data, "--no-plots", "-o", out, *args)
    return out


def assert_same_as_cli(res, out):
    """The result against the files `polrig calibrate` wrote: params.yaml as text, the CSVs as
    exact doubles."""
    assert res.to_yaml() == (out / "params.yaml").read_text()
    pts = read_csv(out / "points.csv")
    np.testing.assert_array_equal(res.theta_ref_deg, pts["theta_ref_deg"])
    np.testing.assert_array_equal(res.V, np.column_stack([pts["V1"], pts["V2"], pts["V3"]]))
    np.testing.assert_array_equal(res.V_model,
                                  np.column_stack([pts["V1_model"], pts["V2_model"], pts["V3_model"]]))
    np.testing.assert_array_equal(res.fitted,
                                  np.column_stack([pts["V1_fitted"], pts["V2_fitted"], pts["V3_fitted"]]) == 1)
    err = read_csv(out / "errors.csv")
    assert set(res.errors) == set(err)
    for name, column in err.items():
        np.testing.assert_array_equal(res.errors[name], column, err_msg=name)
    acc = read_csv(out / "accuracy.csv")
    for k, name in enumerate(acc["angle"]):
        a = res.accuracy[name]
        assert (a.max_deg, a.min_deg, a.accuracy_deg) == (
            acc["max_deg"][k], acc["min_deg"][k], acc["accuracy_deg"][k]), name
    rep = read_csv(out / "replacement.csv")
    got = res.replacement()
    assert [r[0] for r in got] == list(rep["replaced"])
    np.testing.assert_array_equal([r[2] for r in got], rep["accuracy_deg"])
    curve = read_csv(out / "model_curve.csv")
    np.testing.assert_array_equal(res.model(curve["theta_deg"]),
                                  np.column_stack([curve["V1_model"], curve["V2_model"], curve["V3_model"]]))


@pytest.mark.parametrize("method", ["section", "cs", "cs-nc", "nc"])
def test_calibrate_is_the_cli_for_each_method(indoor, tmp_path, method):
    out = cli_calibrate(indoor, tmp_path / method, "--method", method)
    data = polrig.read_measured(str(indoor))
    res = polrig.calibrate(data.theta_R_deg, data.V, method=method, rig=data.rig)
    assert res.usable() and res.fit.usable() and res.fit.termination == "converged"
    assert res.method == method and res.d_a_source == "the rig's device.d"
    assert_same_as_cli(res, out)
    # params.yaml reads back to the same parameters.
    back = polrig.read_params(str(out / "params.yaml"))
    assert back.params == res.params and back.d_a == res.d_a
    assert back.volts_per_decade == res.volts_per_decade == 0.5


def test_d_a_given_is_the_cli_d_a(indoor, tmp_path):
    out = cli_calibrate(indoor, tmp_path / "d", "--method", "cs-nc", "--d-a", "0.55")
    data = polrig.read_measured(str(indoor))
    res = polrig.calibrate(data.theta_R_deg, data.V, d_a=0.55, rig=data.rig)
    assert res.d_a == 0.55 and res.d_a_source == "d_a"
    assert res.to_yaml() == (out / "params.yaml").read_text().replace("d_a_source: --d-a", "d_a_source: d_a")
    np.testing.assert_array_equal(res.errors["errsec_deg"], read_csv(out / "errors.csv")["errsec_deg"])


def test_outdoor_per_stop_drift_is_the_cli(outdoor, tmp_path):
    out = cli_calibrate(outdoor, tmp_path / "ps", "--method", "nc", "--drift", "per-stop")
    data = polrig.read_measured(str(outdoor))
    assert data.t_s is not None and data.t_s.shape == data.theta_R_deg.shape
    res = polrig.calibrate(data.theta_R_deg, data.V, method="nc", rig=data.rig, drift="per-stop",
                           t_s=data.t_s)
    assert res.drift.startswith("per-stop (stop times from the rig's sky.first_stop_utc + t_s")
    assert_same_as_cli(res, out)
    assert not np.all(res.d_ratio == 1)
    # Without the correction the result differs (the test can fail).
    plain = polrig.calibrate(data.theta_R_deg, data.V, method="nc", rig=data.rig)
    assert plain.drift == "" and not np.array_equal(plain.params.alpha_deg, res.params.alpha_deg)


def test_drift_from_utc_and_site_is_the_cli(tmp_path):
    # A CSV with a utc column and --site, as a researcher's outdoor run.
    sim = tmp_path / "sim"
    run_cli("simulate", INDOOR, "--no-plots", "-o", sim)
    stops = read_csv(sim / "stops.csv")
    n = len(stops["theta_R_deg"])
    utc = np.datetime64("2018-11-16T08:09:40") + np.arange(n) * np.timedelta64(3, "s")
    csv = tmp_path / "run.csv"
    with open(csv, "w") as f:
        f.write("theta_R_deg,V1,V2,V3,utc\n")
        for k in range(n):
            f.write(f"{stops['theta_R_deg'][k]!r},{stops['V1'][k]!r},{stops['V2'][k]!r},"
                    f"{stops['V3'][k]!r},{np.datetime_as_string(utc[k])}Z\n")
    out = cli_calibrate(csv, tmp_path / "cal", "--method", "nc", "--drift", "angle",
                        "--site", "38.879167,121.543889")
    data = polrig.read_measured(str(csv))
    np.testing.assert_array_equal(data.utc, utc.astype("datetime64[ns]"))
    res = polrig.calibrate(data.theta_R_deg, data.V, method="nc", drift="angle", utc=data.utc,
                           site=(38.879167, 121.543889))
    cli_yaml = (out / "params.yaml").read_text()
    assert res.to_yaml() == cli_yaml.replace("--site 38.879167,121.543889", "site 38.879167,121.543889")
    np.testing.assert_array_equal(res.theta_ref_deg, read_csv(out / "points.csv")["theta_ref_deg"])
    # ISO strings give the same.
    iso = [np.datetime_as_string(t) + "Z" for t in utc]
    again = polrig.calibrate(data.theta_R_deg, data.V, method="nc", drift="angle", utc=iso,
                             site=(38.879167, 121.543889))
    assert again.to_yaml() == res.to_yaml()


def test_apply_is_the_cli_apply(indoor, tmp_path):
    cal = cli_calibrate(indoor, tmp_path / "cal", "--method", "cs-nc")
    run_cli("apply", cal / "params.yaml", indoor / "stops.csv", "--no-plots", "-o", tmp_path / "ap")
    cli = read_csv(tmp_path / "ap" / "angles.csv")
    pf = polrig.read_params(str(cal / "params.yaml"))
    data = polrig.read_voltages(str(indoor / "stops.csv"))
    a = pf.angles(data.V, theta_R_deg=data.theta_R_deg)
    for name in ("theta_R_deg", "theta12_deg", "theta13_deg", "theta23_deg", "theta_sec_deg", "d",
                 "error_deg"):
        np.testing.assert_array_equal(getattr(a, name), cli[name], err_msg=name)
    np.testing.assert_array_equal(a.section, cli["section"])
    assert a.section.dtype == np.int64 and a.theta_sec_deg.dtype == np.float64
    theta, d = pf.params.apply(data.V, volts_per_decade=pf.volts_per_decade)
    np.testing.assert_array_equal(theta, cli["theta_sec_deg"])
    np.testing.assert_array_equal(d, cli["d"])
    # The form: the result's parameters applied to more voltages.
    res = polrig.calibrate(data.theta_R_deg, data.V, method="cs-nc", rig=polrig.Rig.load(INDOOR))
    theta2, d2 = res.params.apply(data.V)
    np.testing.assert_array_equal(theta2, theta)
    # Without reference angles error_deg is None.
    assert pf.angles(data.V).error_deg is None
    # The paper's arctan inversion agrees with atan2 to rounding on good data.
    t3, _ = pf.apply(data.V, inversion="arctan-sign")
    assert np.max(np.abs((t3 - theta + 90) % 180 - 90)) < 1e-9


def test_read_measured_shapes_and_rig(indoor):
    data = polrig.read_measured(str(indoor))
    stops = read_csv(indoor / "stops.csv")
    assert data.V.shape == (len(stops["theta_R_deg"]), 3) and data.V.dtype == np.float64
    np.testing.assert_array_equal(data.theta_R_deg, stops["theta_R_deg"])
    np.testing.assert_array_equal(data.V[:, 1], stops["V2"])
    assert data.utc is None and data.t_s is None
    assert isinstance(data.rig, polrig.Rig) and data.rig.to_yaml() == polrig.Rig.load(INDOOR).to_yaml()
    assert len(data) == len(stops["theta_R_deg"])


def test_params_fields_theory_table2_and_pickle():
    p = polrig.CalibrationParams()
    assert p == polrig.CalibrationParams.theory([0, 90, 60, 150, 120, 210])
    np.testing.assert_array_equal(p.alpha_deg, [0, 0, -120, -120, 120, 120])
    w = polrig.CalibrationParams.wang2019_indoor()
    assert w != p
    q = w.copy()
    q.kd = q.kd + 0.01
    assert q != w
    assert pickle.loads(pickle.dumps(w)) == w
    with pytest.raises(ValueError, match="kv: expected 3 values, got 2"):
        p.kv = [1, 1]
    with pytest.raises(ValueError, match=r"alpha_deg: element 2 is nan"):
        polrig.CalibrationParams(alpha_deg=[0, 0, np.nan, 0, 0, 0])
    assert p != "not params"


def test_fit_failure_is_data_not_an_exception():
    # Three stops: too few observations for six unknowns per pair.
    theta = np.array([0.0, 10.0, 20.0])
    V = np.array([[0.1, -0.1, 0.05], [0.12, -0.08, 0.02], [0.1, -0.05, 0.0]])
    res = polrig.calibrate(theta, V, method="section")
    assert not res.usable() and res.fit.termination == "too_few_observations"
    assert "not usable" in repr(res)
    assert res.errors["errsec_deg"].shape == (0,)
    assert res.fitted.shape == (3, 3) and not res.fitted.any()
    with pytest.raises(polrig.CalibrationError, match="method section: the fit is not usable: too_few_observations"):
        res.to_yaml()
    with pytest.raises(polrig.CalibrationError, match="not usable"):
        res.model([0.0])


def test_replacement_analysis_function_is_the_cli(indoor, tmp_path):
    out = cli_calibrate(indoor, tmp_path / "section", "--method", "section")
    data = polrig.read_measured(indoor)
    res = polrig.calibrate(data.theta_R_deg, data.V, method="section", rig=data.rig)
    theory = polrig.CalibrationParams.theory(data.rig["device.film_axes_deg"])
    got = polrig.replacement_analysis(res.params, theory, res.theta_ref_deg, res.V,
                                      volts_per_decade=data.rig["electronics.volts_per_decade"])
    rep = read_csv(out / "replacement.csv")
    assert [r[0] for r in got] == list(rep["replaced"]) and [r[1] for r in got] == list(range(16))
    np.testing.assert_array_equal([r[2] for r in got], rep["accuracy_deg"])
    # Independent ends: nothing replaced is the calibration's own θ_sec accuracy, from its errors;
    # everything replaced is the theory parameters applied to the same points.
    errsec = read_csv(out / "errors.csv")["errsec_deg"]
    assert got[0][2] == (errsec.max() - errsec.min()) / 2
    theta, _ = theory.apply(res.V)
    err = (theta - res.theta_ref_deg + 90) % 180 - 90
    assert got[15][0] == "α-k-kv-kd"
    assert got[15][2] == pytest.approx((err.max() - err.min()) / 2, rel=1e-12, abs=1e-12)
    assert got[15][2] > 10 * got[0][2]  # the theory values are far worse: the test can fail


def test_bad_arguments_name_themselves(indoor, tmp_path):
    theta = np.arange(0, 370, 10.0)
    V = np.zeros((len(theta), 3))
    with pytest.raises(ValueError, match=r"V: expected a 2-D array of shape \(N, 3\), got shape \(37,\)"):
        polrig.calibrate(theta, theta)
    bad = V.copy()
    bad[4, 1] = np.inf
    with pytest.raises(ValueError, match="V: element 13 is inf"):
        polrig.calibrate(theta, bad)
    with pytest.raises(ValueError, match="method='all': expected section, cs, cs-nc or nc"):
        polrig.calibrate(theta, V, method="all")
    # d_a outside (0, 1): the CLI's message.
    cli = run_cli("calibrate", indoor, "--d-a", "1.5", "-o", tmp_path / "x", check=False)
    assert cli.returncode != 0
    with pytest.raises(ValueError) as e:
        polrig.calibrate(theta, V, d_a=1.5)
    assert "expected a degree of polarization in (0, 1), got 1.5" in str(e.value)
    assert "expected a degree of polarization in (0, 1), got 1.5" in cli.stderr
    # The noncontinuous rule's ranges: calib/rig_options.h, as the CLI's --nc-* options.
    with pytest.raises(ValueError, match=r"nc_threshold=1.5: expected a finite number in \[0, 1\]"):
        polrig.calibrate(theta, V, nc_threshold=1.5)
    with pytest.raises(ValueError, match=r"nc_min_points=5: expected a whole number in \[6, 100000\]"):
        polrig.calibrate(theta, V, nc_min_points=5)
    assert run_cli("calibrate", indoor, "--nc-min-points", "5", "-o", tmp_path / "y", check=False).returncode != 0
    with pytest.raises(ValueError, match="V: 36 rows for 37 values of theta_R_deg"):
        polrig.calibrate(theta, V[1:])
    big = V.copy()
    big[3, 2] = 150
    with pytest.raises(polrig.DataError, match=r"V row 3: column 'V3': 150 V is outside any ADC's range"):
        polrig.calibrate(theta, big)
    with pytest.raises(ValueError, match="drift='per-stop' needs method 'nc' or 'section'"):
        polrig.calibrate(theta, V, drift="per-stop")
    with pytest.raises(polrig.DataError, match=r"drift='angle': needs the stops' times"):
        polrig.calibrate(theta, V, method="nc", drift="angle", site=(38.9, 121.5))
    with pytest.raises(polrig.DataError, match=r"drift='angle' needs site=\(lat, lon\)"):
        polrig.calibrate(theta, V, method="nc", drift="angle", utc=["2018-11-16T08:09:40Z"] * 37)
    with pytest.raises(ValueError, match=r"site: latitude 95 is outside \[-90, 90\] \(degrees, north positive\)"):
        polrig.calibrate(theta, V, method="nc", drift="angle", site=(95, 121.5))
    with pytest.raises(ValueError, match=r"site: longitude -181 is outside \[-180, 180\]"):
        polrig.calibrate(theta, V, method="nc", drift="angle", site=(38, -181))
    with pytest.raises(ValueError, match="drift='sideways': expected none, angle, per-stop or linear"):
        polrig.calibrate(theta, V, method="nc", drift="sideways")
    with pytest.raises(TypeError, match="rig: expected a polrig.Rig or None, got <class 'str'>"):
        polrig.calibrate(theta, V, rig=INDOOR)
    with pytest.raises(ValueError, match="method='cs-nc': the rig's light is the sky"):
        polrig.calibrate(theta, V, rig=polrig.Rig.load(OUTDOOR))
    # An unpaired CS stop: the library's CalibrationError.
    with pytest.raises(polrig.CalibrationError, match="stop 0"):
        polrig.calibrate(np.array([0.0, 10.0]), np.zeros((2, 3)) + 0.1, method="cs")


def test_apply_refuses_what_the_cli_refuses(tmp_path):
    p = polrig.CalibrationParams()
    with pytest.raises(polrig.DataError, match=r"V row 1: column 'V2': 200 V is outside any ADC's range"):
        p.apply([[0.1, 0.1, 0.1], [0.1, 200.0, 0.1]])
    with pytest.raises(ValueError, match="V: element 0 is nan"):
        p.apply([[np.nan, 0.1, 0.1]])
    with pytest.raises(ValueError, match="volts_per_decade: expected a positive finite number"):
        p.apply([[0.1, 0.1, 0.1]], volts_per_decade=0)
    with pytest.raises(ValueError, match="inversion='x'"):
        p.apply([[0.1, 0.1, 0.1]], inversion="x")
    flat = polrig.CalibrationParams(alpha_deg=np.zeros(6))
    with pytest.raises(polrig.DataError, match="V row 0: V1 = 0.1, V2 = 0.2, V3 = 0.1 give no finite angle"):
        flat.apply([[0.1, 0.2, 0.1]])
    # Voltages beyond 300 decades of light ratio: the CLI's message for the same row.
    params = tmp_path / "params.yaml"
    params.write_text("alpha_deg: [0, 0, -120, -120, 120, 120]\nk_mV: [0, 0, 0]\nkv: [0.5, 1, 1]\n"
                      "kd: [0, 0, 0, 0, 0, 0]\nd_a: 0.5\n")
    volts = tmp_path / "v.csv"
    volts.write_text("V1,V2,V3\n0.1,0.1,0.1\n80,0.1,0.1\n")
    cli = run_cli("apply", params, volts, "--no-plots", "-o", tmp_path / "out", check=False)
    assert cli.returncode == 2
    pf = polrig.read_params(str(params))
    with pytest.raises(polrig.DataError) as e:
        pf.apply([[0.1, 0.1, 0.1], [80, 0.1, 0.1]])
    why = str(e.value).removeprefix("V row 1: ")
    assert "decades of light ratio" in why and f"v.csv:3: {why}" in cli.stderr


def test_params_file_errors_name_file_and_line(tmp_path):
    f = tmp_path / "params.yaml"
    f.write_text("alpha_deg: [0, 0, -120, -120, 120, 120]\nk_mV: [0, 0, 0]\nkv: [1, 1, 1]\n"
                 "kd: [0, 0, 0, 0, 0, 0]\nd_a: 0.5\nbogus: 1\n")
    with pytest.raises(polrig.DataError, match=r"params.yaml:6: key 'bogus': unknown key"):
        polrig.read_params(str(f))
    with pytest.raises(polrig.DataError, match="no such file"):
        polrig.read_params(str(tmp_path / "none.yaml"))


def test_read_measured_errors_name_file_line_column(tmp_path):
    f = tmp_path / "m.csv"
    f.write_text("theta_R_deg,V1,V2,V3\n0,0.1,0.1,0.1\n10,0.1,x,0.1\n")
    with pytest.raises(polrig.DataError, match=r"m.csv:3: column 'V2': expected a finite number, got 'x'"):
        polrig.read_measured(str(f))


def test_fit_limits_reach_the_fit(indoor):
    data = polrig.read_measured(indoor)
    full = polrig.calibrate(data.theta_R_deg, data.V, method="section", rig=data.rig)
    one = polrig.calibrate(data.theta_R_deg, data.V, method="section", rig=data.rig, max_iterations=1)
    assert full.fit.iterations > 1 and one.fit.iterations <= 1
    assert one.fit.termination == "no_convergence" and not one.usable()


def test_paths_may_be_pathlib(indoor, tmp_path):
    cal = cli_calibrate(indoor, tmp_path / "cal", "--method", "cs-nc")
    data = polrig.read_measured(Path(indoor))
    assert len(data) == len(polrig.read_measured(str(indoor)))
    res = polrig.calibrate(data.theta_R_deg, data.V, rig=data.rig)
    res.save(tmp_path / "p.yaml")
    assert (tmp_path / "p.yaml").read_text() == (cal / "params.yaml").read_text()
    pf = polrig.read_params(tmp_path / "p.yaml")
    assert pf.params == res.params and pf.origin == str(tmp_path / "p.yaml")
    v = polrig.read_voltages(Path(indoor) / "stops.csv")
    np.testing.assert_array_equal(v.V, data.V)
    with pytest.raises(TypeError):
        polrig.read_params(3)


def test_array_arguments_convert_and_read_well(indoor):
    data = polrig.read_measured(indoor)
    params = polrig.CalibrationParams()
    theta, d = params.apply(data.V[:5])
    # A list and an int array convert as float64.
    t2, d2 = params.apply(data.V[:5].tolist())
    np.testing.assert_array_equal(t2, theta)
    ints = np.array([[0, 0, 0], [1, 0, -1]])
    np.testing.assert_array_equal(params.apply(ints)[0], params.apply(ints.astype(float))[0])
    with pytest.raises(ValueError, match=r"V: expected a 2-D array of shape \(N, 3\), got shape \(2, 2\)"):
        params.apply([[0.1, 0.1], [0.1, 0.1]])
    with pytest.raises(TypeError, match=r"V: expected an array of numbers, got <class 'str'>"):
        params.apply("volts")
    # A broadcast too big to copy is named as memory, with its size, not as a wrong type.
    huge = np.broadcast_to(np.float32(0.1), (10**12, 3))
    with pytest.raises(ValueError, match=r"V: 3000000000000 numbers do not fit in memory"):
        params.apply(huge)
    with pytest.raises(ValueError, match=r"theta_R_deg: expected a 1-D array, got shape \(\)"):
        polrig.calibrate(3.0, data.V)
    # help() names the kinds of the arguments, not pybind11's 'handle'.
    for f in (polrig.calibrate, polrig.CalibrationParams.apply, polrig.CalibrationParams.angles,
              polrig.ParamsFile.angles, polrig.CalibrationResult.model, polrig.replacement_analysis,
              polrig.CalibrationParams.theory, polrig.CalibrationParams.__init__, polrig.read_measured):
        assert "handle" not in f.__doc__, f.__doc__.splitlines()[0]
    assert "theta_R_deg: numpy.typing.ArrayLike, V: numpy.typing.ArrayLike" in polrig.calibrate.__doc__
    assert "path: os.PathLike" in polrig.read_measured.__doc__


def test_no_non_finite_result_leaves(indoor, tmp_path):
    data = polrig.read_measured(indoor)
    res = polrig.calibrate(data.theta_R_deg, data.V, rig=data.rig)
    # Eq. 15 is undefined where d_ratio·c reaches 1: the CLI's model_curve.csv refuses NaN.
    assert np.isfinite(res.model([0.0, 45.0], d_ratio=[1.0, 1.0])).all()
    with pytest.raises(RuntimeError, match=r"a result is not finite: model\[\d+, \d+\] is nan"):
        res.model([0.0, 45.0], d_ratio=[10.0, 10.0])
    # The readers refuse NaN and inf as the CLI does, with the CLI's message.
    for bad in ("nan", "inf"):
        f = tmp_path / f"{bad}.csv"
        f.write_text(f"theta_R_deg,V1,V2,V3\n0,0.1,0.1,0.1\n10,0.1,{bad},0.1\n")
        cli = run_cli("calibrate", f, "--no-plots", "-o", tmp_path / f"out-{bad}", check=False)
        assert cli.returncode != 0
        with pytest.raises(polrig.DataError) as e:
            polrig.read_measured(f)
        assert str(e.value) in cli.stderr and "column 'V2'" in str(e.value)
        with pytest.raises(polrig.DataError, match="column 'V2'"):
            polrig.read_voltages(f)
