"""Rig.simulate, study_cs, sweep, study_adc, study_calibration and light_at_pose: the CLI's CSV
columns as NumPy arrays, bit for bit, for any thread count."""
import csv
import tracemalloc

import numpy as np
import pytest

import polrig
from conftest import ROOT, read_csv, run_cli

INDOOR = str(ROOT / "rigs" / "wang2019-indoor.yaml")
OUTDOOR = str(ROOT / "rigs" / "wang2019-outdoor1.yaml")
SETS = {"eccentricity.L_S": 0.05, "eccentricity.alpha_IS": 30, "seed": 7}


def cli_sets(sets):
    return [a for k, v in sets.items() for a in ("--set", f"{k}={v}")]


def assert_equal(a, b):
    """Exactly equal, NaN where the other is NaN."""
    np.testing.assert_array_equal(np.asarray(a), np.asarray(b), strict=False)
    a, b = np.asarray(a, dtype=float), np.asarray(b, dtype=float)
    assert a.shape == b.shape and np.array_equal(a, b, equal_nan=True)


# ---- simulate

def check_simulation_is_stops_csv(sim, out):
    stops = read_csv(out / "stops.csv")
    n = len(stops["stop"])
    assert len(sim) == n
    assert_equal(sim.theta_R_deg, stops["theta_R_deg"])
    assert_equal(sim.theta_deg, stops["theta_deg"])
    assert_equal(sim.d, stops["d"])
    assert_equal(sim.E_Wm2, np.column_stack([stops[f"E{m}_Wm2"] for m in range(1, 7)]))
    for name, suffix in (("V_ideal", "_ideal"), ("V_ecc", "_ecc"), ("V_mean", ""), ("V_std", "_std")):
        assert_equal(getattr(sim, name), np.column_stack([stops[f"V{i}{suffix}"] for i in (1, 2, 3)]))
        assert getattr(sim, name).dtype == np.float64 and getattr(sim, name).shape == (n, 3)
    assert ("t_s" in stops) == sim.time_dependent
    if sim.time_dependent:
        assert_equal(sim.t_s, stops["t_s"])


@pytest.mark.parametrize("path,sets", [(INDOOR, SETS), (OUTDOOR, {})], ids=["indoor", "sky"])
def test_simulate_equals_the_cli_stops_and_samples(tmp_path, path, sets):
    rig = polrig.Rig.load(path, set=sets)
    sim = rig.simulate(samples=True, threads=2)
    run_cli("simulate", path, *cli_sets(sets), "--samples", "-o", tmp_path / "s", "--no-plots", "--quiet")
    check_simulation_is_stops_csv(sim, tmp_path / "s")
    samples = read_csv(tmp_path / "s" / "samples.csv")
    n, S = len(sim), sim.samples_per_stop
    assert sim.samples.shape == (n, S, 3)
    flat = sim.samples.reshape(-1, 3)
    for i in range(3):
        assert_equal(flat[:, i], samples[f"V{i + 1}"])
    assert_equal(np.repeat(sim.theta_R_deg, S), samples["theta_R_deg"])
    assert sim.time_dependent == (path == OUTDOOR)


def test_simulate_without_samples_and_any_thread_count():
    rig = polrig.Rig.load(INDOOR, set=SETS)
    one, two = rig.simulate(threads=1), rig.simulate(threads=2)
    assert one.samples is None
    for name in ("theta_R_deg", "t_s", "theta_deg", "d", "E_Wm2", "V_ideal", "V_ecc", "V_mean", "V_std"):
        assert np.array_equal(getattr(one, name), getattr(two, name)), name
    assert "stops" in repr(one)


# ---- study cs

