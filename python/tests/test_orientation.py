"""polrig.sun_vector, polrig.orient and polrig.camera_heading: orientation from a DoFP camera's sky
image (compass/orientation.h, H17 Eqs. 6-14). The sky images are rendered here with polrig.Sky.light
(the Rayleigh sky's AoP chi in the local meridian frame), projected into the image in NumPy:
phi_pix = chi + alpha for a level camera, to exercise the API. The sign test of spec §0 does not
re-render: it takes polrig's own simulated frames and an independent sun (the AA formula). The CLI
`polrig orient` on simulated camera frames is compared with Python in test_dofp_pipeline.py."""
import datetime
import math

import numpy as np
import pytest

import polrig
from conftest import ROOT
from eigen_response import heading_and_elevation_gains, raw_cell_aop

F_C = 405.4
SITE = (28.221, 112.992)  # Changsha (H17 Sec. 4.2)
UTC = "2017-05-28T01:30:00Z"
OUTDOOR = str(ROOT / "rigs" / "han2017-outdoor.yaml")


def render(heading_deg, sky, cols=320, rows=240, element=2.0):
    """AoP image (rows, cols) of a level camera whose X_l points at geographic azimuth heading_deg."""
    x = (np.arange(cols) + 0.5) * element - cols * element / 2
    y = (np.arange(rows) + 0.5) * element - rows * element / 2
    dx, dy = np.meshgrid(x, y)
    alpha = np.degrees(np.arctan2(dy, dx))  # from X_l towards Y_l: anticlockwise seen from above
    gamma = np.degrees(np.arctan(np.hypot(dx, dy) / F_C))
    light = sky.light((heading_deg - alpha) % 360.0, 90.0 - gamma)  # azimuth falls as alpha rises
    return light.aop_deg + alpha, light.dop


def test_sun_vector_and_heading_of_a_rayleigh_sky():
    sky = polrig.Sky(SITE, UTC, 0.65)
    sun = sky.sun()
    for H in (0.0, 47.5, 181.0, 300.0):
        aop, dop = render(H, sky)
        s = polrig.sun_vector(aop, f_c_px=F_C)
        assert s.status == "ok" and s.root == "above-horizon"
        assert s.vectors_used == aop.size
        assert abs(s.sun_el_deg - sun.elevation_deg) < 1e-9
        assert abs((polrig.camera_heading(sun.azimuth_deg, s.sun_az_deg) - H + 180) % 360 - 180) < 1e-9
        assert np.linalg.norm(s.sun) == pytest.approx(1.0, abs=1e-15)
        assert np.all(np.diff(s.eigenvalues) >= 0)
        est = polrig.orient(aop, dop, sun_azimuth_deg=sun.azimuth_deg, f_c_px=F_C)
        assert [e.method for e in est] == ["eigenvector", "single-point", "line-detection"]
        for e in est:
            assert e.solved and e.status == "ok"
            assert abs((e.heading_deg - H + 180) % 360 - 180) < 0.25  # the Hough bin's half
        assert est[1].sun_el_deg is None and est[0].sun_el_deg == pytest.approx(sun.elevation_deg)


def aa_sun(utc, lat_deg, lon_deg):
    """The sun's geographic azimuth and elevation (degrees) by the Astronomical Almanac's
    low-precision formula (Michalsky 1988, spec §1.1; good to about 0.01° for 1950-2050): an
    independent implementation, not polrig's ERFA."""
    t = datetime.datetime.fromisoformat(utc.replace("Z", "+00:00"))
    n = t.timestamp() / 86400.0 + 2440587.5 - 2451545.0  # JD(UT) − 2451545.0
    ut_h = t.hour + t.minute / 60 + t.second / 3600
    r = math.radians
    L, g = 280.460 + 0.9856474 * n, r(357.528 + 0.9856003 * n)
    lam, eps = r(L + 1.915 * math.sin(g) + 0.020 * math.sin(2 * g)), r(23.439 - 0.0000004 * n)
    ra = math.atan2(math.cos(eps) * math.sin(lam), math.cos(lam))
    dec = math.asin(math.sin(eps) * math.sin(lam))
    lha = r(15 * (6.697375 + 0.0657098242 * n + ut_h) + lon_deg) - ra
    phi = r(lat_deg)
    h = math.asin(math.sin(phi) * math.sin(dec) + math.cos(phi) * math.cos(dec) * math.cos(lha))
    A = math.atan2(-math.sin(lha) * math.cos(dec),
                   math.cos(phi) * math.sin(dec) - math.sin(phi) * math.cos(dec) * math.cos(lha))
    return math.degrees(A) % 360.0, math.degrees(h)


