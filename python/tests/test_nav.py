"""polrig.heading, solve_heading, sky_view_body and study_heading: `polrig heading`'s and
`polrig study heading`'s CSVs bit for bit, the forward model inverted, senses, errors, threads."""
import numpy as np
import pytest

import polrig
from conftest import ROOT, read_csv, run_cli

INDOOR = str(ROOT / "rigs" / "wang2019-indoor.yaml")
OUTDOOR = str(ROOT / "rigs" / "wang2019-outdoor1.yaml")
SITE = (38.879167, 121.543889)


def heading_rows(n=200):
    rng = np.random.default_rng(11)
    t = np.datetime64("2019-07-01T00:00:00") + (rng.uniform(0, 86400, n) * 1000).astype("timedelta64[ms]")
    iso = [str(x) + "Z" for x in t]
    roll = np.round(rng.normal(0, 8, n), 3)
    pitch = np.round(rng.normal(0, 8, n), 3)
    aop = np.round(rng.uniform(-360, 360, n), 4)
    prior = np.round(rng.uniform(0, 360, n), 2)
    prior[::3] = np.nan  # empty cells: the root with the sun in front
    return iso, roll, pitch, aop, prior


def test_heading_is_the_cli_csv(tmp_path):
    iso, roll, pitch, aop, prior = heading_rows()
    with open(tmp_path / "in.csv", "w") as f:
        f.write("utc,roll_deg,pitch_deg,aop_deg,heading_prior_deg\n")
        for row in zip(iso, roll, pitch, aop, prior):
            f.write(",".join("" if isinstance(v, float) and np.isnan(v) else str(v) for v in row) + "\n")
    run_cli("heading", tmp_path / "in.csv", "--site", "38.879167,121.543889", "--ut1-minus-utc", 0.3,
            "-o", tmp_path / "h", "--no-plots")
    csv = read_csv(tmp_path / "h" / "heading.csv")
    got = polrig.heading(iso, SITE[0], SITE[1], roll, pitch, aop, prior_deg=prior, ut1_minus_utc_s=0.3)
    for k in ["sun_az_deg", "sun_el_deg", "heading_deg", "heading_alt_deg"]:
        assert np.array_equal(getattr(got, k), csv[k], equal_nan=True), k
    assert list(got.status) == list(csv["status"])
    assert [polrig.HEADING_STATUS[c] for c in got.status_code] == list(csv["status"])
    assert got.status_code.dtype == np.int8
    # the rows exercise both outcomes: headings, and rows without one (the sun near the zenith or
    # no root; NaN heading, as the CLI's nan)
    ok = got.status_code <= 1
    assert 0 < np.sum(ok) < len(iso)
    assert np.array_equal(got.from_prior[ok], ~np.isnan(prior[ok]))
    assert np.all(np.isnan(got.heading_deg[~ok])) and np.all(np.isfinite(got.heading_deg[ok]))
    one = polrig.heading(iso, SITE[0], SITE[1], roll, pitch, aop, prior_deg=prior,
                         ut1_minus_utc_s=0.3, threads=1)
    two = polrig.heading(iso, SITE[0], SITE[1], roll, pitch, aop, prior_deg=prior,
                         ut1_minus_utc_s=0.3, threads=2)
    for k in one.keys():
        a, b = getattr(one, k), getattr(two, k)
        assert np.array_equal(a, b, equal_nan=a.dtype.kind == "f"), k
    with pytest.raises(ValueError, match="read-only"):
        got.heading_deg[0] = 1.0


def test_heading_inverts_the_forward_model():
    # Independent of the solver: θ_b from sky_view_body (the sky's E-vector seen by the body)
    # gives back the true heading, for every attitude.
    rng = np.random.default_rng(5)
    n = 50
    utc = "2019-07-01T11:01:00Z"  # W19's dynamic run, h_s = 2.9°
    H = rng.uniform(0, 360, n)
    roll, pitch = rng.normal(0, 10, n), rng.normal(0, 10, n)
    s = polrig.Sky(site=SITE, utc=utc).sun().enu
    view = polrig.sky_view_body(s, H, roll, pitch)
    assert view.aop_body_deg.shape == (n,)
    got = polrig.heading(utc, *SITE, roll, pitch, view.aop_body_deg, prior_deg=(H + 2.0) % 360)
    assert np.all(got.status == "ok")
    assert np.allclose((got.heading_deg - H + 180) % 360 - 180, 0, atol=1e-8)
    one = polrig.solve_heading(s, float(view.aop_body_deg[0]), roll[0], pitch[0], (H[0] + 2.0) % 360)
    assert one.status == "ok" and one.status_code == 0 and one.from_prior and one.heading_deg == got.heading_deg[0]
    assert abs(one.a * np.cos(np.radians(one.heading_deg)) + one.b * np.sin(np.radians(one.heading_deg)) - one.c) < 1e-9