def check_cs_is_the_cli(cs, out):
    dev = read_csv(out / "deviations.csv")
    summary = read_csv(out / "summary.csv")
    n = len(cs.theta_R_deg)
    assert cs.deviations_mV.shape == (n, 3, 2)
    for i in range(3):  # deviations.csv is pair-major
        rows = dev["pair"] == i + 1
        assert_equal(cs.theta_R_deg, dev["theta_R_deg"][rows])
        assert_equal(cs.deviations_mV[:, i, 0], dev["dv_br_mV"][rows])
        assert_equal(cs.deviations_mV[:, i, 1], dev["dv_mr_mV"][rows])
        if cs.standard_errors:
            assert_equal(cs.deviations_stderr_mV[:, i, 0], dev["dv_br_stderr_mV"][rows])
    for field in ("bsd_mV", "asd_mV", "mean_br_mV", "mean_mr_mV", "eq6_mV"):
        assert_equal(cs.summary[field], summary[field])
    assert cs.coaxial_reference == ("coaxial_bsd_mV" in summary)
    if cs.coaxial_reference:
        for field in ("bsd_mV", "asd_mV", "mean_br_mV"):
            assert_equal(cs.coaxial[field], summary["coaxial_" + field])
    else:
        assert cs.coaxial is None


@pytest.mark.parametrize("path,sets,steps", [(INDOOR, SETS, 360), (OUTDOOR, {}, 72)], ids=["indoor", "sky"])
def test_study_cs_equals_the_cli(tmp_path, path, sets, steps):
    cs = polrig.Rig.load(path, set=sets).study_cs(steps, threads=2)
    run_cli("study", "cs", path, *cli_sets(sets), "--steps", steps, "-o", tmp_path / "cs", "--no-plots", "--quiet")
    check_cs_is_the_cli(cs, tmp_path / "cs")
    assert cs.deviations is cs.deviations_mV
    assert "ASD" in repr(cs)


def test_study_cs_is_the_same_for_any_thread_count_and_checks_steps():
    rig = polrig.Rig.load(INDOOR, set=SETS)
    a, b = rig.study_cs(36, threads=1), rig.study_cs(36, threads=2)
    assert np.array_equal(a.deviations_mV, b.deviations_mV)
    for k in a.summary:
        assert np.array_equal(a.summary[k], b.summary[k])
    for bad in (0, 3, 3600002):
        with pytest.raises(ValueError, match=f"steps={bad}: expected an even number"):
            rig.study_cs(bad)
    with pytest.raises(ValueError, match="threads=0"):
        rig.study_cs(36, threads=0)


def test_a_long_sweep_reports_progress_and_releases_the_gil():
    """A sweep of about a second in a thread: its progress reaches the callable, and Python
    code runs in the main thread meanwhile (the GIL is released around the library call)."""
    import threading
    import time
    seen, result = [], {}
    # 288,000 points: about 2 s here, so that a machine twice as fast still takes over 0.6 s
    grid = {"eccentricity.L_S": "0.001:1:800", "eccentricity.alpha_S": "0:359:360"}
    worker = threading.Thread(target=lambda: result.setdefault(
        "r", polrig.Rig().sweep(grid, progress=lambda stage, f, eta: seen.append((stage, f)))))
    t0 = last = time.perf_counter()
    worker.start()
    longest_pause = 0.0
    while worker.is_alive():
        now = time.perf_counter()
        longest_pause, last = max(longest_pause, now - last), now
    elapsed = time.perf_counter() - t0
    assert result["r"].asd_mV.shape == (800, 360, 3)
    assert elapsed > 0.6, "the sweep was too quick to test this"
    # A held GIL would stop this loop for the whole sweep.
    assert longest_pause < 0.25 * elapsed, (longest_pause, elapsed)
    assert seen and all(stage == "sweep: grid points" for stage, _ in seen)
    assert seen[-1][1] == 1.0 and all(0 <= f <= 1 for _, f in seen)


# ---- sweep

