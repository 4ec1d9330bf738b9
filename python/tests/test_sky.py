"""polrig.Sky, sun_position, sky_table, drift_corrections, spectral_kd and read_exr: the CLI's
files (sky.exr, sun.yaml, sky.csv, kd.csv, spectra.csv) bit for bit, shapes, errors, threads."""
import datetime

import numpy as np
import pytest

import polrig
from conftest import ROOT, read_csv, run_cli

OUTDOOR = str(ROOT / "rigs" / "wang2019-outdoor1.yaml")
SITE = (38.879167, 121.543889)
UTC = "2018-11-16T08:09:40Z"


def read_sun_yaml(path):
    """The numbers of a sun.yaml (shortest round-trip text, so float() is exact)."""
    out = {}
    for line in open(path):
        if line.startswith("#") or ":" not in line:
            continue
        key, _, value = line.strip().partition(":")
        try:
            out[key] = float(value)
        except ValueError:
            out[key] = value.strip()
    return out


def test_sky_map_is_the_cli_exr_and_sun_yaml(tmp_path):
    run_cli("sky", "-o", tmp_path / "s", "--size", 96, "--no-plots", "--utc", "2019-07-01T11:01:00Z",
            "--site", "38.9,121.5", "--p-max", 0.6, "--radiance", "cie-clear", "--refraction",
            "--ut1-minus-utc", 0.25, "--exr-compression", "none")
    sky = polrig.Sky(site=(38.9, 121.5), utc="2019-07-01T11:01:00Z", p_max=0.6, radiance="cie-clear",
                     refraction=True, ut1_minus_utc_s=0.25)
    m = sky.map(96)
    exr = polrig.read_exr(str(tmp_path / "s" / "sky.exr"))
    for layer, name in [("S0", "S0"), ("S1", "S1"), ("S2", "S2"), ("AoP", "aop_deg"), ("DoP", "dop"),
                        ("A", "inside")]:
        got = getattr(m, name)
        assert got.dtype == np.float32 and got.shape == (96, 96)
        assert np.array_equal(exr[layer], got), layer
    sun = read_sun_yaml(tmp_path / "s" / "sun.yaml")
    s = sky.sun()
    for k in ["azimuth_deg", "elevation_deg", "zenith_deg", "declination_deg", "gha_deg", "lha_deg"]:
        assert getattr(s, k) == sun[k] and getattr(m.sun, k) == sun[k], k
    assert m.utc == sky.utc == "2019-07-01T11:01:00Z"


def test_sky_from_rig_is_polrig_sky_rig(tmp_path):
    run_cli("sky", OUTDOOR, "-o", tmp_path / "s", "--size", 32, "--no-plots")
    sky = polrig.Sky.from_rig(polrig.Rig.load(OUTDOOR))
    assert np.array_equal(polrig.read_exr(str(tmp_path / "s" / "sky.exr"))["AoP"], sky.map(32).aop_deg)
    with pytest.raises(polrig.RigError, match="has no sky"):
        polrig.Sky.from_rig(polrig.Rig())


def test_read_exr_checks_the_size_from_the_header(tmp_path):
    """Issue 23 §5.1: width= and height= are checked against the header before any pixel is read;
    a file OpenEXR cannot read is a polrig.DataError (a ValueError) naming it."""
    run_cli("sky", OUTDOOR, "-o", tmp_path / "s", "--size", 32, "--no-plots")
    exr = str(tmp_path / "s" / "sky.exr")
    assert polrig.read_exr(exr, width=32, height=32)["AoP"].shape == (32, 32)
    with pytest.raises(polrig.DataError, match=r"sky\.exr: 32 × 32 px \(expected 32 × 31\)"):
        polrig.read_exr(exr, width=32, height=31)
    with pytest.raises(ValueError, match="give width and height, or neither"):
        polrig.read_exr(exr, width=32)
    with pytest.raises(ValueError, match="cannot read the EXR image"):
        polrig.read_exr(str(tmp_path / "missing.exr"))