def test_aa_sun_agrees_with_the_ephemeris():
    """The AA formula against polrig's ERFA (geometric, refraction off) to the formula's 0.01°."""
    for utc in ("2017-05-28T01:30:00Z", "2017-05-28T11:17:00Z", "2018-11-16T08:09:40Z"):
        A, h = aa_sun(utc, 28.2, 112.9)
        sun = polrig.sun_position(utc, (28.2, 112.9))
        assert abs((A - sun.azimuth_deg + 180) % 360 - 180) < 0.01 and abs(h - sun.elevation_deg) < 0.01, utc


def test_heading_sign_of_spec_0():
    """Spec §0's test, end to end on polrig's own simulator: frames of a level DoFP camera whose
    X_l points at geographic azimuth sky.mount_deg (docs/formats.md: clockwise from north), under
    the Rayleigh sky at Changsha. The cells' AoP is taken from the raw frame here in NumPy (mosaic
    0, 90, 45, 135° at TL, TR, BL, BR), the sun vector by polrig.sun_vector, and the heading by
    spec §0's ψ = β + atan2(s_y, s_x) with β from the AA formula above (not polrig's ephemeris).
    The heading must be sky.mount_deg, and turning the camera 10° anticlockwise seen from above
    (mount_deg − 10) must lower it by 10°. A sign error anywhere (the sky's E-vector, the image
    angles, the sun vector, the heading formula) moves the heading by tens of degrees."""
    utc = "2017-05-28T01:30:00Z"
    beta, h_s = aa_sun(utc, 28.2, 112.9)
    assert 40 < h_s < 60  # a sun well up: the eigenvector's s_z > 0 root is the sun
    headings = []
    for mount in (100.0, 90.0):
        rig = polrig.Rig.load(OUTDOOR, set={"sky.first_stop_utc": utc, "sky.mount_deg": mount,
                                            "schedule.angles_deg": [0], "device.noise": False})
        raw, layers = rig.dofp_frame(0, truth_layers=True)
        phi = raw_cell_aop(raw)
        s = polrig.sun_vector(np.degrees(phi), f_c_px=F_C)
        assert s.status == "ok"
        heading = (beta + math.degrees(math.atan2(s.sun[1], s.sun[0]))) % 360.0
        # The cells' footprint: a cell's four pixels view directions up to 1 px apart, so the sky's
        # gradients (its brightness above all) leak into Q and U, a systematic AoP error δφᵢ per
        # cell (noise is off). δφᵢ against the truth layers' AoP at the cell's centre (the circular
        # mean of its four pixels', exact to O(px²)) and eigen_response's first-order gains give
        # the bias this leaves in the heading and the elevation (about 0.04° here).
        truth = np.radians(layers["AoP"].astype(float))
        c2 = sum(np.exp(2j * truth[r::2, c::2]) for r in (0, 1) for c in (0, 1))
        dphi = np.angle(np.exp(2j * phi) / c2) / 2
        az = math.radians(mount - beta)  # the sun's azimuth in frame l, from the AA sun
        sun_l = [math.cos(math.radians(h_s)) * math.cos(az), math.cos(math.radians(h_s)) * math.sin(az),
                 math.sin(math.radians(h_s))]
        G, E = heading_and_elevation_gains(320, 240, F_C, 320.0, 240.0, sun_l)
        bias_H, bias_h = math.degrees(G @ dphi.reshape(-1)), math.degrees(E @ dphi.reshape(-1))
        print(f"mount {mount}: heading {heading:.4f}° (footprint bias {bias_H:+.4f}°), "
              f"elevation {s.sun_el_deg:.4f}° (AA {h_s:.4f}°, bias {bias_h:+.4f}°)")
        # The AA formula's 0.01° (test_aa_sun_agrees_with_the_ephemeris), plus the float32 truth
        # layers (1e-5°) and second-order terms of a 0.04° bias (≈ 1e-5°).
        assert abs((heading - bias_H - mount + 180) % 360 - 180) < 0.011
        assert abs(s.sun_el_deg - bias_h - h_s) < 0.011
        headings.append(heading - bias_H)
    # The same sun for both: the AA formula's error cancels.
    assert (headings[1] - headings[0] + 180) % 360 - 180 == pytest.approx(-10.0, abs=1e-3)
    assert polrig.camera_heading(350.0, 20.0) == pytest.approx(10.0)


