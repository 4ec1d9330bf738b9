"""Positioning from the sun's zenith angle (W16 Eqs. 15-18, spec sky-and-compasses.md §3.4):
polrig.fix_position, polrig.locate, polrig.two_sighting_error and Rig.study_positioning, the last
against `polrig study positioning`'s CSV files bit for bit."""
import math

import numpy as np
import pytest

import polrig
from conftest import ROOT, read_csv

SITE = (28.221, 112.992)  # W16's roof
RIG = ROOT / "rigs" / "wang2016-static.yaml"  # W16's static hour: the study reads its sky and times


def hour(step_s=1):
    t0 = np.datetime64("2015-12-16T05:37:00", "ns")
    return t0 + np.arange(0, 3601, step_s).astype("timedelta64[s]")



def test_eq15_w16_number():
    angle, dist = polrig.two_sighting_error(0.14, 0.14, 215.0, 200.0)
    assert angle == pytest.approx(0.14 * math.sqrt(2) / math.sin(math.radians(15)), abs=1e-12)
    assert round(angle, 3) == 0.765 and round(dist, 1) == 85.2
    with pytest.raises(ValueError):
        polrig.two_sighting_error(-1, 0.1, 0, 15)


def test_fix_position_noise_free_hour_recovers_the_site():
    t = hour(10)
    z = polrig.sun_position(t, SITE).zenith_deg
    fix = polrig.fix_position(t, z, (28.9, 113.6), truth=SITE)
    assert list(fix.root) == ["chosen", "alternative"]
    assert fix.termination[0] == "converged"
    assert fix.error_km[0] < 1e-3  # metres
    assert fix.error_km[1] > 3000  # the mirror root, far south
    assert fix.lat_deg[1] < -40
    assert fix.rank[0] == 2
    one = polrig.fix_position(t[:1], z[:1], SITE)
    assert one.termination[0] == "too_few_sightings"
    with pytest.raises(ValueError):
        polrig.fix_position(t, z[:-1], SITE)


def sun_in_camera(enu, heading_deg):
    """The ENU sun in frame l of a level camera whose X_l points at geographic azimuth H."""
    h = math.radians(heading_deg)
    x = np.array([math.sin(h), math.cos(h), 0.0])
    y = np.array([-math.cos(h), math.sin(h), 0.0])
    return np.stack([enu @ x, enu @ y, enu[:, 2]], axis=1)


def test_locate_heading_and_the_sign_test():
    t = hour(60)
    enu = polrig.sun_position(t, SITE).enu
    a = polrig.locate(t, sun_in_camera(enu, 180.1), (28.5, 113.4), truth=SITE,
                      true_heading_deg=np.full(len(t), 180.1))
    assert a.fix.error_km[0] < 1e-3
    assert np.abs(a.heading_error_deg).max() < 1e-6
    # W16: α_S rises with β (20.9° → 35.6° while β 201.0° → 215.5°, ψ = 180.1°).
    assert a.alpha_s_deg[0] == pytest.approx(200.87 - 180.1, abs=0.01)
    assert a.alpha_s_deg[-1] == pytest.approx(215.42 - 180.1, abs=0.01)
    # Spec §0: the device turned +10° anticlockwise seen from above: the heading falls by 10°.
    c, s = math.cos(math.radians(-10)), math.sin(math.radians(-10))
    v = sun_in_camera(enu, 180.1)
    turned = np.stack([c * v[:, 0] - s * v[:, 1], s * v[:, 0] + c * v[:, 1], v[:, 2]], axis=1)
    b = polrig.locate(t, turned, (28.5, 113.4))
    assert (b.heading_mean_deg - a.heading_mean_deg + 180) % 360 - 180 == pytest.approx(-10, abs=1e-6)


def test_study_positioning_is_the_cli_bit_for_bit(tmp_path, cli):
    out = tmp_path / "study"
    cli("study", "positioning", RIG, "--trials", "6", "--windows", "300,3600", "--noise", "0,0.14",
        "--tilts", "0.1", "--correlation", "30", "--no-plots", "-o", out, "--quiet")
    rig = polrig.Rig.load(str(RIG))
    r = rig.study_positioning(trials=6, windows_s=[300, 3600], noise_sd_deg=[0, 0.14], tilt_deg=[0.1],
                              correlation_s=30, threads=1)
    summary = read_csv(out / "summary.csv")
    for name, column in summary.items():
        got = getattr(r, "trials_per_cell" if name == "trials" else name)
        if column.dtype == object:
            assert list(got) == list(column), name
        else:
            np.testing.assert_array_equal(np.asarray(got, dtype=float), column, err_msg=name)
    trials = read_csv(out / "trials.csv")
    for name, column in trials.items():
        got = getattr(r.trials, name)
        if column.dtype == object:
            assert list(got) == list(column), name
        else:
            np.testing.assert_array_equal(np.asarray(got, dtype=float), column, err_msg=name)
    with pytest.raises(ValueError, match="noise_sd_deg"):
        rig.study_positioning(trials=2, noise_sd_deg=[11])