def test_turning_anticlockwise_lowers_the_heading():
    # spec §0: rotate the device by +10° anticlockwise seen from above: the fixed E-vector's θ_b
    # (from X_b, anticlockwise) falls by 10°, and the heading (clockwise from north) must fall by
    # 10°.
    s = polrig.Sky(site=SITE, utc="2019-07-01T11:01:00Z").sun().enu
    v = polrig.sky_view_body(s, 100.0)
    a = polrig.solve_heading(s, float(v.aop_body_deg), prior_deg=100.0)
    assert abs(float(polrig.sky_view_body(s, 90.0).aop_body_deg) - (float(v.aop_body_deg) - 10)) < 1e-9
    b = polrig.solve_heading(s, float(v.aop_body_deg) - 10.0, prior_deg=90.0)
    assert abs(a.heading_deg - 100.0) < 1e-9 and abs(b.heading_deg - 90.0) < 1e-9


def test_heading_broadcasts_and_refuses_bad_input():
    got = polrig.heading("2019-07-01T11:01:00Z", *SITE, np.zeros((2, 1)), 0.0, np.arange(3.0))
    assert got.heading_deg.shape == (2, 3) and got.status.shape == (2, 3)
    # prior_deg broadcasts too, NaN meaning none: the same as each row alone
    priors = np.array([[np.nan], [150.0]])
    both = polrig.heading("2019-07-01T11:01:00Z", *SITE, 0.0, 0.0, np.arange(3.0), prior_deg=priors)
    assert both.from_prior.tolist() == [[False] * 3, [True] * 3]
    for i in range(2):
        row = polrig.heading("2019-07-01T11:01:00Z", *SITE, 0.0, 0.0, np.arange(3.0), prior_deg=priors[i, 0])
        assert np.array_equal(both.heading_deg[i], row.heading_deg)
    with pytest.raises(ValueError, match=r"prior_deg: element 1 is inf"):
        polrig.heading("2019-07-01T11:01:00Z", *SITE, 0, 0, [0, 0], prior_deg=[0, np.inf])
    with pytest.raises(ValueError, match=r"do not broadcast.*prior_deg"):
        polrig.heading("2019-07-01T11:01:00Z", *SITE, 0, 0, [0, 0], prior_deg=[0, 1, 2])
    # 2-D times: the same as the flat list, reshaped
    times = [["2019-07-01T11:01:00Z", "2019-07-01T11:02:00Z"], ["2019-07-01T11:03:00Z", "2019-07-01T11:04:00Z"]]
    grid = polrig.heading(times, *SITE, 0.0, 0.0, 10.0)
    flat = polrig.heading(sum(times, []), *SITE, 0.0, 0.0, 10.0)
    assert grid.heading_deg.shape == (2, 2)
    assert np.array_equal(grid.heading_deg.ravel(), flat.heading_deg)
    assert np.array_equal(polrig.heading(np.array(times), *SITE, 0.0, 0.0, 10.0).heading_deg, grid.heading_deg)
    with pytest.raises(ValueError, match=r"utc \(element 3\)"):
        polrig.heading([times[0], ["2019-07-01T11:03:00Z", "noon"]], *SITE, 0, 0, 0)
    with pytest.raises(ValueError, match=r"pitch_deg: element 0 is 95, outside \[-90, 90\]"):
        polrig.heading("2019-07-01T11:01:00Z", *SITE, 0, 95, 0)
    with pytest.raises(ValueError, match=r"roll_deg: element 1 is nan"):
        polrig.heading("2019-07-01T11:01:00Z", *SITE, [0, np.nan], 0, 0)
    with pytest.raises(ValueError, match=r"prior_deg: element 0 is 400"):
        polrig.heading("2019-07-01T11:01:00Z", *SITE, 0, 0, 0, prior_deg=400)
    with pytest.raises(ValueError, match=r"utc \(element 1\)"):
        polrig.heading(["2019-07-01T11:01:00Z", "2019-07-01 11:01"], *SITE, 0, 0, 0)
    with pytest.raises(ValueError, match=r"lon_deg: element 0 is 200"):
        polrig.heading("2019-07-01T11:01:00Z", 38, 200, 0, 0, 0)


