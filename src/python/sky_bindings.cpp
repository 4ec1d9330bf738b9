// polrig.Sky, the sun over arrays of times, `sky table`, all-sky maps, the outdoor drift
// corrections and the spectral model of kd (docs/python.md §6). Frames and senses are sky/'s
// (spec sky-and-compasses.md §0): ENU; geographic azimuths from north towards east (clockwise seen
// from above); AoP in the view's local meridian frame, from e_θ (down the meridian) towards e_φ.
#include <cmath>
#include <optional>
#include <string>
#include <utility>
#include <vector>

#include <fmt/format.h>
#include <pybind11/stl.h>
#include <tbb/parallel_for.h>

#include "bindings.h"
#include "convert.h"
#include "polrig/io/exr.h"
#include "polrig/io/measured.h"
#include "polrig/io/rig_yaml.h"
#include "polrig/io/spectrum_csv.h"
#include "polrig/rig/error.h"
#include "polrig/sky/drift.h"
#include "polrig/sky/rayleigh.h"
#include "polrig/sky/sky.h"
#include "polrig/sky/sky_map.h"
#include "polrig/sky/sun.h"
#include "polrig/sky/berry_fit.h"
#include "polrig/sky/neutral_points.h"
#include "polrig/sky/sun_rows.h"
#include "polrig/sky/vector_rt_sky.h"
#include "polrig/source/sky_settings.h"
#include "polrig/source/source.h"
#include "polrig/spectral/kd.h"
#include "polrig/spectral/sources.h"
#include "records.h"
#include "rig_handle.h"
#include "sky_args.h"