def test_map_threads_do_not_change_it():
    sky = polrig.Sky()
    a, b = sky.map(64, threads=1), sky.map(64, threads=2)
    assert all(np.array_equal(getattr(a, k), getattr(b, k)) for k in ["S0", "S1", "S2", "aop_deg", "dop"])


def write_table_input(path, rows):
    with open(path, "w") as f:
        f.write("utc,lat_deg,lon_deg,view_az_deg,view_el_deg,note\n")
        for r in rows:
            f.write(",".join(map(str, r)) + ",x\n")


def table_rows(n=300):
    rng = np.random.default_rng(3)
    t0 = np.datetime64("2018-11-16T08:00:00")
    times = t0 + (rng.uniform(0, 6 * 3600, n) * 1000).astype("timedelta64[ms]")
    iso = [str(t) + "Z" for t in times]
    lat = np.round(rng.uniform(-60, 60, n), 4)
    lon = np.round(rng.uniform(-180, 180, n), 4)
    az = np.round(rng.uniform(-360, 360, n), 3)
    el = np.round(rng.uniform(-10, 90, n), 3)
    el[:3] = 90  # the zenith: the frame's limit along view_az_deg
    lat[100:] = 38.879167  # one site with many rows: the SunTrack path
    lon[100:] = 121.543889
    return iso, lat, lon, az, el


def test_sky_table_is_the_cli_csv(tmp_path):
    iso, lat, lon, az, el = table_rows()
    write_table_input(tmp_path / "in.csv", zip(iso, lat, lon, az, el))
    run_cli("sky", "table", tmp_path / "in.csv", "-o", tmp_path / "t", "--p-max", 0.65, "--refraction")
    csv = read_csv(tmp_path / "t" / "sky.csv")
    got = polrig.sky_table(iso, lat, lon, az, el, p_max=0.65, refraction=True)
    for k in ["sun_az_deg", "sun_el_deg", "dop", "aop_deg"]:
        assert np.array_equal(getattr(got, k), csv[k]), k
    # datetime64 and aware datetime input give the instants of the ISO text, fractions included
    t64 = np.array([s[:-1] for s in iso], dtype="datetime64[ns]")
    aware = [datetime.datetime.fromisoformat(s[:-1]).replace(tzinfo=datetime.timezone.utc) for s in iso]
    a = polrig.sky_table(iso, lat, lon, az, el, p_max=0.65, refraction=True, threads=1)
    for times in (t64, aware):
        b = polrig.sky_table(times, lat, lon, az, el, p_max=0.65, refraction=True, threads=2)
        assert np.array_equal(a.aop_deg, b.aop_deg) and np.array_equal(a.sun_az_deg, b.sun_az_deg)
    # sun_position over the same rows is the table's sun
    sun = polrig.sun_position(iso, np.stack([lat, lon], axis=-1), refraction=True, threads=2)
    assert np.array_equal(sun.azimuth_deg, csv["sun_az_deg"])
    assert np.array_equal(sun.elevation_deg, csv["sun_el_deg"])


def test_sky_light_and_stokes_are_sky_table_at_one_time(tmp_path):
    az = np.linspace(-350, 350, 15)
    el = np.linspace(-5, 90, 15)
    write_table_input(tmp_path / "in.csv", [(UTC, *SITE, a, e) for a, e in zip(az, el)])
    run_cli("sky", "table", tmp_path / "in.csv", "-o", tmp_path / "t")
    csv = read_csv(tmp_path / "t" / "sky.csv")
    sky = polrig.Sky(site=SITE, utc=UTC)
    light = sky.light(az, el)
    assert np.array_equal(light.dop, csv["dop"]) and np.array_equal(light.aop_deg, csv["aop_deg"])
    assert sky.sun().azimuth_deg == csv["sun_az_deg"][0]
    st = sky.stokes(az, el)
    assert st.shape == (15, 4) and st.dtype == np.float64
    # sky/rayleigh.h: S1 = L·P·cos 2χ, S2 = L·P·sin 2χ, S3 = 0 in the meridian frame
    chi = np.radians(light.aop_deg)
    assert np.allclose(st[:, 1], light.radiance * light.dop * np.cos(2 * chi), atol=1e-15)
    assert np.allclose(st[:, 2], light.radiance * light.dop * np.sin(2 * chi), atol=1e-15)
    assert np.all(st[:, 3] == 0) and np.array_equal(st[:, 0], light.radiance)