def trials_equal_csv(t, path):
    csv = read_csv(path)
    # the seeds are uint64: read as integers, not through float64
    with open(path) as f:
        header = f.readline().strip().split(",")
        seeds = [int(line.split(",")[header.index("seed")]) for line in f]
    for k in csv:
        if k == "status":
            assert list(t.status) == list(csv[k])
        elif k == "seed":
            assert t.seed.tolist() == seeds, k
        else:
            assert np.array_equal(getattr(t, k), csv[k], equal_nan=True), k


def test_study_heading_is_the_cli_trials_csv(tmp_path):
    run_cli("study", "heading", INDOOR, "--trials", 120, "--no-plots", "--roll-sd", 12,
            "--sync-max", 0.2, "--refraction", "-o", tmp_path / "a")
    csv = read_csv(tmp_path / "a" / "trials.csv")
    reports = []
    t1 = polrig.Rig.load(INDOOR).study_heading(trials=120, roll_sd_deg=12, sync_max_s=0.2,
                                               refraction=True, threads=1,
                                               progress=lambda *r: reports.append(r))
    t2 = polrig.Rig.load(INDOOR).study_heading(trials=120, roll_sd_deg=12, sync_max_s=0.2,
                                               refraction=True, threads=2)
    trials_equal_csv(t1, tmp_path / "a" / "trials.csv")
    # a stage shorter than the progress interval reports nothing (polrig/progress.h); any report
    # is (stage, fraction, eta_s)
    assert all(isinstance(st, str) and 0 <= f <= 1 for st, f, _ in reports)
    with pytest.raises(TypeError, match="progress: expected None, a bool or a callable"):
        polrig.Rig.load(INDOOR).study_heading(trials=5, progress=42)
    summary = read_csv(tmp_path / "a" / "summary.csv")
    for k in summary:
        got = getattr(t1.summary, k)
        if got.dtype == object:
            assert list(got) == list(summary[k]), k
        else:
            assert np.array_equal(got, summary[k], equal_nan=True), k
    cdf = read_csv(tmp_path / "a" / "cdf.csv")
    for k in cdf:
        assert np.array_equal(getattr(t1.cdf, k), cdf[k], equal_nan=True), k
    # an independent look: the "all" row's RMS is the RMS of trials.csv's error_deg
    assert np.isclose(t1.summary.rms_deg[0], np.sqrt(np.nanmean(csv["error_deg"] ** 2)), rtol=1e-12)
    for k in t1.keys():
        a, b = getattr(t1, k), getattr(t2, k)
        if k in ("summary", "cdf"):
            for j in a.keys():
                x, y = getattr(a, j), getattr(b, j)
                assert np.array_equal(x, y, equal_nan=x.dtype.kind == "f"), (k, j)
        else:
            assert np.array_equal(a, b, equal_nan=a.dtype.kind == "f"), k
    assert t1.seed.dtype == np.uint64 and t1.trial.dtype == np.int64