def test_sweep_equals_the_cli_sweep_csv(tmp_path):
    rig = polrig.Rig.load(INDOOR, set=SETS)
    grid = {"eccentricity.L_IS": "0.001:1:4", "eccentricity.alpha_S": "0:350:3"}
    res = rig.sweep(grid, steps=36, threads=2)
    run_cli("sweep", INDOOR, *cli_sets(SETS), "--steps", 36, *[a for k, v in grid.items() for a in ("--grid", f"{k}={v}")],
            "-o", tmp_path / "sw", "--no-plots", "--quiet", "--csv")
    csv = read_csv(tmp_path / "sw" / "sweep.csv")
    assert res.shape == (4, 3) and len(res) == 12 and res.keys == list(grid)
    L, a = np.meshgrid(res.axes["eccentricity.L_IS"], res.axes["eccentricity.alpha_S"], indexing="ij")
    assert_equal(L.ravel(), csv["eccentricity.L_IS"])
    assert_equal(a.ravel(), csv["eccentricity.alpha_S"])
    for field in ("bsd_mV", "asd_mV", "asd_bsd_pct", "mean_br_mV", "mean_mr_mV", "eq6_mV", "eq6_dev_pct"):
        arr = getattr(res, field)
        assert arr.shape == (4, 3, 3) and arr.dtype == np.float64
        assert arr is res.fields[field]
        for i in range(3):
            assert_equal(arr.reshape(-1, 3)[:, i], csv[f"pair{i + 1}_{field}"])
    assert res.bsd_stderr_mV is None and not res.standard_errors

    # Explicit values equal the CLI's where they coincide (the CLI's values themselves here).
    listed = rig.sweep({k: res.axes[k] for k in grid}, steps=36, threads=1)
    for field in res.fields:
        assert np.array_equal(listed.fields[field], res.fields[field], equal_nan=True)


def test_sweep_of_explicit_arrays_is_each_points_cs_study():
    rig = polrig.Rig.load(INDOOR)
    res = rig.sweep({"eccentricity.alpha_S": np.arange(0, 360, 45), "eccentricity.L_S": [0.3, 0.01]}, steps=36)
    assert res.shape == (8, 2)
    one = polrig.Rig.load(INDOOR, set={"eccentricity.alpha_S": 135, "eccentricity.L_S": 0.01}).study_cs(36)
    assert np.array_equal(res.asd_mV[3, 1], one.summary["asd_mV"])
    assert np.array_equal(res.mean_mr_mV[3, 1], one.summary["mean_mr_mV"])


def test_sweep_errors_name_key_and_value():
    rig = polrig.Rig()
    with pytest.raises(polrig.RigError, match="unknown key 'eccentricity.nope'"):
        rig.sweep({"eccentricity.nope": [1.0]})
    with pytest.raises(polrig.RigError, match="'source.model' is not a single real number"):
        rig.sweep({"source.model": [1.0]})
    with pytest.raises(polrig.RigError, match=r"eccentricity.L_S: value 2: expected a length in \[0, 100\] mm, got 200"):
        rig.sweep({"eccentricity.L_S": [0.1, 0.2, 200]})
    with pytest.raises(polrig.RigError, match=r"eccentricity.L_IS: value 1: expected .* got nan"):
        rig.sweep({"eccentricity.L_IS": [0.1, np.nan]})
    # The string form is the CLI's --grid, with its message.
    cli = run_cli("sweep", INDOOR, "--grid", "eccentricity.L_S=0:200:3", "-o", "/nonexistent/x", check=False)
    with pytest.raises(polrig.RigError) as e:
        rig.sweep({"eccentricity.L_S": "0:200:3"})
    assert str(e.value) in cli.stderr and "got 200" in str(e.value)
    with pytest.raises(TypeError, match="grid"):
        rig.sweep([("eccentricity.L_S", [0.1])])
    with pytest.raises(ValueError, match="2-D"):
        rig.sweep({"eccentricity.L_S": [[0.1]]})
    # A key the CS study does not read: the CLI's note as a warning, and equal rows.
    with pytest.warns(UserWarning, match="does not depend on 'schedule.start_deg'"):
        res = rig.sweep({"schedule.start_deg": [0.0, 10.0]}, steps=8)
    assert np.array_equal(res.asd_mV[0], res.asd_mV[1])