def test_vector_rt_sky_is_sky_table_with_the_rigs_sky_block(tmp_path):
    az = np.linspace(-350, 350, 12)
    el = np.linspace(-5, 90, 12)
    write_table_input(tmp_path / "in.csv", [(UTC, *SITE, a, e) for a, e in zip(az, el)])
    run_cli("sky", "table", tmp_path / "in.csv", "-o", tmp_path / "t", "--set", "source.model=sky",
            "--set", "sky.model=vector-rt", "--set", "sky.rt.tau_rayleigh=0.25", "--set", "sky.rt.ground_albedo=0.1")
    csv = read_csv(tmp_path / "t" / "sky.csv")
    sky = polrig.Sky(site=SITE, utc=UTC, model="vector-rt", tau_rayleigh=0.25, ground_albedo=0.1)
    assert sky.model == "vector-rt" and sky.tau_rayleigh == 0.25
    light = sky.light(az, el)
    assert np.array_equal(light.dop, csv["dop"]) and np.array_equal(light.aop_deg, csv["aop_deg"])
    iqu = sky.radiance_sr(az, el)
    assert iqu.shape == (12, 3)
    for k, name in enumerate(["I_sr", "Q_sr", "U_sr"]):
        assert np.array_equal(iqu[:, k], csv[name])
    # χ = ½·atan2(U, Q), P = √(Q² + U²)/I (sky table's columns, formats.md §6.12)
    assert np.allclose(np.hypot(iqu[:, 1], iqu[:, 2]) / iqu[:, 0], light.dop, rtol=1e-14)
    assert polrig.Sky(model="vector-rt", tau_rayleigh="bodhaine", wavelength_nm=450).tau_rayleigh == \
        pytest.approx(0.2203, abs=5e-4)
    with pytest.raises(ValueError, match="tau_rayleigh"):
        polrig.Sky(model="vector-rt", tau_rayleigh=-1)
    with pytest.raises(ValueError, match="single-scattering sky has no absolute radiance"):
        polrig.Sky().radiance_sr(0, 90)


def test_aerosol_sky_is_sky_table_with_the_rigs_aerosol(tmp_path):
    phase = ROOT / "data" / "aerosol-phase-matrix" / "iprt-a4-spheroids-350nm.txt"
    az = np.linspace(0, 330, 12)
    el = np.linspace(5, 90, 12)
    write_table_input(tmp_path / "in.csv", [(UTC, *SITE, a, e) for a, e in zip(az, el)])
    run_cli("sky", "table", tmp_path / "in.csv", "-o", tmp_path / "t", "--set", "source.model=sky",
            "--set", "sky.model=vector-rt", "--set", "sky.rt.aerosol.tau=0.2", "--set", "sky.rt.aerosol.ssa=0.787581",
            "--set", f"sky.rt.aerosol.phase_matrix={phase}")
    csv = read_csv(tmp_path / "t" / "sky.csv")
    sky = polrig.Sky(site=SITE, utc=UTC, model="vector-rt", aerosol_tau=0.2, aerosol_ssa=0.787581,
                     aerosol_phase_matrix=phase)
    assert sky.aerosol_tau == 0.2
    iqu = sky.radiance_sr(az, el)
    for k, name in enumerate(["I_sr", "Q_sr", "U_sr"]):
        assert np.array_equal(iqu[:, k], csv[name])
    with pytest.raises(ValueError, match="aerosol_phase_matrix"):
        polrig.Sky(model="vector-rt", aerosol_tau=0.2)
    with pytest.raises(ValueError, match="streams: .* too few"):
        polrig.Sky(model="vector-rt", aerosol_tau=0.2, streams=16, aerosol_phase_matrix=phase)