def test_locate_dataset_is_the_cli_bit_for_bit(tmp_path, cli):
    """polrig.locate_dataset against `polrig locate` on a small four-camera dataset (W16's static
    hour, 4 stops 20 min apart, an eighth-resolution sensor with the same field, with noise)."""
    data, out = tmp_path / "w16", tmp_path / "loc"
    cli("simulate", ROOT / "rigs" / "wang2016-static.yaml", "--layers", "aop", "--quiet",
        "--set", "schedule.count=4", "--set", "schedule.dwell_s=1200",
        "--set", "device.cameras.width_px=130", "--set", "device.cameras.height_px=98",
        "--set", "device.cameras.fx_px=[96.25, 96.4, 96.1125, 96.325]",
        "--set", "device.cameras.fy_px=[96.25, 96.4, 96.1125, 96.325]",
        "--set", "device.cameras.cx_px=[65, 65.3, 64.9625, 65.2375]",
        "--set", "device.cameras.cy_px=[49, 48.975, 49.2875, 49.075]", "-o", data)
    cli("locate", data, "--prior", "29,113.5", "-o", out, "--quiet")
    loc = polrig.locate_dataset(str(data), (29, 113.5))
    heading = read_csv(out / "heading.csv")
    for name, column in heading.items():
        got = getattr(loc, name)
        if name == "utc":
            assert [str(t)[:19] + "Z" for t in got] == list(column)
        else:
            np.testing.assert_array_equal(np.asarray(got, dtype=float), column, err_msg=name)
    fix = read_csv(out / "fix.csv")
    for name, column in fix.items():
        got = getattr(loc.fix, name)
        if column.dtype == object:
            assert list(got) == list(column), name
        else:
            np.testing.assert_array_equal(np.asarray(got, dtype=float), column, err_msg=name)
    assert loc.fix.error_km[0] < 100  # four noisy sightings over an hour: tens of km at most
    # The noise-bias correction (docs/physics.md §15): the CLI's flag and the keyword, bit for bit.
    cli("locate", data, "--prior", "29,113.5", "--correct-noise-bias", "-o", tmp_path / "cor", "--quiet")
    cor = polrig.locate_dataset(str(data), (29, 113.5), correct_noise_bias=True)
    np.testing.assert_array_equal(cor.heading_deg, read_csv(tmp_path / "cor" / "heading.csv")["heading_deg"])
    np.testing.assert_array_equal(cor.fix.error_km, read_csv(tmp_path / "cor" / "fix.csv")["error_km"])
    assert not np.array_equal(cor.heading_deg, loc.heading_deg)
    with pytest.raises(Exception, match="none.stops.csv: cannot open"):  # names the missing file (no truth.yaml is fine: measured data)
        polrig.locate_dataset(str(tmp_path / "none"), (29, 113.5))


def test_the_fix_covariance_holds_where_the_fit_is_linear_and_not_across_a_short_arc():
    # The fix's s²(JᵀWJ)⁻¹ with its north–east correlation (what navigation.measurement pns-fix feeds
    # the filter) against 200 Monte-Carlo fits of Z21's static site, white zenith noise: its NEES is
    # χ²(2) (mean 2, sd of the mean 0.14; Hotelling's 2(N−2)/(N−4) ≈ 2.01 with s² estimated) while
    # the fit is linear, 0.01° over 300 s; with Z21's 0.1° the 300-s ellipse is ~140 km long across
    # the sun, beyond the linear regime, and the NEES is about twice its χ² (docs/validation.md).
    t0 = np.datetime64("2019-09-18T08:14:00")
    site = (39.979, 116.339, 50.0)
    rng = np.random.default_rng(20190918)
    utc = t0 + np.arange(1, 301).astype("timedelta64[s]")
    z0 = np.asarray(polrig.sun_position(utc, site).zenith_deg)
    mean_nees = {}
    for sigma in (0.01, 0.1):
        nees = []
        for _ in range(200):
            f = polrig.fix_position(utc, z0 + sigma * rng.standard_normal(utc.size), site, second_root=False)
            assert f.termination[0] == "converged"
            e = np.array([np.radians(f.lat_deg[0] - site[0]),
                          np.radians(f.lon_deg[0] - site[1]) * np.cos(np.radians(site[0]))]) * polrig_radius_km()
            sn, se, c = f.sd_north_km[0], f.sd_east_km[0], f.corr_north_east[0]
            assert -1 < c < -0.99  # the ellipse is near a line across the sun
            C = np.array([[sn * sn, c * sn * se], [c * sn * se, se * se]])
            nees.append(e @ np.linalg.solve(C, e))
        mean_nees[sigma] = np.mean(nees)
    assert abs(mean_nees[0.01] - 2.01) < 4 * 0.14, mean_nees
    assert mean_nees[0.1] > 3.0, mean_nees


def polrig_radius_km():
    return 6371.0088  # compass/positioning.h's kEarthMeanRadiusKm, the fit's north/east scale