def test_sweep_is_the_same_for_any_thread_count():
    rig = polrig.Rig()
    grid = {"eccentricity.L_S": np.linspace(1e-3, 1, 50), "eccentricity.alpha_S": np.arange(0, 360, 30)}
    a, b = rig.sweep(grid, steps=8, threads=1), rig.sweep(grid, steps=8, threads=2)
    for field in a.fields:
        assert np.array_equal(a.fields[field], b.fields[field], equal_nan=True)


def test_large_sweep_makes_no_python_object_per_point():
    points = 100_000
    tracemalloc.start()
    res = polrig.Rig().sweep({"eccentricity.L_S": np.linspace(1e-3, 1, 1000), "eccentricity.alpha_S": np.arange(100.0)},
                             steps=2)
    _, peak = tracemalloc.get_traced_memory()
    tracemalloc.stop()
    assert len(res) == points and res.asd_mV.shape == (1000, 100, 3)
    # The result arrays themselves (7 fields × 3 pairs × 8 bytes per point, ~17 MB) and nothing
    # per point beyond them: a Python float alone is 24 bytes.
    arrays = sum(a.nbytes for a in res.fields.values())
    assert peak < arrays + 24 * points, (peak, arrays)


# ---- study adc, study calibration, light at a pose

def test_study_adc_equals_the_cli(tmp_path):
    rig = polrig.Rig.load(INDOOR)
    res = rig.study_adc(d="0.1:0.9:5", step=0.5)
    run_cli("study", "adc", INDOOR, "--d", "0.1:0.9:5", "--step", 0.5, "-o", tmp_path / "a", "--no-plots", "--quiet")
    csv = read_csv(tmp_path / "a" / "accuracy_limit.csv")
    for k in ("d", "vmax_mV", "limit_deg"):
        assert_equal(res[k], csv[k])
    again = rig.study_adc(d=np.array([0.3, 0.7]), step=0.5)
    assert_equal(again["limit_deg"], res["limit_deg"][[1, 3]])
    with pytest.raises(ValueError, match=r"d: element 1 is 1;"):
        rig.study_adc(d=[0.5, 1.0])
    # Text is the CLI's --d, with its messages.
    assert_equal(rig.study_adc(d="0.3,0.7", step=0.5)["limit_deg"], again["limit_deg"])
    with pytest.raises(polrig.RigError, match="^--d 0.1:0.5: expected a,b,c or start:stop:count$"):
        rig.study_adc(d="0.1:0.5")
    with pytest.raises(polrig.RigError, match=r"^--d 0.1,1: expected degrees of polarization in \(0, 1\), got 1$"):
        rig.study_adc(d="0.1,1")
    with pytest.raises(polrig.RigError, match="device.d"):
        rig.study_adc(d="0.5:1.5:3")
    with pytest.raises(ValueError, match="step=0"):
        rig.study_adc(step=0)


def test_study_calibration_equals_the_cli(tmp_path):
    rig = polrig.Rig.load(INDOOR)
    res = rig.study_calibration(trials=6, threads=2)
    run_cli("study", "calibration", INDOOR, "--trials", 6, "-o", tmp_path / "t", "--no-plots", "--quiet")
    csv = read_csv(tmp_path / "t" / "trials.csv")
    assert_equal(res.trial, csv["trial"])
    assert res.seed.dtype == np.uint64
    rows = (tmp_path / "t" / "trials.csv").read_text().splitlines()[1:]
    assert res.seed.tolist() == [int(r.split(",")[1]) for r in rows]
    for k in ("L_IS", "alpha_IS", "L_S", "alpha_S"):
        assert_equal(getattr(res, k), csv[k])
    for j, c in enumerate(("acc_section_deg", "acc_cs_deg", "acc_cs_nc_deg")):
        assert_equal(res.accuracy_deg[:, j], csv[c])
    summary = read_csv(tmp_path / "t" / "summary.csv")
    for row, method in enumerate(summary["method"]):
        for k in ("succeeded", "failed", "median_deg", "p05_deg", "p95_deg", "mean_deg"):
            assert res.summary[method][k] == summary[k][row]
    assert res.methods == ["section", "cs", "cs-nc"]
    one = rig.study_calibration(trials=6, threads=1)
    assert np.array_equal(one.accuracy_deg, res.accuracy_deg, equal_nan=True)