def test_study_heading_near_the_zenith_summarises_only_solved_trials(tmp_path):
    # The sun 1° from the zenith: some trials have no heading (NaN errors, shorter CDF columns).
    args = dict(trials=300, site=(23.4, 116.0), utc="2019-06-21T04:13:00Z", roll_sd_deg=1, pitch_sd_deg=1)
    run_cli("study", "heading", INDOOR, "--trials", 300, "--no-plots", "--site", "23.4,116.0", "--utc",
            "2019-06-21T04:13:00Z", "--roll-sd", 1, "--pitch-sd", 1, "-o", tmp_path / "z")
    t = polrig.Rig.load(INDOOR).study_heading(**args)
    trials_equal_csv(t, tmp_path / "z" / "trials.csv")
    assert 0 < np.sum(t.status_code != 0) < 300 and np.all(np.isnan(t.error_deg[t.status_code >= 2]))
    summary = read_csv(tmp_path / "z" / "summary.csv")
    for k in ["bin_lo", "bin_hi", "trials", "solved", "mean_deg", "rms_deg", "p50_abs_deg", "max_abs_deg"]:
        assert np.array_equal(getattr(t.summary, k), summary[k], equal_nan=True), k
    cdf = read_csv(tmp_path / "z" / "cdf.csv")
    assert all(np.array_equal(getattr(t.cdf, k), cdf[k], equal_nan=True) for k in cdf)
    assert t.summary.solved[0] == np.sum(t.status_code <= 1)


def test_study_heading_takes_a_sky_rigs_run(tmp_path):
    run_cli("study", "heading", OUTDOOR, "--trials", 20, "--no-plots", "--utc", "2018-11-16T08:11:28Z",
            "-o", tmp_path / "g")
    trials_equal_csv(polrig.Rig.load(OUTDOOR).study_heading(trials=20, utc="2018-11-16T08:11:28Z"),
                     tmp_path / "g" / "trials.csv")
    run_cli("study", "heading", OUTDOOR, "--trials", 20, "--no-plots", "-o", tmp_path / "f")
    trials_equal_csv(polrig.Rig.load(OUTDOOR).study_heading(trials=20), tmp_path / "f" / "trials.csv")


def test_study_heading_errors():
    rig = polrig.Rig()
    with pytest.raises(ValueError, match="p_max_min 0.9 is above p_max_max 0.7"):
        rig.study_heading(trials=5, p_max_min=0.9)
    with pytest.raises(ValueError, match=r"roll_sd_deg: expected a finite number in \[0, 30\] °, got 31"):
        rig.study_heading(trials=5, roll_sd_deg=31)
    with pytest.raises(ValueError, match=r"trials: expected a whole number in \[1, 10000000\], got 0"):
        rig.study_heading(trials=0)
    with pytest.raises(ValueError, match=r"site: height 200000 m is outside \[-1e5, 1e5\]"):
        rig.study_heading(trials=5, site=(38.9, 121.5, 2e5))
    assert not hasattr(polrig, "study_heading")


def test_solve_heading_and_sky_view_body_refuse_a_non_unit_sun():
    with pytest.raises(ValueError, match=r"sun_enu \(2, 0, 0\) has length 2: expected the unit vector"):
        polrig.solve_heading([2.0, 0.0, 0.0], 30.0)
    with pytest.raises(ValueError, match=r"sun_enu \(0, 0, 0\) has length 0"):
        polrig.solve_heading([0.0, 0.0, 0.0], 30.0)
    with pytest.raises(ValueError, match=r"sun_enu \(0, 0, 1.5\) has length 1.5"):
        polrig.sky_view_body([[0.0, 0.6, 0.8], [0.0, 0.0, 1.5]], 10.0)
    with pytest.raises(ValueError, match="sun_enu: expected"):
        polrig.solve_heading([1.0, 0.0], 30.0)
    with pytest.raises(TypeError):
        polrig.sky_view_body([0.0, 0.6, 0.8], 10.0, radiance="rayleigh")
    # within 1e-9 of unit length is accepted
    assert polrig.solve_heading([0.6, 0.8, 1e-10], 30.0).status == "ok"


def test_study_heading_reports_progress_to_a_callable():
    # a stage reports after the progress interval (0.5 s) and at its end: (stage, fraction, eta_s)
    reports = []
    # 1e6 trials: about 2 s of trials on this 2-core machine, well over the 0.5 s interval
    polrig.Rig().study_heading(trials=1000000, threads=2, progress=lambda *r: reports.append(r))
    assert len(reports) >= 2
    assert all(stage == "study heading: trials" for stage, _, _ in reports)
    fractions = [f for _, f, _ in reports]
    assert fractions == sorted(fractions) and 0 < fractions[0] < 1 and fractions[-1] == 1
    assert reports[-1][2] == 0