def test_neutral_points_are_the_cli_csv(tmp_path):
    run_cli("sky", "neutral-points", "--set", "source.model=sky", "--set", "sky.model=vector-rt",
            "--set", "sky.rt.tau_rayleigh=0.25", "--sun-el-deg", "5:45:3", "--no-plots", "-o", tmp_path / "np")
    csv = read_csv(tmp_path / "np" / "neutral_points.csv")
    p = polrig.Sky(model="vector-rt", tau_rayleigh=0.25).neutral_points([5, 25, 45])
    for name in ["sun_el_deg", "babinet_deg", "brewster_deg", "arago_deg"]:
        assert np.array_equal(getattr(p, name), csv[name], equal_nan=True)
    assert np.isnan(p.brewster_deg[0]) and np.isnan(p.arago_deg[2])
    assert np.all(np.isnan(polrig.Sky().neutral_points(30).babinet_deg))
    with pytest.raises(ValueError, match="sun_el_deg"):
        polrig.Sky(model="vector-rt").neutral_points(1)


def test_berry_fit_and_neutral_points_are_the_cli_csv(tmp_path):
    run_cli("sky", "berry-fit", "--set", "source.model=sky", "--set", "sky.model=vector-rt",
            "--set", "sky.rt.tau_rayleigh=0.25", "--sun-el-deg", "10:50:3", "--no-plots", "-o", tmp_path / "bf")
    csv = read_csv(tmp_path / "bf" / "berry_fit.csv")
    f = polrig.Sky(model="vector-rt", tau_rayleigh=0.25).berry_fit([10, 30, 50])
    for name in ["sun_el_deg", "babinet_deg", "brewster_deg", "aop_rms_deg", "single_aop_rms_deg"]:
        assert np.array_equal(getattr(f, name), csv[name])
    assert all(s.endswith("TooSmall") for s in f.status)
    # Berry's sky with one fitted distance: its neutral points are its distances (CLI and Python).
    run_cli("sky", "neutral-points", "--set", "source.model=sky", "--set", "sky.model=berry",
            "--set", "sky.berry.brewster_deg=17.5", "--sun-el-deg", "10:50:3", "--no-plots", "-o", tmp_path / "np")
    np_csv = read_csv(tmp_path / "np" / "neutral_points.csv")
    b = polrig.Sky(model="berry", brewster_deg=17.5)
    p = b.neutral_points([10, 30, 50])
    for name in ["babinet_deg", "brewster_deg", "arago_deg"]:
        assert np.array_equal(getattr(p, name), np_csv[name], equal_nan=True)
    assert np.isnan(p.brewster_deg[0]) and p.arago_deg[0] == 17.5 and p.brewster_deg[1] == 17.5
    assert b.model == "berry"
    with pytest.raises(ValueError, match="berry"):
        polrig.Sky(model="berry", babinet_deg=95.0)
    with pytest.raises(ValueError, match="no atmosphere"):
        polrig.Sky().berry_fit(30)


def test_broadcasting_shapes():
    sky = polrig.Sky()
    az = np.arange(0, 360, 30.0)[None, :]
    el = np.array([10.0, 45.0, 80.0])[:, None]
    light = sky.light(az, el)
    assert light.dop.shape == (3, 12) and light.e_vector.shape == (3, 12, 3)
    assert sky.stokes(az, el).shape == (3, 12, 4)
    assert sky.stokes(0, 45).shape == (4,)
    # e is perpendicular to the sun and to the view (single scattering), unit length
    s = sky.sun().enu
    assert np.allclose(light.e_vector @ s, 0, atol=1e-12)
    assert np.allclose(np.linalg.norm(light.e_vector, axis=-1), 1)
    with pytest.raises(ValueError, match="do not broadcast"):
        sky.light([1.0, 2.0], [1.0, 2.0, 3.0])


