"""polrig.sun_vector, polrig.orient and polrig.camera_heading: orientation from a DoFP camera's sky
image (nav/orientation.h, H17 Eqs. 6-14). The sky images are rendered here with polrig.Sky.light
(the Rayleigh sky's AoP chi in the local meridian frame), projected into the image in NumPy:
phi_pix = chi + alpha for a level camera. The CLI `polrig orient` on simulated camera frames is
compared with Python in test_dofp_pipeline.py."""
import numpy as np
import pytest

import polrig

F_C = 405.4
SITE = (28.221, 112.992)  # Changsha (H17 Sec. 4.2)
UTC = "2017-05-28T01:30:00Z"


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


def test_heading_sign_of_spec_0():
    """Rotating the camera +10 deg anticlockwise seen from above lowers the heading by 10 deg."""
    sky = polrig.Sky(SITE, UTC, 0.65)
    A = sky.sun().azimuth_deg
    h0 = polrig.orient(render(100.0, sky)[0], sun_azimuth_deg=A, f_c_px=F_C)[0].heading_deg
    h1 = polrig.orient(render(90.0, sky)[0], sun_azimuth_deg=A, f_c_px=F_C)[0].heading_deg
    assert h1 - h0 == pytest.approx(-10.0, abs=1e-9)
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
