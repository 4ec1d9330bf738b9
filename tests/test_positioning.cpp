// compass/positioning: position from the sun's zenith angle (W16 Eqs. 15–17) and the heading at the
// fix (Eq. 18), spec sky-and-compasses.md §3.4–3.6. The data come from sky/sun.h's full ERFA
// sun_position at the true site (what the sky source simulates), never from the fit's own model;
// the sun vectors of a level camera are built here from ENU with this file's own frame.
#include <cmath>
#include <filesystem>
#include <numbers>
#include <vector>

#include <gtest/gtest.h>

#include "polrig/compass/orientation.h"
#include "polrig/compass/positioning.h"
#include "polrig/report/positioning_reports.h"
#include "polrig/sky/sun.h"
#include "polrig/study/positioning.h"
#include "support.h"

namespace {
using namespace polrig;

double rad(double deg) { return deg * std::numbers::pi / 180.0; }
double deg(double r) { return r * 180.0 / std::numbers::pi; }

// W16's static run (spec §3.5): the roof at E112.992°, N28.221°, 16 Dec 2015, 13:37–14:37
// Beijing time (UTC+8), 1 Hz.
const Site kW16Site{28.221, 112.992, 0};
const UtcTime kW16Start = parse_utc("2015-12-16T05:37:00Z");

std::vector<UtcTime> window(double seconds, double step_s = 1) {
  std::vector<UtcTime> t;
  for (double s = 0; s <= seconds + 1e-9; s += step_s) t.push_back(kW16Start.plus_seconds(s));
  return t;
}

std::vector<ZenithSighting> exact_zeniths(const std::vector<UtcTime>& times, const Site& site,
                                          const SunSettings& sun = {}) {
  std::vector<ZenithSighting> z;
  for (const UtcTime& t : times) z.push_back({t, sun_position(t, site, sun).zenith_deg, 1.0});
  return z;
}

// The sun in frame l of a level camera whose X_l points at geographic azimuth H (clockwise from
// north): X_l = (sin H, cos H, 0) in ENU, Z_l up, Y_l = Z_l × X_l.
Vec3 sun_in_camera(const SunPosition& sun, double heading_deg) {
  const Vec3 s = sun_direction_enu(sun);
  const double H = rad(heading_deg);
  const Vec3 x{std::sin(H), std::cos(H), 0}, y{-std::cos(H), std::sin(H), 0};
  return {s[0] * x[0] + s[1] * x[1], s[0] * y[0] + s[1] * y[1], s[2]};
}

double angle_diff(double a, double b) { return std::remainder(a - b, 360.0); }

// §3.6 item 1: the ephemeris beside W16 (β 201.0° → 215.5°, θ_s ≈ 60.7° at 14:37, ≈ 80.4° at
// 16:40) and the spec's own values (200.87° → 215.42°, 60.75°, 80.45°, from an independent
// ephemeris within 0.001°; printed to 0.01°, so ±0.005°).
TEST(W16Ephemeris, SpecAndPaperValues) {
  const SunPosition a = sun_position(kW16Start, kW16Site);
  const SunPosition b = sun_position(parse_utc("2015-12-16T06:37:00Z"), kW16Site);
  const SunPosition c = sun_position(parse_utc("2015-12-16T08:40:00Z"), kW16Site);
  EXPECT_NEAR(a.azimuth_deg, 200.87, 0.005);
  EXPECT_NEAR(b.azimuth_deg, 215.42, 0.005);
  EXPECT_NEAR(b.zenith_deg, 60.75, 0.005);
  EXPECT_NEAR(c.zenith_deg, 80.45, 0.005);
  // W16 rounds to 0.1°; its β is 0.1° high at both ends (its own clock or ephemeris).
  EXPECT_NEAR(a.azimuth_deg, 201.0, 0.15);
  EXPECT_NEAR(b.azimuth_deg, 215.5, 0.1);
  EXPECT_NEAR(b.zenith_deg, 60.7, 0.06);
  EXPECT_NEAR(c.zenith_deg, 80.4, 0.06);
}

// Eq. 17's model with sun_position's topocentric δ and GHA is the zenith angle sun_position
// gives (sun.h: exact with refraction off), to < 1e-9° (0.1 mm on the ground: ERFA's horizon
// transformation also carries the TIO locator s′ in its longitude).
TEST(ZenithModel, IsTheEphemerisZenith) {
  for (double s = 0; s <= 3600; s += 600) {
    const SunPosition p = sun_position(kW16Start.plus_seconds(s), kW16Site);
    const ZenithModel m = zenith_model(rad(p.declination_deg), rad(p.gha_deg), rad(kW16Site.lat_deg),
                                       rad(kW16Site.lon_deg));
    EXPECT_NEAR(deg(m.zenith_rad), p.zenith_deg, 2e-9);
  }
}

// SunTrack::hour_angle_at (the fit's fast path) is at()'s declination and hour angle.
TEST(ZenithModel, TrackHourAngleIsAtsDeclinationAndHourAngle) {
  const SunTrack track(kW16Start, kW16Start.plus_seconds(3600), kW16Site);
  for (double s = 0; s <= 3600; s += 450) {
    const UtcTime t = kW16Start.plus_seconds(s);
    const SunPosition p = track.at(t);
    const SunTrack::HourAngle h = track.hour_angle_at(t);
    EXPECT_NEAR(deg(std::atan2(h.sin_dec, h.cos_dec)), p.declination_deg, 1e-12);
    EXPECT_NEAR(std::remainder(deg(std::atan2(h.sin_gha, h.cos_gha)) - p.gha_deg, 360.0), 0, 1e-11);
    EXPECT_NEAR(h.sin_dec * h.sin_dec + h.cos_dec * h.cos_dec, 1, 1e-15);
    EXPECT_NEAR(h.sin_gha * h.sin_gha + h.cos_gha * h.cos_gha, 1, 1e-15);
    // and the track is the full ephemeris to < 1e-6° (sun.h's bound).
    EXPECT_NEAR(p.zenith_deg, sun_position(t, kW16Site).zenith_deg, 1e-6);
  }
  EXPECT_THROW(track.hour_angle_at(kW16Start.plus_seconds(3601)), std::out_of_range);
}

// The analytic Jacobian against central differences: of the closed form (the derivatives'
// algebra) and of ERFA's own zenith angle moved with the site (which also moves the parallax:
// 8.8″ over an Earth radius, a relative 4e-5).
TEST(ZenithModel, JacobianAgainstFiniteDifferences) {
  const double h = 1e-5;  // rad
  for (double s : {0.0, 1800.0, 3600.0}) {
    const UtcTime t = kW16Start.plus_seconds(s);
    const SunPosition p = sun_position(t, kW16Site);
    const double dec = rad(p.declination_deg), gha = rad(p.gha_deg);
    const double L = rad(kW16Site.lat_deg), lam = rad(kW16Site.lon_deg);
    const ZenithModel m = zenith_model(dec, gha, L, lam);
    const auto th = [&](double l, double o) { return zenith_model(dec, gha, l, o).zenith_rad; };
    EXPECT_NEAR(m.d_lat, (th(L + h, lam) - th(L - h, lam)) / (2 * h), 1e-8);
    EXPECT_NEAR(m.d_lon, (th(L, lam + h) - th(L, lam - h)) / (2 * h), 1e-8);
    const auto erfa = [&](double dl, double dn) {
      return rad(sun_position(t, {kW16Site.lat_deg + deg(dl), kW16Site.lon_deg + deg(dn), 0}).zenith_deg);
    };
    const double hh = 1e-4;
    EXPECT_NEAR(m.d_lat, (erfa(hh, 0) - erfa(-hh, 0)) / (2 * hh), 1e-4);
    EXPECT_NEAR(m.d_lon, (erfa(0, hh) - erfa(0, -hh)) / (2 * hh), 1e-4);
    EXPECT_GT(std::abs(m.d_lat), 0.1);
    EXPECT_GT(std::abs(m.d_lon), 0.1);
  }
}

// Eq. 15 with W16's numbers: ε_γ = 0.14° for both sightings, Δα = 15° → 0.765° = 85.2 km.
TEST(Eq15, W16Number) {
  const TwoSightingError e = two_sighting_error(0.14, 0.14, 215.0, 200.0);
  EXPECT_NEAR(e.angle_deg, 0.14 * std::sqrt(2.0) / std::sin(rad(15)), 1e-12);
  EXPECT_NEAR(e.angle_deg, 0.765, 0.0005);
  EXPECT_NEAR(e.km, 85.2, 0.05);
  EXPECT_EQ(two_sighting_error(0.14, 0.14, 200.0, 215.0).km, e.km);  // |sin|
  EXPECT_TRUE(std::isinf(two_sighting_error(0.1, 0.1, 30.0, 210.0).km));
  EXPECT_THROW(two_sighting_error(-0.1, 0.1, 0, 15), std::invalid_argument);
}

// §3.5: W16's stated fix (E113.591°, N27.868°) is 70.7 km from the roof, not the 68.6 km it says.
TEST(GreatCircle, W16StatedFixIs70_7km) {
  EXPECT_NEAR(great_circle_km(27.868, 113.591, 28.221, 112.992), 70.7, 0.05);
  EXPECT_NEAR(great_circle_km(0, 0, 0, 1), kEarthMeanRadiusKm * std::numbers::pi / 180, 1e-9);
}

// Noise-free zenith angles over W16's hour at 1 Hz recover the site to metres from a prior
// 100 km away; the mirror root is found, far away, and the prior picks the true one.
TEST(FixPosition, NoiseFreeW16HourRecoversTheSiteToMetres) {
  const std::vector<ZenithSighting> z = exact_zeniths(window(3600), kW16Site);
  ASSERT_EQ(z.size(), 3601u);
  const Site prior{28.9, 113.6, 0};
  const PositionFix fix = fix_position(z, prior);
  ASSERT_TRUE(fix.usable()) << fix.chosen.summary.brief_report();
  const double error_m = great_circle_km(fix.chosen.lat_deg, fix.chosen.lon_deg, kW16Site.lat_deg,
                                         kW16Site.lon_deg) * 1e3;
  EXPECT_LT(error_m, 0.5) << fix.chosen.summary.brief_report();
  EXPECT_LT(fix.chosen.summary.residual_rms_deg, 2e-6);
  EXPECT_EQ(fix.chosen.summary.rank, 2);
  EXPECT_EQ(fix.chosen.summary.sightings, 3601);
  EXPECT_GT(fix.chosen.summary.relinearizations, 1);
  // The hour's sun moves 14.5° in azimuth: the conditioning is about that spread (rad).
  EXPECT_GT(fix.chosen.summary.singular_ratio, 0.03);
  EXPECT_LT(fix.chosen.summary.singular_ratio, 0.3);
  ASSERT_TRUE(fix.alternative.has_value()) << fix.alternative_note;
  const PositionRoot& alt = *fix.alternative;
  EXPECT_GT(great_circle_km(alt.lat_deg, alt.lon_deg, kW16Site.lat_deg, kW16Site.lon_deg), 3000);
  EXPECT_LT(alt.lat_deg, -40);  // the mirror of 28° N about a track at δ = −23.3°
  EXPECT_GT(alt.prior_distance_km, fix.chosen.prior_distance_km);
  // Over an hour the ground track is not a great circle: the mirror fits worse.
  EXPECT_GT(alt.summary.final_cost_deg2, 1e3 * fix.chosen.summary.final_cost_deg2);
}

// Two instants: two equal-altitude circles, two exact intersections (W16's M and M′). The prior
// chooses; each root's own ERFA zenith angles equal the measured ones.
TEST(FixPosition, TwoSightingsGiveTwoExactRootsAndThePriorChooses) {
  const std::vector<ZenithSighting> z = exact_zeniths({kW16Start, kW16Start.plus_seconds(3600)}, kW16Site);
  const PositionFix near = fix_position(z, {28.0, 113.0, 0});
  ASSERT_TRUE(near.usable()) << near.chosen.summary.brief_report();
  ASSERT_TRUE(near.alternative.has_value()) << near.alternative_note;
  EXPECT_LT(great_circle_km(near.chosen.lat_deg, near.chosen.lon_deg, kW16Site.lat_deg, kW16Site.lon_deg), 1e-3);
  const PositionRoot& m2 = *near.alternative;
  ASSERT_TRUE(m2.summary.usable()) << m2.summary.brief_report();
  for (const ZenithSighting& s : z)
    EXPECT_NEAR(sun_position(s.utc, m2.site()).zenith_deg, s.zenith_deg, 1e-6);
  // A prior near M′ chooses M′.
  const PositionFix far = fix_position(z, {m2.lat_deg + 1, m2.lon_deg - 1, 0});
  ASSERT_TRUE(far.usable());
  EXPECT_LT(great_circle_km(far.chosen.lat_deg, far.chosen.lon_deg, m2.lat_deg, m2.lon_deg), 1e-3);
  ASSERT_TRUE(far.alternative.has_value());
  EXPECT_LT(great_circle_km(far.alternative->lat_deg, far.alternative->lon_deg, kW16Site.lat_deg,
                            kW16Site.lon_deg), 1e-3);
}

// Refraction on in the data and in the fit: still metres.
TEST(FixPosition, RefractedSunRecoversTheSite) {
  SunSettings sun;
  sun.refraction = true;
  const std::vector<ZenithSighting> z = exact_zeniths(window(3600, 60), kW16Site, sun);
  PositionOptions o;
  o.sun = sun;
  const PositionFix fix = fix_position(z, {28.5, 113.3, 0}, o);
  ASSERT_TRUE(fix.usable()) << fix.chosen.summary.brief_report();
  EXPECT_LT(great_circle_km(fix.chosen.lat_deg, fix.chosen.lon_deg, kW16Site.lat_deg, kW16Site.lon_deg) * 1e3, 0.5);
  // Without refraction in the fit the same data miss by kilometres (1.7′ at 60° is 3 km).
  const PositionFix wrong = fix_position(z, {28.5, 113.3, 0});
  EXPECT_GT(great_circle_km(wrong.chosen.lat_deg, wrong.chosen.lon_deg, kW16Site.lat_deg, kW16Site.lon_deg), 1.0);
}

// Failures are data: too few sightings, a window of one instant, zero weights.
TEST(FixPosition, DegenerateWindowsAreStatuses) {
  const std::vector<ZenithSighting> one = exact_zeniths({kW16Start}, kW16Site);
  EXPECT_EQ(fix_position(one, kW16Site).chosen.summary.termination, PositionTermination::TooFewSightings);
  EXPECT_EQ(fix_position({}, kW16Site).chosen.summary.termination, PositionTermination::TooFewSightings);
  std::vector<ZenithSighting> same = exact_zeniths({kW16Start, kW16Start, kW16Start}, kW16Site);
  const PositionFix f = fix_position(same, {28.5, 113.3, 0});
  EXPECT_EQ(f.chosen.summary.termination, PositionTermination::RankDeficient) << f.chosen.summary.brief_report();
  EXPECT_FALSE(f.usable());
  std::vector<ZenithSighting> z = exact_zeniths(window(60, 30), kW16Site);
  for (ZenithSighting& s : z) s.weight = 0;
  z[0].weight = 1;
  EXPECT_EQ(fix_position(z, kW16Site).chosen.summary.termination, PositionTermination::TooFewSightings);
  z[0].zenith_deg = 181;
  EXPECT_THROW(fix_position(z, kW16Site), std::invalid_argument);
  EXPECT_THROW(fix_position(exact_zeniths({kW16Start}, kW16Site), {95, 0, 0}), std::invalid_argument);
}

// W16's arithmetic (§3.6 item 3): ψ = β − α_S = 201.0 − 20.9 = 180.1°, with α_S clockwise:
// camera_heading_deg takes the anticlockwise atan2(s_y, s_x) = −α_S.
TEST(Heading, W16Arithmetic) {
  EXPECT_NEAR(camera_heading_deg(201.0, -20.9), 180.1, 1e-12);
  EXPECT_NEAR(camera_heading_deg(215.5, -35.6), 179.9, 1e-12);
}

// The locate core on a level camera's sun vectors: the fix, α_S rising with β as W16's (20.9° →
// 35.6° while β 201.0° → 215.5°, heading 180.1°), the heading, and spec §0's sign test: turned by
// +10° anticlockwise seen from above, the heading falls by 10°.
TEST(Locate, HeadingAndTheSignTest) {
  const std::vector<UtcTime> times = window(3600, 10);
  const auto run = [&](double heading_deg) {
    std::vector<SunSighting> s;
    for (const UtcTime& t : times) s.push_back({t, vec3::mul(sun_in_camera(sun_position(t, kW16Site), heading_deg), 2.5), 1});
    return locate(s, {28.5, 113.4, 0});
  };
  const Location a = run(180.1);
  ASSERT_TRUE(a.fix.usable()) << a.fix.chosen.summary.brief_report();
  EXPECT_LT(great_circle_km(a.fix.chosen.lat_deg, a.fix.chosen.lon_deg, kW16Site.lat_deg, kW16Site.lon_deg) * 1e3, 1.0);
  ASSERT_EQ(a.samples.size(), times.size());
  EXPECT_NEAR(a.samples.front().alpha_s_deg, 200.87 - 180.1, 0.01);
  EXPECT_NEAR(a.samples.back().alpha_s_deg, 215.42 - 180.1, 0.01);
  for (const LocateSample& s : a.samples) {
    EXPECT_NEAR(angle_diff(s.heading_deg, 180.1), 0, 1e-6);
    EXPECT_NEAR(s.residual_deg, 0, 1e-5);
  }
  EXPECT_NEAR(a.heading_mean_deg, 180.1, 1e-6);
  EXPECT_LT(a.heading_sd_deg, 1e-6);
  // The device turned +10° anticlockwise seen from above: its X_l now points 10° further
  // anticlockwise, i.e. its geographic azimuth is 10° less; the sun vectors are those of heading
  // 170.1, built from ENU. The heading must fall by 10°.
  std::vector<SunSighting> turned;
  for (const UtcTime& t : times) {
    // The same sun, its frame-l vector rotated by −10° about Z_l (the sky turns the other way).
    const Vec3 s0 = sun_in_camera(sun_position(t, kW16Site), 180.1);
    const double c = std::cos(rad(-10)), sn = std::sin(rad(-10));
    turned.push_back({t, {c * s0[0] - sn * s0[1], sn * s0[0] + c * s0[1], s0[2]}, 1});
  }
  const Location b = locate(turned, {28.5, 113.4, 0});
  ASSERT_TRUE(b.fix.usable());
  EXPECT_NEAR(angle_diff(b.heading_mean_deg, a.heading_mean_deg), -10, 1e-6);
  EXPECT_THROW(locate(std::vector<SunSighting>{{kW16Start, {0, 0, 0}, 1}, {kW16Start, {0, 0, 1}, 1}}, kW16Site),
               std::invalid_argument);
}

// The Monte-Carlo against the linearized least-squares error (P·Σ·Pᵀ from the Jacobian at the
// truth, an analytic prediction independent of the trials): white noise, a levelling error alone
// and Gauss–Markov noise. 200 trials: the RMS has a relative standard error of 5 %.
TEST(PositioningStudy, MonteCarloMatchesTheLinearizedError) {
  PositioningStudySettings s;
  s.times_s.clear();
  for (int k = 0; k <= 360; ++k) s.times_s.push_back(10.0 * k);  // the hour at 0.1 Hz
  s.windows_s = {3600};
  s.noise_sd_deg = {0.14};
  s.tilt_deg = {0.1};
  s.baseline_noise_sd_deg = 0;  // cells: the window (noise-free), σ = 0.14° alone, τ = 0.1° alone
  s.trials = 200;
  const PositioningStudy white = positioning_study(s);
  ASSERT_EQ(white.cells.size(), 3u);
  EXPECT_LT(white.stats[0].max_km, 1e-3);
  for (std::size_t c : {1u, 2u}) {
    EXPECT_EQ(white.stats[c].converged, 200);
    EXPECT_NEAR(white.stats[c].rms_km / white.cells[c].linear_rms_km, 1, 0.15) << c;
  }
  EXPECT_GT(white.cells[1].linear_rms_km, 5);  // 0.14° over 361 sightings: ~11 km
  EXPECT_LT(white.cells[1].linear_rms_km, 20);
  s.tilt_deg = {0};
  s.correlation_s = 120;
  const PositioningStudy gm = positioning_study(s);
  EXPECT_NEAR(gm.stats[1].rms_km / gm.cells[1].linear_rms_km, 1, 0.15);
  EXPECT_GT(gm.stats[1].rms_km, 2 * white.stats[1].rms_km);  // correlated noise averages less
  s.trials = 0;
  EXPECT_THROW(positioning_study(s), std::invalid_argument);
}

// W16's M′ in every cell: with two sightings the equal-altitude circles are symmetric about the
// great circle through their two sub-solar points (δ, −GHA), so M′ is the truth reflected in that
// plane: written here with plain vectors on the sphere Eq. 17 uses. Then the hour at 0.1 Hz: M′ is
// ~11 000 km away, no trial ends nearer it, and Eq. 15's span is the window's Δβ.
TEST(PositioningStudy, EveryCellReportsTheMirrorRootAndEq15sSpan) {
  PositioningStudySettings s;
  s.times_s = {0, 3600};
  s.windows_s = {3600};
  s.noise_sd_deg = {0};
  s.tilt_deg = {0};
  s.baseline_noise_sd_deg = 0;
  s.trials = 2;
  const PositioningStudy two = positioning_study(s);
  const auto unit = [](double lat_deg, double lon_deg) {
    const double la = lat_deg * std::numbers::pi / 180, lo = lon_deg * std::numbers::pi / 180;
    return Vec3{std::cos(la) * std::cos(lo), std::cos(la) * std::sin(lo), std::sin(la)};
  };
  Vec3 sub[2];
  for (int k = 0; k < 2; ++k) {
    const SunPosition p = sun_position(s.first.plus_seconds(s.times_s[static_cast<std::size_t>(k)]), s.site, s.sun);
    sub[k] = unit(p.declination_deg, -p.gha_deg);
  }
  const Vec3 n = vec3::unit(vec3::cross(sub[0], sub[1]));
  const Vec3 x = unit(s.site.lat_deg, s.site.lon_deg);
  const Vec3 m = vec3::sub(x, vec3::mul(n, 2 * vec3::dot(n, x)));
  const double lat = std::asin(m[2]) * 180 / std::numbers::pi, lon = std::atan2(m[1], m[0]) * 180 / std::numbers::pi;
  for (const PositioningCell& c : two.cells) {
    // The fit's δ and GHA are topocentric: at M′ the zenith angles differ from the site's by up to
    // the solar parallax (8.8″ = 0.0024°), which Eq. 15 carries to M′ as 0.0024°·√2/sin 14.5° =
    // 0.014° (1.5 km).
    EXPECT_NEAR(c.mirror_lat_deg, lat, 0.015) << c.index;
    EXPECT_NEAR(std::remainder(c.mirror_lon_deg - lon, 360.0), 0.0, 0.015) << c.index;
    EXPECT_NEAR(c.mirror_km, great_circle_km(lat, lon, s.site.lat_deg, s.site.lon_deg), 1.7) << c.index;
  }
  s.times_s.clear();
  for (int k = 0; k <= 360; ++k) s.times_s.push_back(10.0 * k);
  s.windows_s = {600, 3600};
  s.noise_sd_deg = {0.14};
  s.trials = 20;
  const PositioningStudy hour = positioning_study(s);
  for (std::size_t c = 0; c < hour.cells.size(); ++c) {
    EXPECT_GT(hour.cells[c].mirror_km, 5000) << c;
    EXPECT_EQ(hour.stats[c].wrong_root, 0) << c;
  }
  const PositioningCell& full = hour.cells[2];  // cells: windows 600 s, 3600 s (σ = 0), then σ = 0.14°
  ASSERT_EQ(full.factor, "noise");
  EXPECT_NEAR(full.delta_beta_deg, 14.54, 0.01);  // W16: β 201.0° → 215.5°
  // Eq. 15 over that span: 0.14°·√2/sin 14.54°·111.32 km/° = 87.8 km (spec §3.4 gives 85.2 km for 15°).
  EXPECT_NEAR(full.eq15_km, 0.14 * std::sqrt(2.0) / std::sin(14.54 * std::numbers::pi / 180) * 111.32, 0.1);
}

// fix.csv and heading.csv from the locate core: every column, the chosen root first.
TEST(Locate, WritesFixAndHeading) {
  std::vector<SunSighting> s;
  for (const UtcTime& t : window(3600, 60)) s.push_back({t, sun_in_camera(sun_position(t, kW16Site), 42.0), 1});
  const Location loc = locate(s, {28.6, 113.5, 0});
  polrig::test::TempDir dir("polrig_test_positioning_");
  const std::vector<double> truth(s.size(), 42.0);
  const auto files = report_location(dir.path(), loc, kW16Site, truth);
  EXPECT_EQ(files.size(), 2u);
  const polrig::test::Csv fix = polrig::test::read_csv(dir.path() / "fix.csv");
  ASSERT_EQ(fix.rows.size(), 2u);
  EXPECT_EQ(fix.rows[0][fix.col("root")], "chosen");
  EXPECT_EQ(fix.rows[1][fix.col("root")], "alternative");
  EXPECT_EQ(fix.rows[0][fix.col("termination")], "converged");
  EXPECT_LT(std::stod(fix.rows[0][fix.col("error_km")]), 1e-3);
  EXPECT_GT(std::stod(fix.rows[1][fix.col("error_km")]), 3000);
  const polrig::test::Csv h = polrig::test::read_csv(dir.path() / "heading.csv");
  ASSERT_EQ(h.rows.size(), s.size());
  EXPECT_EQ(h.rows[0][h.col("utc")], "2015-12-16T05:37:00Z");
  for (const auto& row : h.rows) EXPECT_LT(std::abs(std::stod(row[h.col("heading_error_deg")])), 1e-6);
  // Without a truth: nan.
  polrig::test::TempDir bare("polrig_test_positioning_");
  report_location(bare.path(), loc);
  const polrig::test::Csv f2 = polrig::test::read_csv(bare.path() / "fix.csv");
  EXPECT_EQ(f2.rows[0][f2.col("error_km")], "nan");
  EXPECT_THROW(report_location(bare.path(), loc, kW16Site, {1.0}), std::invalid_argument);
}

}  // namespace