def test_study_calibration_failures_and_terminations_equal_the_cli(tmp_path):
    """Offsets up to 100 mm: some fits end without converging (failures.csv)."""
    rig = polrig.Rig.load(INDOOR)
    res = rig.study_calibration(trials=6, L_IS_max=100, L_S_max=100)
    run_cli("study", "calibration", INDOOR, "--trials", 6, "--L-IS-max", 100, "--L-S-max", 100,
            "-o", tmp_path / "t", "--no-plots", "--quiet")
    with open(tmp_path / "t" / "failures.csv", newline="") as f:
        failures = list(csv.DictReader(f))
    assert failures and len(res.failures) == len(failures)
    for got, row in zip(res.failures, failures):
        assert got["reason"].replace('"', "'") == row["reason"]
        assert (got["method"], got["termination"]) == (row["method"], row["termination"])
        for k in ("trial", "iterations", "evaluations"):
            assert got[k] == int(row[k])
    with open(tmp_path / "t" / "summary.csv", newline="") as f:
        summary = list(csv.DictReader(f))
    assert [r["method"] for r in summary] == list(res.summary)
    for row in summary:
        got = res.summary[row["method"]]
        assert (got["succeeded"], got["failed"]) == (int(row["succeeded"]), int(row["failed"]))
        for k in ("median_deg", "p05_deg", "p95_deg", "mean_deg"):
            assert got[k] == float(row[k])
        ends = got["terminations"]
        assert list(ends) == list(row)[7:] and sum(ends.values()) == 6
        assert all(ends[name] == int(row[name]) for name in ends)
    assert sum(s["failed"] for s in res.summary.values()) == len(failures)
    # Changing what a read returns leaves the result as it was.
    res.failures.clear()
    res.summary["cs"]["failed"] = -1
    assert len(res.failures) == len(failures) and res.summary["cs"]["failed"] >= 0
    with pytest.raises(polrig.RigError, match="trials=0: expected a whole number in"):
        rig.study_calibration(trials=0)
    with pytest.raises(polrig.RigError, match=r"L_S_max=101: expected a number in \[0, 100\] mm"):
        rig.study_calibration(L_S_max=101)
    with pytest.raises(ValueError, match=r"nc_min_points=5: expected a whole number in \[6, 100000\]"):
        rig.study_calibration(nc_min_points=5)


def test_result_arrays_are_read_only():
    rig = polrig.Rig.load(INDOOR, set=SETS)
    cs = rig.study_cs(36)
    sim = rig.simulate(samples=True)
    sw = rig.sweep({"eccentricity.L_IS": "0:1:3"}, steps=36)
    trials = rig.study_calibration(trials=2)
    arrays = [cs.theta_R_deg, cs.deviations_mV, cs.deviations, *cs.summary.values(),
              sim.theta_R_deg, sim.V_mean, sim.E_Wm2, sim.samples, sw.asd_mV, *sw.fields.values(),
              *sw.axes.values(), trials.accuracy_deg, trials.L_IS, trials.seed, trials.trial]
    for a in arrays:
        with pytest.raises(ValueError, match="read-only"):
            a[...] = 0
    for mapping in (cs.summary, sw.fields, sw.axes):  # read-only views of the result's dicts
        with pytest.raises(TypeError):
            mapping["asd_mV"] = None
    assert cs.summary is cs.summary and cs.summary["asd_mV"] is cs.summary["asd_mV"]


def test_a_sweep_too_large_for_memory_is_refused_before_allocating():
    grid = {"eccentricity.L_IS": "0:1:1000", "eccentricity.alpha_S": "0:359:1000",
            "eccentricity.L_S": "0:1:1000"}  # 1e9 points: check_grid's limit, 156 GiB of results
    tracemalloc.start()
    with pytest.raises(polrig.RigError, match=r"grid: 1000000000 points need 156\.5 GiB .* more than half"):
        polrig.Rig().sweep(grid)
    peak = tracemalloc.get_traced_memory()[1]
    tracemalloc.stop()
    assert peak < 1 << 20