def near(got, text):
    """A spec number given to its last digit: within half a unit of that digit plus 0.001° (spec
    sky-and-compasses.md §1.1: the independent formulas agree to under 0.001°)."""
    decimals = len(text.partition(".")[2])
    return abs(got - float(text)) <= 0.5 * 10.0 ** -decimals + 0.001


def test_sun_position_matches_the_spec_numbers():
    # spec sky-and-compasses.md §1.1 "Checks" (Beijing time = UTC + 8 h), geometric sun.
    beijing = (39.979, 116.339)
    s = polrig.sun_position(["2019-09-18T08:14:00Z", "2019-09-18T08:34:00Z"], beijing)
    assert near(s.elevation_deg[0], "22.94") and near(s.azimuth_deg[0], "252.1")
    assert near(s.declination_deg[0], "1.93") and near(s.lha_deg[0], "61.27")
    assert near(s.elevation_deg[1], "19.26")
    changsha = (28.221, 112.992)
    c = polrig.sun_position(["2015-12-16T05:37:00Z", "2015-12-16T06:37:00Z", "2015-12-16T08:40:00Z"], changsha)
    assert near(c.azimuth_deg[0], "200.87") and near(c.azimuth_deg[1], "215.42")
    assert near(c.zenith_deg[1], "60.75") and near(c.zenith_deg[2], "80.45")
    dalian = (38 + 52 / 60 + 45 / 3600, 121 + 32 / 60 + 38 / 3600)
    d = polrig.sun_position(["2018-11-16T08:09:40Z", "2018-11-16T08:10:34Z", "2018-11-16T08:11:28Z"], dalian)
    assert abs(d.azimuth_deg[1] - d.azimuth_deg[0] - 0.1474) <= 0.00005 + 0.00001  # measured 0.147419
    assert near(d.elevation_deg[0], "4.42") and near(d.elevation_deg[2], "4.11")
    w19 = polrig.Sky(site=dalian, utc="2019-07-01T11:01:00Z").sun()
    assert near(w19.elevation_deg, "2.9") and near(w19.azimuth_deg, "297.6")


def test_sun_position_shapes_and_sites():
    times = np.datetime64("2018-11-16T00:00") + np.arange(0, 86400, 3600).astype("timedelta64[s]")
    s = polrig.sun_position(times, SITE)
    assert s.azimuth_deg.shape == (24,) and s.enu.shape == (24, 3)
    one = polrig.sun_position(UTC, SITE)
    assert one.azimuth_deg.shape == ()
    assert float(one.azimuth_deg) == polrig.Sky(site=SITE, utc=UTC).sun().azimuth_deg
    aware = datetime.datetime(2018, 11, 16, 8, 9, 40, tzinfo=datetime.timezone.utc)
    assert polrig.Sky(utc=aware).sun().azimuth_deg == polrig.Sky(utc=UTC).sun().azimuth_deg
    # many sites at one time, with heights: each as the sky at that site (the height moves the
    # topocentric sun, so a dropped height would show)
    sites = np.array([[0.0, 0.0, 0.0], [45.0, 90.0, 3000.0], [-30.0, -60.0, 90000.0]])
    many = polrig.sun_position(UTC, sites)
    assert many.elevation_deg.shape == (3,)
    for k in range(3):
        assert many.elevation_deg[k] == polrig.Sky(site=tuple(sites[k]), utc=UTC).sun().elevation_deg
    assert many.elevation_deg[2] != polrig.sun_position(UTC, sites[2, :2]).elevation_deg
    # 2-D times (a list of lists and a str array), element for element the flat ones
    grid = [["2018-11-16T08:00:00Z", "2018-11-16T09:00:00Z"], ["2018-11-16T10:00:00Z", "2018-11-16T11:00:00Z"]]
    g = polrig.sun_position(grid, SITE)
    assert g.azimuth_deg.shape == (2, 2)
    assert np.array_equal(g.azimuth_deg.ravel(), polrig.sun_position(sum(grid, []), SITE).azimuth_deg)
    assert np.array_equal(polrig.sun_position(np.array(grid), SITE).azimuth_deg, g.azimuth_deg)
    with pytest.raises(ValueError, match=r"site\[\.\.\., 2\] \(height_m\): element 1: height 200000 m"):
        polrig.sun_position(UTC, [[0.0, 0.0, 0.0], [1.0, 1.0, 2e5]])
    with pytest.raises(ValueError, match=r"site\[\.\.\., 0\] \(lat_deg\): element 0: latitude 91"):
        polrig.sun_position(UTC, [91.0, 0.0])
    with pytest.raises(ValueError, match=r"site: height -200000 m is outside \[-1e5, 1e5\]"):
        polrig.Sky(site=(38.9, 121.5, -2e5))