def test_dop_weighting_and_prior():
    sky = polrig.Sky(SITE, UTC, 0.65)
    aop, dop = render(30.0, sky)
    aop = aop.copy()
    dop = dop.copy()
    aop[::7, ::5] += 40.0
    dop[::7, ::5] = 0.0
    good = polrig.sun_vector(aop, dop, f_c_px=F_C, dop_weighting=True)
    bad = polrig.sun_vector(aop, dop, f_c_px=F_C)
    truth = sky.sun().elevation_deg
    assert abs(good.sun_el_deg - truth) < 1e-9
    assert abs(bad.sun_el_deg - truth) > 1e-3
    # A prior pointing below the horizon picks the antisun.
    flipped = polrig.sun_vector(aop, dop, f_c_px=F_C, dop_weighting=True, prior_sun=-good.sun)
    assert flipped.root == "prior"
    assert np.allclose(flipped.sun, -good.sun, atol=1e-15)


def test_bad_input_gives_a_status_or_a_value_error():
    blank = np.full((240, 320), np.nan)
    s = polrig.sun_vector(blank)
    assert s.status == "too-few-vectors" and s.vectors_used == 0
    assert np.all(np.isfinite(s.sun))
    est = polrig.orient(blank, sun_azimuth_deg=10.0)
    assert [e.status for e in est] == ["too-few-vectors", "no-points", "no-points"]
    assert all(e.heading_deg is None and e.sun_az_deg is None for e in est)
    with pytest.raises(ValueError, match="aop_deg"):
        polrig.sun_vector(np.zeros(10))
    with pytest.raises(ValueError, match="dop"):
        polrig.sun_vector(np.zeros((4, 4)), np.zeros((4, 5)))
    with pytest.raises(ValueError, match="conversion"):
        polrig.sun_vector(np.zeros((4, 4)), conversion="fisheye")
    with pytest.raises(ValueError, match="f_c"):
        polrig.sun_vector(np.zeros((4, 4)), f_c_px=0.0)
    with pytest.raises(ValueError, match="hough_bin_deg"):
        polrig.orient(np.zeros((4, 4)), hough_bin_deg=0.0)
    with pytest.raises(ValueError, match=r"hough_bin_deg = 1e-09: must be in \[0.001°, 30°\]"):
        polrig.orient(np.zeros((4, 4)), hough_bin_deg=1e-9)


def test_correct_noise_bias_removes_the_bias_and_measures_the_noise():
    """Gaussian noise of SD sigma on the normalised Stokes (q, u) of a rendered Rayleigh sky (NumPy,
    independent of polrig's cameras): the unweighted sun is biased by many standard errors, the
    corrected one is not, and its stokes_noise_sd is the sigma put in (docs/physics.md §15)."""
    sky = polrig.Sky(SITE, UTC, 0.65)
    aop, dop = render(30.0, sky, cols=160, rows=120, element=4.0)
    truth = sky.sun().elevation_deg
    clean = polrig.sun_vector(aop, dop, f_c_px=F_C, element_px=4.0, correct_noise_bias=True)
    assert abs(clean.sun_el_deg - truth) < 1e-9 and clean.stokes_noise_sd < 1e-6
    rng = np.random.default_rng(20151216)
    sigma = 0.01
    phi = np.radians(aop)
    plain, corrected, sd = [], [], []
    for _ in range(96):
        q = dop * np.cos(2 * phi) + sigma * rng.standard_normal(dop.shape)
        u = dop * np.sin(2 * phi) + sigma * rng.standard_normal(dop.shape)
        a, d = np.degrees(0.5 * np.arctan2(u, q)), np.hypot(q, u)
        plain.append(polrig.sun_vector(a, d, f_c_px=F_C, element_px=4.0).sun_el_deg - truth)
        c = polrig.sun_vector(a, d, f_c_px=F_C, element_px=4.0, correct_noise_bias=True)
        corrected.append(c.sun_el_deg - truth)
        sd.append(c.stokes_noise_sd)
    se = lambda x: np.std(x, ddof=1) / math.sqrt(len(x))
    print(f"elevation bias: unweighted {np.mean(plain):+.5f} ± {se(plain):.5f}°, "
          f"corrected {np.mean(corrected):+.5f} ± {se(corrected):.5f}°; σ {np.mean(sd):.5f}")
    assert abs(np.mean(plain)) > 5 * se(plain)
    # First order in σ² removed: what is left (≈ 0.7 % at σ = 0.01, second order) is within the
    # Monte-Carlo error of 96 realisations.
    assert abs(np.mean(corrected)) < 3 * se(corrected)
    assert abs(np.mean(corrected)) < 0.02 * abs(np.mean(plain))
    assert np.mean(sd) == pytest.approx(sigma, rel=0.03)
    with pytest.raises(ValueError, match="correct_noise_bias"):
        polrig.sun_vector(aop, f_c_px=F_C, correct_noise_bias=True)