def test_progress_true_writes_the_clis_line_on_stderr(capfd):
    """About 2 s on one thread on an AVX-512 machine (~12 s on the AVX2 ones): well over the first report's 0.5 s."""
    polrig.Rig().sweep({"eccentricity.L_IS": "0:1:800000"}, threads=1, progress=True)
    err = capfd.readouterr().err
    assert "polrig: sweep: grid points" in err and "100 %" in err, err


def test_light_at_pose_is_a_simulated_stop():
    rig = polrig.Rig.load(OUTDOOR)
    sim = rig.simulate()
    k = 5
    one = rig.light_at_pose(sim.theta_R_deg[k], sim.t_s[k])
    assert_equal(one["E_Wm2"], sim.E_Wm2[k])
    assert one["theta_deg"] == sim.theta_deg[k] and one["d"] == sim.d[k]
    indoor = polrig.Rig.load(INDOOR, set=SETS)
    s = indoor.simulate()
    many = indoor.light_at_pose(s.theta_R_deg)
    assert_equal(many["E_Wm2"], s.E_Wm2)
    assert_equal(many["theta_deg"], s.theta_deg)
    with pytest.raises(ValueError, match="theta_R_deg: element 1 is nan"):
        indoor.light_at_pose([0.0, np.nan])


# ---- a traced sphere (small): standard errors and the coaxial reference

@pytest.fixture(scope="module")
def traced_rig(tmp_path_factory):
    """rigs/wang2019-indoor-traced.yaml with a scene traced with few photons (quick)."""
    d = tmp_path_factory.mktemp("traced")
    scene = (ROOT / "scenes" / "jf500.yaml").read_text()
    for a, b in (("photons: 2000000", "photons: 20000"), ("batches: 16", "batches: 4"),
                 ("wall_bins_theta: 90", "wall_bins_theta: 18"), ("wall_bins_phi: 180", "wall_bins_phi: 36"),
                 ("plane_samples: 4096", "plane_samples: 256")):
        assert a in scene
        scene = scene.replace(a, b)
    (d / "scene.yaml").write_text(scene)
    rig = (ROOT / "rigs" / "wang2019-indoor-traced.yaml").read_text()
    (d / "rig.yaml").write_text(rig.replace("scene: ../scenes/jf500.yaml", "scene: scene.yaml"))
    return str(d / "rig.yaml")


def test_traced_study_cs_has_standard_errors_and_the_coaxial_summary(tmp_path, traced_rig):
    cs = polrig.Rig.load(traced_rig).study_cs(8, threads=2)
    run_cli("study", "cs", traced_rig, "--steps", 8, "-o", tmp_path / "cs", "--no-plots", "--quiet")
    assert cs.standard_errors and cs.coaxial_reference and not cs.eq6
    check_cs_is_the_cli(cs, tmp_path / "cs")
    dev, summary = read_csv(tmp_path / "cs" / "deviations.csv"), read_csv(tmp_path / "cs" / "summary.csv")
    for i in range(3):
        assert_equal(cs.deviations_stderr_mV[:, i, 1], dev["dv_mr_stderr_mV"][dev["pair"] == i + 1])
    for f in ("bsd", "asd", "mean_br", "mean_mr"):
        assert_equal(cs.summary[f + "_stderr_mV"], summary[f + "_stderr_mV"])
    assert np.isnan(cs.summary["eq6_mV"]).all()