def test_errors_name_the_argument():
    with pytest.raises(ValueError, match=r"p_max: expected a finite number in \[1e-06, 1\], got 2"):
        polrig.Sky(p_max=2)
    with pytest.raises(ValueError, match=r"site: latitude 95 is outside \[-90, 90\]"):
        polrig.Sky(site=(95, 0))
    with pytest.raises(ValueError, match=r"ut1_minus_utc_s: expected a finite number in \[-1, 1\] s"):
        polrig.Sky(ut1_minus_utc_s=1.5)
    with pytest.raises(ValueError, match="radiance 'foggy'"):
        polrig.Sky(radiance="foggy")
    with pytest.raises(ValueError, match="utc: .*Z"):
        polrig.Sky(utc="2018-11-16T08:09:40")
    with pytest.raises(ValueError, match=r"view_el_deg: element 1 is 91"):
        polrig.Sky().light([0, 0], [10, 91])
    with pytest.raises(ValueError, match=r"view_az_deg: element 0 is nan"):
        polrig.Sky().stokes([np.nan], [10])
    with pytest.raises(ValueError, match=r"utc \(element 1\): invalid UTC time .*2150"):
        polrig.sun_position(["2018-01-01T00:00:00Z", "2150-01-01T00:00:00Z"], SITE)
    with pytest.raises(ValueError, match="P_max"):
        polrig.Sky(p_max_table=[[10, 0.5], [5, 0.6]])


def test_p_max_table_is_used():
    table = np.array([[-10.0, 0.5], [80.0, 0.8]])
    sky = polrig.Sky(p_max_table=table)
    assert np.array_equal(sky.p_max_table, table)
    h = sky.sun().elevation_deg
    p = np.interp(h, table[:, 0], table[:, 1])
    # at 90° from the sun the degree is P_max: sin²γ/(1 + cos²γ) = 1
    s = sky.sun().enu
    v = np.cross(s, [0.0, 0.0, 1.0])
    v /= np.linalg.norm(v)
    az, el = np.degrees(np.arctan2(v[0], v[1])), np.degrees(np.arcsin(v[2]))
    assert abs(sky.light(az, el).dop - p) < 1e-12