namespace polrig::python {
using namespace pybind11::literals;

namespace {

struct SunPositionsTag {};
struct SkyLightTag {};
struct SkyMapTag {};
struct SkyTableTag {};
struct NeutralPointsTag {};
struct BerryFitTag {};
struct DriftTag {};
struct SpectralKdTag {};
struct KdSpectraTag {};

// The Python Sky: a sky (site, time, sun settings, model) and its sun at that time.
struct PySky {
  Sky sky;
  SunPosition sun;
  explicit PySky(const Sky& s) : sky(s), sun(sun_position(s.first_stop, s.site, s.sun)) {}
};

std::string radiance_name(SkyRadiance r) { return std::string(sky_radiance_name(r)); }

// The sun's position and its ENU unit vector as a record of arrays of `shape`.
Record sun_record(const std::vector<SunPosition>& suns, const std::vector<py::ssize_t>& shape) {
  const std::size_t n = suns.size();
  std::vector<double> az(n), el(n), zen(n), dec(n), gha(n), lha(n), enu(3 * n);
  for (std::size_t i = 0; i < n; ++i) {
    const SunPosition& s = suns[i];
    az[i] = s.azimuth_deg, el[i] = s.elevation_deg, zen[i] = s.zenith_deg;
    dec[i] = s.declination_deg, gha[i] = s.gha_deg, lha[i] = s.lha_deg;
    const Vec3 v = sun_direction_enu(s);
    for (int k = 0; k < 3; ++k) enu[3 * i + static_cast<std::size_t>(k)] = v[static_cast<std::size_t>(k)];
  }
  std::vector<py::ssize_t> shape3 = shape;
  shape3.push_back(3);
  Record r;
  r.add("azimuth_deg", take(std::move(az), shape));
  r.add("elevation_deg", take(std::move(el), shape));
  r.add("zenith_deg", take(std::move(zen), shape));
  r.add("declination_deg", take(std::move(dec), shape));
  r.add("gha_deg", take(std::move(gha), shape));
  r.add("lha_deg", take(std::move(lha), shape));
  r.add("enu", take(std::move(enu), shape3));
  return r;
}

// Viewing directions broadcast together, in the ranges of `sky table`'s columns.
Broadcast view_directions(const py::object& az, const py::object& el) {
  Broadcast b = broadcast({{az, "view_az_deg"}, {el, "view_el_deg"}});
  check_range(b.values[0], "view_az_deg", -360, 360, "degrees, geographic: from north towards east");
  check_range(b.values[1], "view_el_deg", -90, 90, "degrees above the horizon");
  return b;
}

std::vector<SkyLight> lights_of(const PySky& s, const Broadcast& b) {
  py::gil_scoped_release release;
  return sky_light_toward(s.sun, b.values[0], b.values[1], s.sky.model);
}

Record light_record(const std::vector<SkyLight>& lights, const std::vector<py::ssize_t>& shape) {
  const std::size_t n = lights.size();
  std::vector<double> L(n), dop(n), aop(n), e(3 * n);
  for (std::size_t i = 0; i < n; ++i) {
    L[i] = lights[i].radiance, dop[i] = lights[i].dop, aop[i] = lights[i].aop_deg;
    for (std::size_t k = 0; k < 3; ++k) e[3 * i + k] = lights[i].e_vector[k];
  }
  std::vector<py::ssize_t> shape3 = shape;
  shape3.push_back(3);
  Record r;
  r.add("radiance", take(std::move(L), shape));
  r.add("dop", take(std::move(dop), shape));
  r.add("aop_deg", take(std::move(aop), shape));
  r.add("e_vector", take(std::move(e), shape3));
  return r;
}

py::array_t<float> image(std::vector<float>&& layer, int size) {
  return take(std::move(layer), {size, size});
}

constexpr const char* kSunFields =
    "azimuth_deg: A_s, geographic, from north towards east (clockwise seen from above), [0, 360).\n"
    "elevation_deg: h_s (refracted when refraction=True); zenith_deg: 90 - h_s.\n"
    "declination_deg: apparent topocentric declination; gha_deg, lha_deg: Greenwich and local hour "
    "angles, westwards, [0, 360).\n"
    "enu: the unit vector to the sun in ENU (x east, y north, z up), shape (..., 3).";

}  // namespace

void bind_sky(py::module_& m) {
  // ---- result classes
  py::class_<SunPosition>(m, "SunPosition",
                          (std::string("The apparent topocentric position of the sun (ERFA), degrees.\n\n") +
                           kSunFields).c_str())
      .def_readonly("azimuth_deg", &SunPosition::azimuth_deg,
                    "A_s in degrees, geographic: from north towards east (clockwise seen from above), [0, 360).")
      .def_readonly("elevation_deg", &SunPosition::elevation_deg, "h_s in degrees (refracted when asked).")
      .def_readonly("zenith_deg", &SunPosition::zenith_deg, "θ_s = 90° − h_s, degrees.")
      .def_readonly("declination_deg", &SunPosition::declination_deg, "δ, apparent topocentric, degrees.")
      .def_readonly("gha_deg", &SunPosition::gha_deg, "Greenwich hour angle, westwards, [0, 360) degrees.")
      .def_readonly("lha_deg", &SunPosition::lha_deg, "Local hour angle GHA + λ, westwards, [0, 360) degrees.")
      .def_property_readonly("enu", [](const SunPosition& s) { return to_array(sun_direction_enu(s)); },
                             "The unit vector to the sun in ENU (x east, y north, z up), shape (3,).")
      .def("to_dict", [](const SunPosition& s) {
        return py::dict("azimuth_deg"_a = s.azimuth_deg, "elevation_deg"_a = s.elevation_deg,
                        "zenith_deg"_a = s.zenith_deg, "declination_deg"_a = s.declination_deg,
                        "gha_deg"_a = s.gha_deg, "lha_deg"_a = s.lha_deg);
      }, "The six angles as a dict (degrees), as sun.yaml writes them.")
      .def("__repr__", [](const SunPosition& s) {
        return fmt::format("<polrig.SunPosition: azimuth_deg {}, elevation_deg {}, zenith_deg {}, "
                           "declination_deg {}, gha_deg {}, lha_deg {}>", s.azimuth_deg,
                           s.elevation_deg, s.zenith_deg, s.declination_deg, s.gha_deg, s.lha_deg);
      });

  bind_record<SunPositionsTag>(m, "SunPositions",
      "The sun at many (time, site) rows: arrays of the broadcast shape of utc and site.", {
      {"azimuth_deg", "A_s in degrees, from north towards east (clockwise seen from above), [0, 360)."},
      {"elevation_deg", "h_s in degrees (refracted when refraction=True)."},
      {"zenith_deg", "θ_s = 90° − h_s, degrees."},
      {"declination_deg", "δ, apparent topocentric, degrees."},
      {"gha_deg", "Greenwich hour angle, westwards, [0, 360) degrees."},
      {"lha_deg", "local hour angle, westwards, [0, 360) degrees."},
      {"enu", "unit vectors to the sun in ENU (x east, y north, z up), shape (..., 3)."}});
  bind_record<SkyLightTag>(m, "SkyLight",
      "The sky along viewing directions (sky/rayleigh.h: single scattering, or the vector-RT sky).", {
      {"radiance", "relative radiance (1 at the zenith; 1 everywhere for radiance='uniform'; the vector-RT "
                   "sky's diffuse radiance over the zenith's)."},
      {"dop", "degree of linear polarization: P = P_max·sin²γ/(1 + cos²γ), γ the view-sun angle, or the "
              "vector-RT sky's √(Q² + U²)/I."},
      {"aop_deg", "angle of polarization χ in degrees, [0, 180), in the view's local meridian frame: "
                  "from e_θ (down the meridian, towards the horizon) towards e_φ (along the almucantar, "
                  "anticlockwise seen from above); at the zenith, the limit along view_az_deg."},
      {"e_vector", "the E-vector in ENU, shape (..., 3): e = (s × v)/|s × v| (single scattering), or "
                   "cos χ·e_θ + sin χ·e_φ (the vector-RT sky); zero where undefined (unpolarized)."}});
  bind_record<NeutralPointsTag>(m, "NeutralPoints",
      "`polrig sky neutral-points`: the neutral points on the solar meridian for each sun elevation "
      "(sky/neutral_points.h), arrays of the elevations' shape; NaN where a point is absent or below "
      "the horizon (everywhere for a single-scattering sky).", {
      {"sun_el_deg", "the sun's elevation, degrees."},
      {"babinet_deg", "the Babinet point's angular distance above the sun along the meridian, degrees."},
      {"brewster_deg", "the Brewster point's distance below the sun, degrees."},
      {"arago_deg", "the Arago point's distance above the antisun, degrees."}});
  bind_record<BerryFitTag>(m, "BerryFit",
      "`polrig sky berry-fit`: Berry's two distances fitted to the vector-RT sky for each sun elevation "
      "(sky/berry_fit.h), arrays of the elevations' shape, berry_fit.csv's columns.", {
      {"sun_el_deg", "the sun's elevation, degrees."},
      {"babinet_deg", "the fitted Babinet distance above the sun, degrees."},
      {"brewster_deg", "the fitted Brewster distance below the sun, degrees."},
      {"aop_rms_deg", "Berry's AoP less the exact sky's, rms over the views with exact DoP ≥ 0.02, degrees."},
      {"aop_p95_deg", "its 95th percentile of |ΔAoP|, degrees."},
      {"single_aop_rms_deg", "single scattering's AoP less the exact sky's, rms over the same views, degrees."},
      {"views", "the views the fit used (int)."},
      {"iterations", "Levenberg–Marquardt's Jacobian evaluations (int)."},
      {"status", "list of str: Eigen's LevenbergMarquardtSpace::Status for each fit."}});
  bind_record<SkyMapTag>(m, "SkyMap",
      "An all-sky map, an equidistant fisheye seen from below (zenith at the centre, north up, east "
      "LEFT, r = (θ/90°)·size/2): the layers of `polrig sky`'s sky.exr as float32 (size, size) "
      "arrays, row-major, top row first; 0 outside the horizon circle.", {
      {"S0", "radiance (relative), float32 (size, size)."},
      {"S1", "Stokes S1 with reference axis e_θ of each pixel's direction, float32 (size, size)."},
      {"S2", "Stokes S2 (angles from e_θ towards e_φ), float32 (size, size)."},
      {"aop_deg", "AoP χ in degrees, [0, 180), local meridian frame (sky.exr's AoP layer)."},
      {"dop", "degree of linear polarization (sky.exr's DoP layer)."},
      {"inside", "1 inside the horizon circle, 0 outside (sky.exr's A layer)."},
      {"utc", "the map's time, ISO 8601 with Z."},
      {"sun", "the sun at that time (polrig.SunPosition), as sun.yaml."}});
  bind_record<SkyTableTag>(m, "SkyTable",
      "`polrig sky table`'s added columns for every row: arrays of the broadcast shape.", {
      {"sun_az_deg", "the sun's azimuth, degrees, from north towards east, [0, 360)."},
      {"sun_el_deg", "the sun's elevation, degrees."},
      {"dop", "degree of linear polarization along the view."},
      {"aop_deg", "AoP χ, degrees, [0, 180), in the view's local meridian frame (from e_θ towards e_φ)."}});
  bind_record<DriftTag>(m, "DriftCorrections",
      "Per-stop sun-drift corrections of an outdoor calibration (sky/drift.h); (N,) arrays for every mode: zeros and ones for 'none'.", {
      {"dtheta_deg", "added to each stop's table angle, degrees, polrig's sensor frame "
                     "(anticlockwise seen from above): −(A_s(t_k) − A_s(t_0)) wrapped to (−180, 180]."},
      {"d_ratio", "multiplies the fitted d: d(t_k)/d(t_0) ('per-stop'), linear in time ('linear'); "
                  "1 for 'none' and 'angle'."}});
  bind_record<SpectralKdTag>(m, "SpectralKd",
      "`polrig spectral kd`: kd.csv's columns, one row per channel (shape (6,)), and `spectra` "
      "(spectra.csv's columns).", {
      {"channel", "channel number 1..6."},
      {"tau_m_scale", "the channel's factor on the film's leakage τm."},
      {"d_eff_lamp", "effective degree under the lamp (a blackbody)."},
      {"kd_lamp", "kd = d_eff − 1 under the lamp."},
      {"d_eff_sky", "effective degree under the Rayleigh sky."},
      {"kd_sky", "kd under the sky."},
      {"kd_sky_minus_lamp", "kd_sky − kd_lamp."},
      {"spectra", "polrig.KdSpectra: the spectra on a 1 nm grid (spectra.csv)."}});
  bind_record<KdSpectraTag>(m, "KdSpectra",
      "spectra.csv of `polrig spectral kd`: on a 1 nm grid over the response's band.", {
      {"wavelength_nm", "wavelength, nm."},
      {"tau_M", "film transmittance along its axis."},
      {"tau_m", "film transmittance across its axis."},
      {"film_d", "(τM − τm)/(τM + τm); NaN where no light passes (the CLI writes nan)."},
      {"response", "filter × photodiode responsivity (as in the file)."},
      {"lamp_weight", "lamp spectrum × response, normalised to 1 at its peak."},
      {"sky_weight", "sky spectrum × response, normalised to 1 at its peak."}});

  // ---- Sky
  py::class_<PySky>(m, "Sky",
      "A sky: where and when it is seen, how the sun is computed and the single-scattering "
      "Rayleigh model (`polrig sky`'s options; a rig's `sky:` block through Sky.from_rig).\n\n"
      "Frames (spec sky-and-compasses.md §0): ENU (x east, y north, z up); azimuths geographic, "
      "from north towards east (clockwise seen from above); elevations above the horizon; AoP in the "
      "view's local meridian frame, from e_θ (down the meridian) towards e_φ.")
      .def(py::init([](const py::object& site, const py::object& utc, double p_max,
                       const std::string& radiance, bool refraction, double ut1_minus_utc_s,
                       const py::object& p_max_table, const std::string& model, const py::object& tau_rayleigh,
                       double wavelength_nm, double pressure_hPa, double depolarization, double ground_albedo,
                       int streams, const py::object& babinet_deg, const py::object& brewster_deg,
                       double aerosol_tau, double aerosol_ssa, const py::object& aerosol_phase_matrix,
                       const std::string& direct_beam) {
             Sky s;
             s.site = site_of(site, "site");
             s.first_stop = utc_time(utc, "utc");
             check_option(p_max, "p_max", 1e-6, 1.0, "");
             s.model.P_max.constant = p_max;
             s.model.radiance = radiance_of(radiance);
             s.sun.refraction = refraction;
             check_option(ut1_minus_utc_s, "ut1_minus_utc_s", -1, 1, "s");
             s.sun.ut1_minus_utc_s = ut1_minus_utc_s;
             s.model.P_max.table = p_max_table_of(p_max_table);
             check_sky_model(s.model);
             // The vector-RT and Berry skies through the rig's own resolution of its keys (sky_settings.h).
             const auto text = [](const py::object& v) {
               return py::isinstance<py::str>(v) ? v.cast<std::string>() : fmt::format("{}", v.cast<double>());
             };
             SkySettings keys;
             keys.model = model;
             keys.tau_rayleigh = text(tau_rayleigh);
             keys.wavelength_nm = wavelength_nm, keys.pressure_hPa = pressure_hPa;
             keys.rt.depolarization = depolarization, keys.rt.ground_albedo = ground_albedo, keys.rt.streams = streams;
             keys.berry_babinet_deg = text(babinet_deg), keys.berry_brewster_deg = text(brewster_deg);
             check_option(aerosol_tau, "aerosol_tau", 0, 100, "");
             if (!(aerosol_ssa > 0 && aerosol_ssa <= 1))
               throw py::value_error(fmt::format("aerosol_ssa: expected a single-scattering albedo in (0, 1], got {}", aerosol_ssa));
             keys.rt.aerosol.tau = aerosol_tau, keys.rt.aerosol.ssa = aerosol_ssa;
             keys.direct_beam = direct_beam;
             if (!aerosol_phase_matrix.is_none())
               keys.aerosol_phase_matrix = py::str(aerosol_phase_matrix).cast<std::string>();
             if (!parse_sky_kind(model))
               throw py::value_error("model: expected 'single-scattering', 'vector-rt' or 'berry', got '" + model + "'");
             try {
               keys.resolve_kind(s.model);
             } catch (const SourceSettingError& e) {  // the rig key's name → the argument's
               std::string arg = e.key.substr(e.key.rfind('.') + 1);
               if (e.key.starts_with("sky.rt.aerosol.")) arg = "aerosol_" + arg;
               throw py::value_error(arg + ": " + e.what());
             }
             return PySky(s);
           }),
           "site"_a = py::make_tuple(38.879167, 121.543889), "utc"_a = "2018-11-16T08:09:40Z",
           "p_max"_a = 0.7, py::kw_only(), "radiance"_a = "uniform", "refraction"_a = false,
           "ut1_minus_utc_s"_a = 0.0, "p_max_table"_a = py::none(), "model"_a = "single-scattering",
           "tau_rayleigh"_a = py::float_(0.1), "wavelength_nm"_a = 550.0, "pressure_hPa"_a = 1013.25,
           "depolarization"_a = 0.0279, "ground_albedo"_a = 0.0, "streams"_a = 32,
           "babinet_deg"_a = "fit", "brewster_deg"_a = "fit", "aerosol_tau"_a = 0.0, "aerosol_ssa"_a = 1.0,
           "aerosol_phase_matrix"_a = py::none(), "direct_beam"_a = "plane-parallel",
           "A sky at one time and place (the defaults: W19 Outdoor1's first stop on its roof in "
           "Dalian).\n\n"
           "site: (lat_deg, lon_deg) or (lat_deg, lon_deg, height_m): latitude in [-90, 90] "
           "(north positive), longitude in [-180, 180] (east positive), height above the WGS-84 "
           "ellipsoid in m.\n"
           "utc: the time: an ISO 8601 string with Z, an aware datetime or a numpy.datetime64.\n"
           "p_max: the maximum degree of polarization P_max, (0, 1] (checked in [1e-06, 1]).\n"
           "radiance: 'uniform', 'rayleigh' or 'cie-clear' (sky/rayleigh.h).\n"
           "refraction: refract the sun (Saemundsson, 1010 hPa, 10 °C); False: geometric.\n"
           "ut1_minus_utc_s: UT1 − UTC in seconds, [-1, 1].\n"
           "p_max_table: None, or an (N, 2) array of (sun elevation in degrees, rising; P_max), "
           "interpolated linearly and held beyond its ends; replaces p_max.\n"
           "model: 'single-scattering' (p_max, radiance) or 'vector-rt', the exact polarized Rayleigh "
           "sky (docs/physics.md §21; p_max and radiance unused): tau_rayleigh, a number in (0, 100] or "
           "'bodhaine' (Bodhaine et al. 1999 at wavelength_nm and pressure_hPa); depolarization ρ in "
           "[0, 0.5); ground_albedo in [0, 1]; streams even in [4, 128]. The rig keys sky.model and "
           "sky.rt.* (docs/formats.md §1.10). Its sun must stand at 2° or higher.\n"
           "model='berry': Berry et al. 2004's sky (docs/physics.md §22) with p_max and radiance: "
           "babinet_deg and brewster_deg, each a distance in [0, 90) degrees along the solar meridian "
           "or 'fit' (fitted to the vector-RT sky of tau_rayleigh, depolarization, ground_albedo, "
           "streams; its sun at 2° or higher): the rig keys sky.berry.*.\n"
           "aerosol_tau in [0, 100], aerosol_ssa in (0, 1], aerosol_phase_matrix (a path, str or "
           "os.PathLike; docs/formats.md §6.22): an aerosol mixed with the air (docs/physics.md §24; the "
           "rig keys sky.rt.aerosol.*), its phase matrix truncated by δ-M with the single-scattering "
           "correction; tau_rayleigh may then be 0.\n"
           "direct_beam: 'plane-parallel' (the sun at 2° or higher) or 'pseudo-spherical' (the Chapman "
           "air mass; the sun at 1° or higher): the rig key sky.rt.direct_beam.\n"
           "Raises ValueError naming the argument and value (the CLI's ranges; a site out of "
           "range included), and for a date outside ERFA's range.")
      .def_static("from_rig", [](const PyRig& r) {
             const std::optional<Sky> sky = rig_sky(r.rig());
             if (!sky) throw RigError(no_sky_message(r.rig(), r.loaded.origin));
             return PySky(*sky);
           }, "rig"_a,
           "The sky of a rig with source.model sky (its sky block: site, first stop, P_max or its "
           "table, radiance, refraction, UT1 − UTC), as `polrig sky RIG` uses it. Raises "
           "polrig.RigError for a rig without a sky.")
      .def_property_readonly("site", [](const PySky& s) {
             return py::make_tuple(s.sky.site.lat_deg, s.sky.site.lon_deg, s.sky.site.height_m);
           }, "(lat_deg, lon_deg, height_m): north and east positive, m above the ellipsoid.")
      .def_property_readonly("utc", [](const PySky& s) { return format_utc(s.sky.first_stop); },
                             "The sky's time, ISO 8601 with Z.")
      .def_property_readonly("p_max", [](const PySky& s) { return s.sky.model.P_max.constant; },
                             "The constant P_max (unused when p_max_table is given).")
      .def_property_readonly("p_max_table", [](const PySky& s) -> py::object {
             const auto& t = s.sky.model.P_max.table;
             if (t.empty()) return py::none();
             std::vector<double> v;
             for (const auto& [h, p] : t) v.insert(v.end(), {h, p});
             return take(std::move(v), {static_cast<py::ssize_t>(t.size()), 2});
           }, "None, or the (N, 2) table of (sun elevation in degrees, P_max).")
      .def_property_readonly("radiance", [](const PySky& s) { return radiance_name(s.sky.model.radiance); },
                             "The radiance model: 'uniform', 'rayleigh' or 'cie-clear'.")
      .def_property_readonly("model", [](const PySky& s) { return std::string(sky_kind_name(s.sky.model.kind)); },
                             "What the sky is: 'single-scattering', 'vector-rt' or 'berry'.")
      .def_property_readonly("tau_rayleigh", [](const PySky& s) -> py::object {
             if (!s.sky.model.vector_rt) return py::none();
             return py::float_(s.sky.model.vector_rt->settings().tau_rayleigh);
           }, "The vector-RT sky's Rayleigh optical depth (resolved, Bodhaine's if asked); None otherwise.")
      .def_property_readonly("aerosol_tau", [](const PySky& s) -> py::object {
             if (!s.sky.model.vector_rt) return py::none();
             return py::float_(s.sky.model.vector_rt->settings().aerosol.tau);
           }, "The vector-RT sky's aerosol optical depth (0: none); None for another sky.")
      .def("radiance_sr", [](const PySky& s, const py::object& az, const py::object& el, std::optional<int> threads) {
             if (!s.sky.model.vector_rt) throw py::value_error("radiance_sr: a single-scattering sky has no absolute radiance (model='vector-rt' has)");
             const Broadcast b = view_directions(az, el);
             ThreadLimit limit(threads);
             std::vector<SkyQuery> q(b.values[0].size());
             for (std::size_t i = 0; i < q.size(); ++i)
               q[i].sun = s.sun, q[i].view_az_deg = b.values[0][i], q[i].view_el_deg = b.values[1][i];
             std::vector<SkySample> samples;
             {
               py::gil_scoped_release release;
               samples = sky_along(q, s.sky.model);
             }
             std::vector<double> out(3 * q.size());
             for (std::size_t i = 0; i < q.size(); ++i)
               for (int k = 0; k < 3; ++k) out[3 * i + static_cast<std::size_t>(k)] = (*samples[i].absolute)(k);
             std::vector<py::ssize_t> shape = b.shape;
             shape.push_back(3);
             return take(std::move(out), shape);
           }, "view_az_deg"_a, "view_el_deg"_a, py::kw_only(), "threads"_a = py::none(),
           (std::string("The vector-RT sky's diffuse (I, Q, U) along viewing directions, vectorised: "
                        "L/E₀ in sr⁻¹ per unit extraterrestrial irradiance normal to the sun's beam, Q and U "
                        "in the view's meridian frame (χ = ½·atan2(U, Q)): `polrig sky table`'s I_sr, Q_sr, "
                        "U_sr. view_az_deg, view_el_deg as in Sky.light; returns shape S + (3,). Raises "
                        "ValueError for a single-scattering sky.\n") + kThreadsDoc).c_str())
      .def("neutral_points", [](const PySky& s, const py::object& sun_el, std::optional<int> threads) {
             Broadcast b = broadcast({{sun_el, "sun_el_deg"}});
             check_range(b.values[0], "sun_el_deg", min_sun_elevation_deg(s.sky.model), 90, "degrees above the horizon");
             ThreadLimit limit(threads);
             const std::vector<double>& h = b.values[0];
             std::vector<NeutralPoints> p(h.size());
             {
               py::gil_scoped_release release;
               tbb::parallel_for(std::size_t{0}, h.size(), [&](std::size_t k) {
                 p[k] = sky_neutral_points(s.sky.model, h[k]);
               });
             }
             const double nan = std::nan("");
             std::vector<double> el(h.size()), ba(h.size()), br(h.size()), ar(h.size());
             for (std::size_t k = 0; k < h.size(); ++k)
               el[k] = h[k], ba[k] = p[k].babinet_deg.value_or(nan), br[k] = p[k].brewster_deg.value_or(nan),
               ar[k] = p[k].arago_deg.value_or(nan);
             Record r;
             r.add("sun_el_deg", take(std::move(el), b.shape));
             r.add("babinet_deg", take(std::move(ba), b.shape));
             r.add("brewster_deg", take(std::move(br), b.shape));
             r.add("arago_deg", take(std::move(ar), b.shape));
             return RecordOf<NeutralPointsTag>(std::move(r));
           }, "sun_el_deg"_a, py::kw_only(), "threads"_a = py::none(),
           (std::string("The neutral points of this sky's model on its solar meridian at the sun elevations "
                        "sun_el_deg (array-like, degrees; the vector-RT sky and a fitted Berry sky need 2 or more): "
                        "polrig.NeutralPoints, what `polrig sky neutral-points` writes (its site and time are "
                        "not used). Raises ValueError for an elevation out of range.\n") + kThreadsDoc).c_str())
      .def("berry_fit", [](const PySky& s, const py::object& sun_el, std::optional<int> threads) {
             std::shared_ptr<const VectorRtSky> exact = s.sky.model.vector_rt;
             if (!exact && s.sky.model.berry.fit) exact = vector_rt_sky(s.sky.model.berry.fit->sky().settings());
             if (!exact) throw py::value_error("berry_fit: this sky has no atmosphere to fit (model='vector-rt', or 'berry' with a distance 'fit', has)");
             Broadcast b = broadcast({{sun_el, "sun_el_deg"}});
             check_range(b.values[0], "sun_el_deg", VectorRtSky::kMinSunElevationDeg, 90, "degrees above the horizon");
             ThreadLimit limit(threads);
             const std::vector<double>& h = b.values[0];
             std::vector<BerryFitResult> f(h.size());
             {
               py::gil_scoped_release release;
               tbb::parallel_for(std::size_t{0}, h.size(), [&](std::size_t k) { f[k] = fit_berry(exact->for_sun(h[k]), h[k]); });
             }
             const std::size_t n = h.size();
             std::vector<double> el(n), ba(n), br(n), rms(n), p95(n), single(n);
             std::vector<long long> views(n), iterations(n);
             py::list status;
             for (std::size_t k = 0; k < n; ++k) {
               el[k] = h[k], ba[k] = f[k].distances.babinet_deg, br[k] = f[k].distances.brewster_deg;
               rms[k] = f[k].summary.aop_rms_deg, p95[k] = f[k].summary.aop_p95_deg, single[k] = f[k].summary.single_aop_rms_deg;
               views[k] = f[k].summary.views, iterations[k] = f[k].summary.iterations;
               status.append(f[k].summary.status);
             }
             Record r;
             r.add("sun_el_deg", take(std::move(el), b.shape));
             r.add("babinet_deg", take(std::move(ba), b.shape));
             r.add("brewster_deg", take(std::move(br), b.shape));
             r.add("aop_rms_deg", take(std::move(rms), b.shape));
             r.add("aop_p95_deg", take(std::move(p95), b.shape));
             r.add("single_aop_rms_deg", take(std::move(single), b.shape));
             r.add("views", take(std::move(views), b.shape));
             r.add("iterations", take(std::move(iterations), b.shape));
             r.add("status", status);
             return RecordOf<BerryFitTag>(std::move(r));
           }, "sun_el_deg"_a, py::kw_only(), "threads"_a = py::none(),
           (std::string("Berry's distances fitted to this sky's vector-RT sky (its own, or the one a fitted Berry "
                        "sky is fitted to) at the sun elevations sun_el_deg (array-like, degrees, 2 to 90): "
                        "polrig.BerryFit, what `polrig sky berry-fit` writes. Raises ValueError for a sky "
                        "without an atmosphere or an elevation out of range.\n") + kThreadsDoc).c_str())
      .def_property_readonly("refraction", [](const PySky& s) { return s.sky.sun.refraction; },
                             "Whether the sun is refracted.")
      .def_property_readonly("ut1_minus_utc_s", [](const PySky& s) { return s.sky.sun.ut1_minus_utc_s; },
                             "UT1 − UTC, seconds.")
      .def("sun", [](const PySky& s) { return s.sun; },
           "The sun at the sky's time and site (ERFA's apparent topocentric place): a "
           "polrig.SunPosition (degrees; its .enu is the unit vector to the sun in ENU). The "
           "values of `polrig sky`'s sun.yaml.")
      .def("light", [](const PySky& s, const py::object& az, const py::object& el, std::optional<int> threads) {
             const Broadcast b = view_directions(az, el);
             ThreadLimit limit(threads);
             return RecordOf<SkyLightTag>(light_record(lights_of(s, b), b.shape));
           }, "view_az_deg"_a, "view_el_deg"_a, py::kw_only(), "threads"_a = py::none(),
           (std::string("The sky along viewing directions (where the light comes from), vectorised.\n\n"
           "view_az_deg: geographic azimuth of the view, degrees, from north towards east "
           "(clockwise seen from above), in [-360, 360]; view_el_deg: its elevation above the "
           "horizon, degrees, in [-90, 90]. Both array-like, broadcast together to a shape S.\n"
           "Returns polrig.SkyLight: radiance, dop, aop_deg of shape S and e_vector of shape "
           "S + (3,) (ENU). aop_deg is χ in the view's local meridian frame: from e_θ (down the "
           "meridian, towards the horizon) towards e_φ = ẑ × v/|ẑ × v| (anticlockwise seen from "
           "above), [0, 180); at the zenith the frame is the limit along view_az_deg. The values "
           "`polrig sky table` writes for the same time, site and view.\n") + kThreadsDoc).c_str())
      .def("stokes", [](const PySky& s, const py::object& az, const py::object& el, std::optional<int> threads) {
             const Broadcast b = view_directions(az, el);
             ThreadLimit limit(threads);
             const std::vector<SkyLight> lights = lights_of(s, b);
             std::vector<double> out(4 * lights.size());
             for (std::size_t i = 0; i < lights.size(); ++i) {
               const Stokes st = sky_stokes(lights[i]);
               for (std::size_t k = 0; k < 4; ++k) out[4 * i + k] = st[static_cast<Eigen::Index>(k)];
             }
             std::vector<py::ssize_t> shape = b.shape;
             shape.push_back(4);
             return take(std::move(out), shape);
           }, "view_az_deg"_a, "view_el_deg"_a, py::kw_only(), "threads"_a = py::none(),
           (std::string("The Stokes vectors (S0, S1, S2, S3) of the sky along viewing directions, vectorised.\n\n"
           "view_az_deg, view_el_deg: as in Sky.light (degrees; geographic azimuth from north "
           "towards east; elevation above the horizon), broadcast to a shape S.\n"
           "Returns a float64 array of shape S + (4,). The reference axis is e_θ of the view's "
           "local meridian frame (down the meridian, towards the horizon), angles from e_θ towards "
           "e_φ (anticlockwise seen from above): S0 = L, S1 = L·P·cos 2χ, S2 = L·P·sin 2χ, S3 = 0 "
           "(sky/rayleigh.h's sky_stokes; L relative, 1 at the zenith).\n") + kThreadsDoc).c_str())
      .def("map", [](const PySky& s, int size, std::optional<int> threads) {
             ThreadLimit limit(threads);
             SkyMap map;
             {
               py::gil_scoped_release release;
               map = sky_map(s.sky, size);
             }
             Record r;
             r.add("S0", image(std::move(map.S0), size));
             r.add("S1", image(std::move(map.S1), size));
             r.add("S2", image(std::move(map.S2), size));
             r.add("aop_deg", image(std::move(map.aop_deg), size));
             r.add("dop", image(std::move(map.dop), size));
             r.add("inside", image(std::move(map.inside), size));
             r.add("utc", py::str(format_utc(map.time)));
             r.add("sun", py::cast(map.sun));
             return RecordOf<SkyMapTag>(std::move(r));
           }, "size"_a = 1024, py::kw_only(), "threads"_a = py::none(),
           (std::string("The all-sky map `polrig sky` writes to sky.exr, as float32 (size, size) "
                        "arrays, bit for bit: an equidistant fisheye seen from below (zenith at the "
                        "centre, north up, east LEFT, radius (θ/90°)·size/2 pixels; pixel (i, j) "
                        "column i from the left, row j from the top).\n\n"
                        "size: width = height in pixels, [2, 8192].\n") + kThreadsDoc +
            "\nReturns polrig.SkyMap (S0, S1, S2 with reference axis e_θ; aop_deg; dop; inside; "
            "utc; sun).").c_str())
      .def("__repr__", [](const PySky& s) {
        if (s.sky.model.vector_rt) {
          const VectorRtSettings& v = s.sky.model.vector_rt->settings();
          return fmt::format("<polrig.Sky: site ({}, {}, {}), utc {}, model vector-rt, tau_rayleigh {}, "
                             "depolarization {}, ground_albedo {}, streams {}>", s.sky.site.lat_deg,
                             s.sky.site.lon_deg, s.sky.site.height_m, format_utc(s.sky.first_stop),
                             v.tau_rayleigh, v.depolarization, v.ground_albedo, v.streams);
        }
        return fmt::format("<polrig.Sky: site ({}, {}, {}), utc {}, p_max {}, radiance {}, "
                           "refraction {}, ut1_minus_utc_s {}>", s.sky.site.lat_deg,
                           s.sky.site.lon_deg, s.sky.site.height_m, format_utc(s.sky.first_stop),
                           s.sky.model.P_max.constant, radiance_name(s.sky.model.radiance),
                           s.sky.sun.refraction ? "True" : "False", s.sky.sun.ut1_minus_utc_s);
      });

  // ---- the sun over arrays
  m.def("sun_position", [](const py::object& utc, const py::object& site, bool refraction,
                           double ut1_minus_utc_s, std::optional<int> threads, const py::object& progress) {
        SunSettings settings;
        settings.refraction = refraction;
        check_option(ut1_minus_utc_s, "ut1_minus_utc_s", -1, 1, "s");
        settings.ut1_minus_utc_s = ut1_minus_utc_s;
        const std::vector<UtcTime> times = utc_times(utc, "utc");
        const SiteArrays sites = site_arrays(site, "site");
        const Broadcast b = broadcast({{utc_index(utc), "utc"}, {sites.lat, "site[..., 0] (lat_deg)"},
                                       {sites.lon, "site[..., 1] (lon_deg)"},
                                       {sites.height, "site[..., 2] (height_m)"}});
        check_site_rows(b.values[1], b.values[2], b.values[3], "site");
        std::vector<SunRow> rows(b.size);
        for (std::size_t i = 0; i < b.size; ++i)
          rows[i] = {times[static_cast<std::size_t>(b.values[0][i])],
                     {b.values[1][i], b.values[2][i], b.values[3][i]}};
        const Progress p = progress_from(progress);
        ThreadLimit limit(threads);
        std::vector<SunPosition> suns;
        {
          py::gil_scoped_release release;
          suns = sun_rows_or_error(rows, settings, p, "utc");
        }
        return RecordOf<SunPositionsTag>(sun_record(suns, b.shape));
      }, "utc"_a, "site"_a = py::make_tuple(38.879167, 121.543889), py::kw_only(),
      "refraction"_a = false, "ut1_minus_utc_s"_a = 0.0, "threads"_a = py::none(),
      "progress"_a = py::none(),
      (std::string("The sun's apparent topocentric position (ERFA) at many times and sites, as "
                   "`polrig heading` and `polrig sky table` compute it (sky/sun_rows.h: the rows of "
                   "one site are interpolated along a SunTrack, < 1e-6°, when they are many; else "
                   "each is exact).\n\n"
                   "utc: one time or an array of times (ISO strings with Z, aware datetimes, "
                   "numpy.datetime64); site: (lat_deg, lon_deg[, height_m]) or an array of them, "
                   "shape (..., 2) or (..., 3): latitude in [-90, 90] north positive, longitude in "
                   "[-180, 180] east positive, height in m. utc's shape and site's leading shape "
                   "broadcast to the result's shape S.\n"
                   "refraction: refract the sun (1010 hPa, 10 °C); ut1_minus_utc_s: UT1 − UTC in "
                   "s, [-1, 1].\n") + kThreadsDoc + "\n" + kProgressDoc +
       "\nReturns polrig.SunPositions: azimuth_deg (from north towards east, clockwise seen from "
       "above), elevation_deg, zenith_deg, declination_deg, gha_deg, lha_deg (westwards) of shape S, "
       "enu of shape S + (3,). Raises ValueError naming the argument and element.").c_str());

  m.def("sky_table", [](const py::object& utc, const py::object& lat, const py::object& lon,
                        const py::object& az, const py::object& el, double p_max, bool refraction,
                        double ut1_minus_utc_s, std::optional<int> threads, const py::object& progress) {
        Sky sky;
        check_option(p_max, "p_max", 1e-6, 1.0, "");
        sky.model.P_max.constant = p_max;
        sky.sun.refraction = refraction;
        check_option(ut1_minus_utc_s, "ut1_minus_utc_s", -1, 1, "s");
        sky.sun.ut1_minus_utc_s = ut1_minus_utc_s;
        const std::vector<UtcTime> times = utc_times(utc, "utc");
        const char* names[] = {"utc", "lat_deg", "lon_deg", "view_az_deg", "view_el_deg"};
        const Broadcast b = broadcast({{utc_index(utc), names[0]}, {lat, names[1]}, {lon, names[2]},
                                       {az, names[3]}, {el, names[4]}});
        for (std::size_t k = 1; k <= 4; ++k) check_input(b.values[k], names[k], sky_query_range(names[k]));
        std::vector<SkyQuery> queries(b.size);
        for (std::size_t i = 0; i < b.size; ++i)
          queries[i] = {{times[static_cast<std::size_t>(b.values[0][i])], {b.values[1][i], b.values[2][i], 0}},
                        b.values[3][i], b.values[4][i]};
        const Progress p = progress_from(progress);
        ThreadLimit limit(threads);
        std::vector<SkySample> samples;
        {
          py::gil_scoped_release release;
          try {
            samples = sky_along(queries, sky.model, sky.sun, p);
          } catch (const SunRowError& e) {
            throw py::value_error(fmt::format("utc (element {}): {}", e.row, e.what()));
          }
        }
        std::vector<double> az_s(b.size), el_s(b.size), dop(b.size), aop(b.size);
        for (std::size_t i = 0; i < b.size; ++i) {
          az_s[i] = samples[i].sun.azimuth_deg, el_s[i] = samples[i].sun.elevation_deg;
          dop[i] = samples[i].light.dop, aop[i] = samples[i].light.aop_deg;
        }
        Record r;
        r.add("sun_az_deg", take(std::move(az_s), b.shape));
        r.add("sun_el_deg", take(std::move(el_s), b.shape));
        r.add("dop", take(std::move(dop), b.shape));
        r.add("aop_deg", take(std::move(aop), b.shape));
        return RecordOf<SkyTableTag>(std::move(r));
      }, "utc"_a, "lat_deg"_a, "lon_deg"_a, "view_az_deg"_a, "view_el_deg"_a, py::kw_only(),
      "p_max"_a = 0.7, "refraction"_a = false, "ut1_minus_utc_s"_a = 0.0, "threads"_a = py::none(),
      "progress"_a = py::none(),
      (std::string("`polrig sky table`: the sun and the sky's polarization at the times, places and "
                   "view directions given (the CSV's columns as arrays), bit for bit the values "
                   "of its sky.csv.\n\n"
                   "utc: times (ISO strings with Z, aware datetimes, numpy.datetime64); lat_deg in "
                   "[-90, 90] (north positive), lon_deg in [-180, 180] (east positive); "
                   "view_az_deg in [-360, 360] (geographic, from north towards east), view_el_deg "
                   "in [-90, 90] (above the horizon); all broadcast to the result's shape S.\n"
                   "p_max: P_max in (0, 1]; refraction; ut1_minus_utc_s in [-1, 1] s (as the "
                   "CLI's options; the radiance is uniform).\n") + kThreadsDoc + "\n" + kProgressDoc +
       "\nReturns polrig.SkyTable: sun_az_deg, sun_el_deg, dop, aop_deg (local meridian frame, "
       "from e_θ towards e_φ), shape S. A row's sun is exact when few rows share its site and "
       "interpolated along a SunTrack when many do (sky/sun_rows.h), so it may differ by ~1e-8° "
       "depending on how many rows share the call.").c_str());

  // ---- drift
  m.def("drift_corrections", [](const py::object& utc, const py::object& site, const std::string& mode,
                                double p_max, const py::object& p_max_table, bool refraction,
                                double ut1_minus_utc_s) {
        const auto parsed = parse_drift_mode(mode);
        if (!parsed)
          throw py::value_error(fmt::format("mode '{}': expected one of none, angle, per-stop, linear", mode));
        SunSettings settings;
        settings.refraction = refraction;
        check_option(ut1_minus_utc_s, "ut1_minus_utc_s", -1, 1, "s");
        settings.ut1_minus_utc_s = ut1_minus_utc_s;
        SkyModel model;
        check_option(p_max, "p_max", 1e-6, 1.0, "");
        model.P_max.constant = p_max;
        model.P_max.table = p_max_table_of(p_max_table);
        check_sky_model(model);
        const std::vector<UtcTime> times = utc_times(utc, "utc");
        const Site where = site_of(site, "site");
        SkyDrift d;
        {
          py::gil_scoped_release release;
          d = drift_corrections(times, where, settings, model.P_max, *parsed);
        }
        // drift.h leaves what a mode does not correct empty; the arrays here are always (N,):
        // no angle correction is 0°, no d correction a ratio of 1 (as the calibration applies them).
        if (d.dtheta_deg.empty()) d.dtheta_deg.assign(times.size(), 0.0);
        if (d.d_ratio.empty()) d.d_ratio.assign(times.size(), 1.0);
        Record r;
        r.add("dtheta_deg", take(std::move(d.dtheta_deg)));
        r.add("d_ratio", take(std::move(d.d_ratio)));
        return RecordOf<DriftTag>(std::move(r));
      }, "utc"_a, "site"_a, "mode"_a = "angle", py::kw_only(), "p_max"_a = 0.7,
      "p_max_table"_a = py::none(), "refraction"_a = false, "ut1_minus_utc_s"_a = 0.0,
      "The sun-drift corrections of an outdoor turntable calibration at each stop's time "
      "(sky/drift.h's drift_corrections: a sensor looking at the zenith).\n\n"
      "utc: the stops' times, a 1-D sequence or datetime64 array (N,); the first stop is the "
      "earliest. site: (lat_deg, lon_deg[, height_m]). mode: 'none' (no correction: zeros and ones), 'angle' "
      "(the azimuth drift), 'per-stop' (and d(t_k)/d(t_0) from the zenith's DoP), 'linear' (first "
      "and last stop, linear in time). p_max, p_max_table: the sky's P_max (as polrig.Sky); "
      "refraction, ut1_minus_utc_s: the sun's settings.\n"
      "Returns polrig.DriftCorrections: dtheta_deg (N,), degrees added to each stop's table angle "
      "in polrig's sensor frame (anticlockwise seen from above; the E-vector turns clockwise as "
      "A_s rises, so dtheta = −ΔA_s; zeros for 'none'); d_ratio (N,) d(t_k)/d(t_0) for per-stop and "
      "linear, ones for 'none' and 'angle'. Raises "
      "ValueError for a bad mode, a date ERFA refuses, or an unpolarized zenith at the first "
      "stop (per-stop/linear).");

  // ---- spectral kd
  m.def("spectral_kd", [](const std::string& films, const std::string& response,
                          const std::string& response_column, double lamp_K,
                          const std::optional<std::string>& sun_path, const std::string& sun_column,
                          double sun_K, const py::object& tau_m_scale) {
        constexpr int kChannels = 6;
        check_option(lamp_K, "lamp_temperature_K", kMinTemperature_K, kMaxTemperature_K, "K");
        check_option(sun_K, "sun_temperature_K", kMinTemperature_K, kMaxTemperature_K, "K");
        std::vector<double> scale(kChannels, 1.0);
        if (!tau_m_scale.is_none()) {
          scale = finite_values(as_array(tau_m_scale, "tau_m_scale", 1), "tau_m_scale");
          if (scale.size() != kChannels)
            throw py::value_error(fmt::format("tau_m_scale: {} values; expected {} (one per channel) or None",
                                              scale.size(), kChannels));
          for (double s : scale) check_option(s, "tau_m_scale", 1e-6, 1e3, "");
        }
        const FilmSpectra film = read_film_csv(films);
        const Spectrum resp = read_spectrum_csv(response, response_column);
        const Spectrum sun = sun_path ? read_spectrum_csv(*sun_path, sun_column)
                                      : blackbody(sun_K, resp.min_nm(), resp.max_nm());
        SpectralKd result;
        try {
          result = spectral_kd(film, resp, lamp_K, sun, scale,
                               {"films " + films, "sun " + sun_path.value_or(""), "tau_m_scale"});
        } catch (const SpectrumError& e) {
          throw DataError(e.what());
        }
        std::vector<double> channel, s_col, dl, kl, ds, ks, shift;
        for (std::size_t c = 0; c < result.channels.size(); ++c) {
          const ChannelKd& k = result.channels[c];
          channel.push_back(static_cast<double>(c + 1)), s_col.push_back(scale[c]);
          dl.push_back(k.lamp.d_eff), kl.push_back(k.lamp.kd());
          ds.push_back(k.sky.d_eff), ks.push_back(k.sky.kd()), shift.push_back(k.kd_sky_minus_lamp());
        }
        KdSpectra& t = result.spectra;
        Record spectra;
        spectra.add("wavelength_nm", take(std::move(t.wavelength_nm)));
        spectra.add("tau_M", take(std::move(t.tau_M)));
        spectra.add("tau_m", take(std::move(t.tau_m)));
        spectra.add("film_d", take(std::move(t.film_d)));
        spectra.add("response", take(std::move(t.response)));
        spectra.add("lamp_weight", take(std::move(t.lamp_weight)));
        spectra.add("sky_weight", take(std::move(t.sky_weight)));
        Record r;
        r.add("channel", take(std::move(channel)));
        r.add("tau_m_scale", take(std::move(s_col)));
        r.add("d_eff_lamp", take(std::move(dl)));
        r.add("kd_lamp", take(std::move(kl)));
        r.add("d_eff_sky", take(std::move(ds)));
        r.add("kd_sky", take(std::move(ks)));
        r.add("kd_sky_minus_lamp", take(std::move(shift)));
        r.add("spectra", py::cast(RecordOf<KdSpectraTag>(std::move(spectra))));
        return RecordOf<SpectralKdTag>(std::move(r));
      }, "films"_a, "response"_a, py::kw_only(), "response_column"_a = "response",
      "lamp_temperature_K"_a = kIlluminantA_K, "sun"_a = py::none(),
      "sun_column"_a = "extraterrestrial", "sun_temperature_K"_a = kSunBlackbody_K,
      "tau_m_scale"_a = py::none(),
      "`polrig spectral kd`: each channel's effective degree d_eff = ∫(τM − s·τm)·S·R/∫(τM + s·τm)·S·R "
      "and kd = d_eff − 1 under the sphere's lamp (a blackbody) and under the Rayleigh sky "
      "(sunlight × λ⁻⁴), bit for bit kd.csv and spectra.csv.\n\n"
      "films: CSV path with wavelength_nm, tau_M, tau_m; response: CSV path with wavelength_nm "
      "and response_column (its wavelengths set the band); lamp_temperature_K: the lamp's "
      "temperature, [500, 50000] K (CIE A: 2856); sun: a solar spectrum CSV path (column "
      "sun_column, e.g. data/spectra/astm-g173.csv) or None for a blackbody at sun_temperature_K "
      "([500, 50000] K); tau_m_scale: six factors on each channel's leakage τm, each in "
      "[1e-06, 1000], or None (all 1).\n"
      "Returns polrig.SpectralKd (arrays of shape (6,), and .spectra, a polrig.KdSpectra). "
      "Raises polrig.DataError naming the file, line and column of a bad CSV, or the channel.");

  // ---- EXR
  m.def("read_exr", [](const std::string& path, std::optional<int> width, std::optional<int> height) {
        if (width.has_value() != height.has_value()) throw py::value_error("read_exr: give width and height, or neither");
        std::optional<ExrSize> expected;
        if (width) expected = ExrSize{*width, *height};
        int w = 0, h = 0;
        std::vector<ExrChannel> channels = read_exr(path, w, h, expected);
        py::dict d;
        for (ExrChannel& c : channels) d[py::str(c.name)] = take(std::move(c.pixels), {h, w});
        return d;
      }, "path"_a, py::kw_only(), "width"_a = py::none(), "height"_a = py::none(),
      "The channels of an OpenEXR file (e.g. `polrig sky`'s sky.exr: S0, S1, S2, AoP, DoP, A) as "
      "{name: float32 array of shape (height, width)}, row-major, top row first. The size is checked "
      "from the header before any pixel is read: with width and height, another size raises "
      "polrig.DataError (\"FILE: N × M px (expected W × H)\"); without them, a side beyond 16384 px "
      "does. Raises polrig.DataError naming the file when OpenEXR cannot read it (missing, truncated).");
}

}  // namespace polrig::python