def test_traced_sweep_and_simulate_equal_the_cli(tmp_path, traced_rig):
    rig = polrig.Rig.load(traced_rig)
    res = rig.sweep({"eccentricity.L_IS": "0:0.2:3"}, steps=8, threads=1)
    run_cli("sweep", traced_rig, "--grid", "eccentricity.L_IS=0:0.2:3", "--steps", 8, "-o", tmp_path / "sw",
            "--no-plots", "--quiet", "--csv")
    csv = read_csv(tmp_path / "sw" / "sweep.csv")
    assert res.standard_errors and res.asd_stderr_mV.shape == (3, 3)
    for field in ("bsd_mV", "asd_mV", "asd_bsd_pct", "mean_br_mV", "mean_mr_mV", "eq6_mV", "eq6_dev_pct"):
        for i in range(3):
            assert_equal(getattr(res, field)[:, i], csv[f"pair{i + 1}_{field}"])
    # The standard errors (not in sweep.csv) are each point's CS study's.
    at = polrig.Rig.load(traced_rig, set={"eccentricity.L_IS": 0.1}).study_cs(8)
    assert np.array_equal(res.asd_stderr_mV[1], at.summary["asd_stderr_mV"])
    sim = rig.simulate(threads=2)
    run_cli("simulate", traced_rig, "-o", tmp_path / "s", "--no-plots", "--quiet")
    check_simulation_is_stops_csv(sim, tmp_path / "s")
    assert np.array_equal(sim.V_mean, rig.simulate(threads=1).V_mean)


def test_simulate_writes_the_clis_dataset(tmp_path):
    rig = polrig.Rig.load(INDOOR, set=SETS)
    sim = rig.simulate(samples=True, out=tmp_path / "py")
    run_cli("simulate", INDOOR, *[a for k, v in SETS.items() for a in ("--set", f"{k}={v}")],
            "--samples", "--no-plots", "-o", tmp_path / "cli")
    for name in ("stops.csv", "samples.csv", "rig.yaml"):
        assert (tmp_path / "py" / name).read_bytes() == (tmp_path / "cli" / name).read_bytes(), name
    py_manifest = (tmp_path / "py" / "manifest.yaml").read_text().splitlines()
    cli_manifest = (tmp_path / "cli" / "manifest.yaml").read_text().splitlines()
    # the command differs, and the git revision may (the module and the CLI are built separately)
    differ = [(a, b) for a, b in zip(py_manifest, cli_manifest)
              if a != b and not a.startswith("git_revision:")]
    assert len(py_manifest) == len(cli_manifest) and len(differ) == 1 and "command" in differ[0][0], differ
    assert_equal(read_csv(tmp_path / "py" / "stops.csv")["V1"], sim.V_mean[:, 0])
    # the dataset calibrates like the CLI's
    run_cli("calibrate", tmp_path / "py", "--method", "cs-nc", "--no-plots", "-o", tmp_path / "cal")


def test_simulate_never_replaces_a_folder_without_force(tmp_path):
    (tmp_path / "d").mkdir()
    (tmp_path / "d" / "mine.txt").write_text("keep")
    with pytest.raises(RuntimeError, match="exists"):
        polrig.Rig().simulate(out=tmp_path / "d")
    assert [p.name for p in (tmp_path / "d").iterdir()] == ["mine.txt"]
    polrig.Rig().simulate(out=tmp_path / "d", force=True)
    assert (tmp_path / "d" / "stops.csv").is_file() and not (tmp_path / "d" / "mine.txt").exists()
    assert [p.name for p in tmp_path.iterdir()] == ["d"]  # no staging folder left behind


def test_trace_writes_what_polrig_trace_writes(tmp_path):
    # 16000 photons (1000 per batch): about 10 s each way
    scene = ROOT / "scenes" / "jf500.yaml"
    names = polrig.trace(scene, tmp_path / "py", photons=16000)
    run_cli("trace", scene, "--photons", 16000, "--no-plots", "-o", tmp_path / "cli")
    written = sorted(p.name for p in (tmp_path / "py").iterdir())
    assert written == sorted(p.name for p in (tmp_path / "cli").iterdir())
    assert set(names) <= set(written) and "wall_radiance.csv" in names
    for name in written:
        if name != "manifest.yaml":
            assert (tmp_path / "py" / name).read_bytes() == (tmp_path / "cli" / name).read_bytes(), name
    with pytest.raises(polrig.RigError, match=r"photons=1500: expected at least 100 per batch \(1600 for 16 batches\)"):
        polrig.trace(scene, tmp_path / "x", photons=1500)
    assert not (tmp_path / "x").exists()