def test_drift_corrections_follow_the_sun():
    t = np.datetime64("2018-11-16T08:09:40") + np.arange(0, 600, 60).astype("timedelta64[s]")
    d = polrig.drift_corrections(t, SITE, "per-stop", p_max=0.7)
    sun = polrig.sun_position(t, SITE)
    # sky/drift.h: −ΔA_s, the sun of each stop computed exactly (as few rows of one site are)
    single = np.array([polrig.Sky(site=SITE, utc=x).sun().azimuth_deg for x in t])
    assert np.array_equal(d.dtheta_deg, -(single - single[0]))
    # d(t_k)/d(t_0) from the zenith's DoP, spec §1.2 with γ = θ_s: P_max·sin²θ_s/(1 + cos²θ_s)
    suns = [polrig.Sky(site=SITE, utc=x).sun() for x in t]
    c = np.cos(np.deg2rad([x.zenith_deg for x in suns]))
    dop = 0.7 * (1.0 - c * c) / (1.0 + c * c)
    for k in range(10):
        assert d.d_ratio[k] == dop[k] / dop[0], k
    # the same DoP as the sky model's own at the zenith (another route: vectors, not θ_s)
    zenith = np.array([polrig.Sky(site=SITE, utc=x, p_max=0.7).light(0.0, 90.0).dop for x in t])
    assert np.allclose(dop, zenith, rtol=1e-12, atol=0)
    assert d.d_ratio.shape == (10,) and sun.azimuth_deg.shape == (10,)
    none = polrig.drift_corrections(t, SITE, "none")
    assert np.array_equal(none.dtheta_deg, np.zeros(10)) and np.array_equal(none.d_ratio, np.ones(10))
    angle = polrig.drift_corrections(t, SITE, "angle")
    assert np.array_equal(angle.dtheta_deg, d.dtheta_deg) and np.array_equal(angle.d_ratio, np.ones(10))
    lin = polrig.drift_corrections(t, SITE, "linear")
    assert np.allclose(lin.dtheta_deg, np.linspace(lin.dtheta_deg[0], lin.dtheta_deg[-1], 10), atol=1e-12)
    # spec §1.1: ΔA_s = 0.1474° over 16:09:40–16:10:34 Beijing time (measured 0.147419)
    dalian = (38 + 52 / 60 + 45 / 3600, 121 + 32 / 60 + 38 / 3600)
    w19 = polrig.drift_corrections(["2018-11-16T08:09:40Z", "2018-11-16T08:10:34Z"], dalian, "angle")
    assert abs(-w19.dtheta_deg[1] - 0.1474) <= 0.00006
    with pytest.raises(ValueError, match="mode 'sideways'"):
        polrig.drift_corrections(t, SITE, "sideways")
    with pytest.raises(ValueError, match=r"site: latitude 95"):
        polrig.drift_corrections(t, (95.0, 0.0), "angle")
    with pytest.raises(ValueError, match=r"utc \(element 1\)"):
        polrig.drift_corrections(["2018-11-16T08:09:40Z", "later"], SITE, "angle")
    with pytest.raises(ValueError, match=r"p_max: expected a finite number"):
        polrig.drift_corrections(t, SITE, "per-stop", p_max=0)


def test_light_and_stokes_take_threads():
    sky = polrig.Sky()
    az, el = np.meshgrid(np.arange(0, 360, 7.0), np.arange(0, 90, 3.0))
    a, b = sky.light(az, el, threads=1), sky.light(az, el, threads=2)
    for k in a.keys():
        assert np.array_equal(getattr(a, k), getattr(b, k), equal_nan=True), k
    assert np.array_equal(sky.stokes(az, el, threads=1), sky.stokes(az, el, threads=2))
    with pytest.raises(ValueError, match="threads=0"):
        sky.light(0, 10, threads=0)


SPECTRA = ROOT / "data" / "spectra"


@pytest.mark.parametrize("sun", [None, "astm-g173.csv"])
def test_spectral_kd_is_the_cli(tmp_path, sun):
    films, resp = SPECTRA / "sheet-polarizer-synthetic.csv", SPECTRA / "blue-filter-photodiode-synthetic.csv"
    scale = [1, 0.95, 0.9, 1, 0.8, 0.99]
    args = ["spectral", "kd", "--films", films, "--response", resp, "--tau-m-scale",
            ",".join(map(str, scale)), "--lamp-temperature", 3000, "--no-plots", "-o", tmp_path / "k"]
    kw = {}
    if sun:
        args += ["--sun", SPECTRA / sun]
        kw["sun"] = str(SPECTRA / sun)
    run_cli(*args)
    got = polrig.spectral_kd(str(films), str(resp), lamp_temperature_K=3000, tau_m_scale=scale, **kw)
    kd = read_csv(tmp_path / "k" / "kd.csv")
    for k in kd:
        assert np.array_equal(getattr(got, k), kd[k]), k
    spectra = read_csv(tmp_path / "k" / "spectra.csv")
    for k in spectra:
        assert np.array_equal(getattr(got.spectra, k), spectra[k], equal_nan=True), k


def test_spectral_kd_errors():
    films, resp = SPECTRA / "sheet-polarizer-synthetic.csv", SPECTRA / "blue-filter-photodiode-synthetic.csv"
    with pytest.raises(ValueError, match="tau_m_scale: 2 values; expected 6"):
        polrig.spectral_kd(str(films), str(resp), tau_m_scale=[1, 2])
    with pytest.raises(ValueError, match=r"lamp_temperature_K: expected a finite number in \[500, 50000\] K"):
        polrig.spectral_kd(str(films), str(resp), lamp_temperature_K=100)
    with pytest.raises(polrig.DataError, match="nope.csv"):
        polrig.spectral_kd(str(SPECTRA / "nope.csv"), str(resp))


def test_spectral_kd_coverage_is_the_clis_message(tmp_path):
    # a response wider than the films (320-800 nm) and than a sun file: the CLI's message, its
    # option names replaced by the argument names
    films = SPECTRA / "sheet-polarizer-synthetic.csv"
    wide = tmp_path / "wide.csv"
    wide.write_text("wavelength_nm,response\n300,1\n900,1\n")
    cli = run_cli("spectral", "kd", "--films", films, "--response", wide, "--no-plots", "-o",
                  tmp_path / "k", check=False)
    assert cli.returncode != 0
    with pytest.raises(polrig.DataError) as e:
        polrig.spectral_kd(str(films), str(wide))
    assert str(e.value) == f"films {films}: its wavelengths [320, 800] nm do not cover the response's [300, 900] nm"
    assert f"--{e.value}" in cli.stderr
    sun = tmp_path / "sun.csv"
    sun.write_text("wavelength_nm,extraterrestrial\n330,1\n700,1\n")
    with pytest.raises(polrig.DataError, match=r"sun .*sun.csv: its wavelengths \[330, 700\] nm do not cover"):
        polrig.spectral_kd(str(films), str(SPECTRA / "blue-filter-photodiode-synthetic.csv"), sun=str(sun))


def test_study_sky_is_the_cli_bit_for_bit(tmp_path, cli):
    """Rig.study_sky against `polrig study sky` (Z21's unit array, two skies, noisy trials)."""
    rig_file = ROOT / "rigs" / "zhang2021-static.yaml"
    out = tmp_path / "study"
    cli("study", "sky", rig_file, "--tau", "0.1", "--albedo", "0,0.5", "--sun-el-deg", "10:50:3", "--tilts", "0,5",
        "--headings", "0,90", "--trials", "4", "--no-plots", "-o", out, "--quiet")
    r = polrig.Rig.load(str(rig_file)).study_sky(tau=[0.1], albedo=[0, 0.5], sun_el_deg=[10, 30, 50],
                                                 tilt_deg=[0, 5], heading_deg=[0, 90], trials=4, threads=1)
    assert r.device == "unit-array"
    for record, name in ((r.bias, "bias.csv"), (r.sky_dop, "sky_dop.csv"), (r.evector_by_dop, "evector_by_dop.csv")):
        for column_name, column in read_csv(out / name).items():
            got = getattr(record, column_name)
            if column.dtype == object:
                assert list(got) == list(column), column_name
            else:
                np.testing.assert_array_equal(np.asarray(got, dtype=float), column, err_msg=column_name)
    # Single scattering is the method's own sky: no bias; the exact sky's is real.
    single = r.bias.sky == "single-scattering"
    assert np.nanmax(np.abs(r.bias.sun_el_error_deg[single])) < 1e-8
    assert np.nanmax(np.abs(r.bias.sun_el_error_deg[~single])) > 0.1
    with pytest.raises(ValueError, match="albedo"):
        polrig.Rig.load(str(rig_file)).study_sky(albedo=[2], trials=0)
