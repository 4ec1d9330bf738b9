#include "polrig/io/four_camera_calibration.h"
#include "polrig/quoted.h"

#include <cmath>
#include <set>
#include <stdexcept>

#include <Eigen/Geometry>
#include <fmt/format.h>
#include <yaml-cpp/yaml.h>

#include "polrig/io/measured.h"
#include "polrig/units.h"
#include "yaml_load.h"

namespace polrig {

namespace {

// The physical ranges (docs/formats.md "Four-camera calibration").
struct Range {
  double lo, hi;
  const char* why;
};
constexpr Range kSize{2, 16384, "an integer number of pixels in [2, 16384]"};
constexpr Range kGain{1e-6, 1e6, "a gain in (0, 1e6] DN per unit intensity"};
constexpr Range kOffsetDn{-65535, 65535, "an offset within ±65535 DN (16 bits)"};
constexpr Range kPolarizer{-180, 180, "a polarizer axis in [-180, 180] deg"};
constexpr Range kEps{-45, 45, "a mounting error within ±45 deg (beyond, it is another nominal axis)"};
constexpr Range kAxis{-225, 225, "an axis in [-225, 225] deg (polarizer_deg + eps_deg)"};
constexpr Range kFocal{1, 1e5, "a focal length in [1, 1e5] px"};
constexpr Range kK{-kMaxKannalaBrandtK, kMaxKannalaBrandtK, "a Kannala-Brandt coefficient within ±10"};
constexpr Range kRvec{-180, 180, "a rotation-vector component within ±180 deg"};
constexpr Range kPosition{-1e4, 1e4, "a position within ±10 m (in mm)"};
constexpr Range kRotationElement{-1, 1, "a rotation matrix's element in [-1, 1]"};

std::string where(const std::filesystem::path& path, const YAML::Node& node) {
  return node.Mark().is_null() ? path.string() : fmt::format("{}:{}", path.string(), node.Mark().line + 1);
}

[[noreturn]] void refuse(const std::filesystem::path& path, const YAML::Node& node, const std::string& key,
                         const std::string& problem) {
  throw DataError(fmt::format("{}: key '{}': {}", where(path, node), quoted_value(key), problem));
}

double number(const std::filesystem::path& path, const YAML::Node& node, const std::string& key, const Range& r) {
  if (!node || !node.IsScalar()) refuse(path, node, key, fmt::format("expected {}", r.why));
  double v = 0;
  try {
    v = node.as<double>();
  } catch (const YAML::Exception&) {
    refuse(path, node, key, fmt::format("expected {}, got '{}'", r.why, quoted_value(node.Scalar())));
  }
  if (!(std::isfinite(v) && v >= r.lo && v <= r.hi)) refuse(path, node, key, fmt::format("expected {}, got {}", r.why, quoted_value(node.Scalar())));
  return v;
}

template <std::size_t N>
std::array<double, N> numbers(const std::filesystem::path& path, const YAML::Node& node, const std::string& key,
                              const Range& r) {
  if (!node || !node.IsSequence() || node.size() != N)
    refuse(path, node, key, fmt::format("expected a list of {} numbers, each {}", N, r.why));
  std::array<double, N> out{};
  for (std::size_t i = 0; i < N; ++i) out[i] = number(path, node[i], fmt::format("{}[{}]", key, i), r);
  return out;
}

YAML::Node child(const std::filesystem::path& path, const YAML::Node& parent, const std::string& key,
                 const std::string& full, const char* what) {
  const YAML::Node n = parent[key];
  if (!n) refuse(path, parent, full, fmt::format("missing ({})", what));
  return n;
}

// A YAML double-quoted scalar.
std::string yaml_quoted(const std::string& text) {
  std::string q = "\"";
  for (char ch : text) {
    if (ch == '"' || ch == '\\') q += '\\';
    if (ch == '\n') {
      q += "\\n";
      continue;
    }
    q += ch;
  }
  return q + "\"";
}

// A whole number of pixels in kSize.
int pixels(const std::filesystem::path& path, const YAML::Node& node, const std::string& key) {
  const double v = number(path, node, key, kSize);
  if (v != std::floor(v)) refuse(path, node, key, fmt::format("expected {}, got {}", kSize.why, quoted_value(node.Scalar())));
  return static_cast<int>(v);
}

// truth.yaml's virtual_camera: exactly its five keys, each in its range.
VirtualCameraSpec virtual_camera(const std::filesystem::path& path, const YAML::Node& v) {
  if (!v.IsMap()) refuse(path, v, "virtual_camera", "expected a map (width_px, height_px, f_c_px, cx_px, cy_px)");
  static const std::set<std::string> kKeys = {"width_px", "height_px", "f_c_px", "cx_px", "cy_px"};
  for (const auto& kv : v)
    if (!kKeys.contains(kv.first.as<std::string>()))
      refuse(path, kv.first, "virtual_camera." + kv.first.as<std::string>(),
             "unknown key (expected width_px, height_px, f_c_px, cx_px, cy_px)");
  const auto get = [&](const char* k, const char* what) {
    return child(path, v, k, std::string("virtual_camera.") + k, what);
  };
  VirtualCameraSpec s;
  s.width = pixels(path, get("width_px", "the fused image's columns"), "virtual_camera.width_px");
  s.height = pixels(path, get("height_px", "the fused image's rows"), "virtual_camera.height_px");
  s.camera.f_c_px = number(path, get("f_c_px", "the focal length"), "virtual_camera.f_c_px", kFocal);
  s.camera.x_c_px = number(path, get("cx_px", "the principal point's column"), "virtual_camera.cx_px",
                       {0, double(s.width), "a principal point inside the image: [0, width_px] px"});
  s.camera.y_c_px = number(path, get("cy_px", "the principal point's row"), "virtual_camera.cy_px",
                       {0, double(s.height), "a principal point inside the image: [0, height_px] px"});
  return s;
}

}  // namespace

Vec3 rotation_vector_deg(const std::array<double, 9>& R) {
  const Eigen::Matrix3d M = Eigen::Map<const Eigen::Matrix<double, 3, 3, Eigen::RowMajor>>(R.data());
  const Eigen::AngleAxisd a(M);
  const Eigen::Vector3d v = a.axis() * rad2deg(a.angle());
  return {v(0), v(1), v(2)};
}

std::string four_camera_calibration_yaml(const FourCameraCalibrationFile& f) {
  const FourCameraModel& m = f.model;
  std::string y =
      "# The four-camera sensor's calibration (docs/formats.md \"Four-camera calibration\"): truth.yaml's keys.\n"
      "# Camera j's frame: X_j image +x (columns), Y_j image +y (rows), Z_j the optical axis; angles from X towards\n"
      "# Y. Pixel (col, row)'s centre at (col + 0.5, row + 0.5). R_j1 (v_j = R_j1 v_1) as its rotation vector.\n"
      "# Eq. 1: f_j = K_j I [1 + d cos(2 phi - 2 axis_j)] + b_j, axis_j = polarizer_j + eps_j (camera j's frame);\n"
      "# gauge eps_1 = 0: the fused AoP's zero is camera 1's polarizer axis.\n";
  y += fmt::format("width_px: {}\nheight_px: {}\n", m.width, m.height);
  y += fmt::format("sources:\n  radiometric: {}\n  polarizer: {}\n  geometry: {}\n", yaml_quoted(f.radiometric_from),
                   yaml_quoted(f.polarizer_from), yaml_quoted(f.geometry_from));
  y += "cameras:\n";
  for (std::size_t j = 0; j < 4; ++j) {
    const CameraGeometry& c = m.camera[j];
    y += fmt::format("  - camera: {}\n", j + 1);
    if (f.radiometric) y += fmt::format("    K_DN: {}\n    b_DN: {}\n", m.K[j], m.b[j]);
    if (f.polarizer)
      y += fmt::format("    polarizer_deg: {}\n    eps_deg: {}\n    axis_deg: {}\n", f.polarizer_deg[j], f.eps_deg[j],
                       m.axis_deg[j]);
    const Vec3 r = j == 0 ? Vec3{0, 0, 0} : rotation_vector_deg(c.R);
    y += fmt::format("    fx_px: {}\n    fy_px: {}\n    cx_px: {}\n    cy_px: {}\n", c.fx, c.fy, c.cx, c.cy);
    y += fmt::format("    k: [{}, {}, {}, {}]\n", c.k[0], c.k[1], c.k[2], c.k[3]);
    y += fmt::format("    rvec_deg: [{}, {}, {}]\n", r[0], r[1], r[2]);
    y += fmt::format("    position_mm: [{}, {}, {}]\n", f.position_mm[j][0], f.position_mm[j][1], f.position_mm[j][2]);
  }
  return y;
}

FourCameraCalibrationFile read_four_camera_calibration(const std::filesystem::path& path) {
  const YAML::Node root = load_yaml<DataError>(read_yaml_file<DataError>(path, "calibration file"), path.string(),
                                              "a calibration.yaml nests 3 levels", kMaxYamlBytes);
  refuse_duplicate_keys<DataError>(root, path.string());
  if (!root.IsMap()) throw DataError(fmt::format("{}: expected a map of keys (width_px, height_px, cameras, ...)", path.string()));
  // truth.yaml's keys beside the calibration's: read where shared, ignored otherwise.
  static const std::set<std::string> kTop = {"width_px", "height_px", "sources", "cameras",
                                             "pixel_um", "adc_bits", "baseline_mm", "virtual_camera"};
  static const std::set<std::string> kCamera = {"camera", "K_DN", "b_DN", "polarizer_deg", "eps_deg", "axis_deg",
                                                "fx_px",  "fy_px", "cx_px", "cy_px", "k", "rvec_deg",
                                                "position_mm", "focal_mm", "R_j1"};
  for (const auto& kv : root)
    if (!kTop.contains(kv.first.as<std::string>()))
      refuse(path, kv.first, kv.first.as<std::string>(), "unknown key (expected width_px, height_px, sources, cameras)");
  FourCameraCalibrationFile f;
  FourCameraModel& m = f.model;
  const double w = number(path, child(path, root, "width_px", "width_px", "the image's columns"), "width_px", kSize);
  const double h = number(path, child(path, root, "height_px", "height_px", "the image's rows"), "height_px", kSize);
  if (w != std::floor(w)) refuse(path, root["width_px"], "width_px", fmt::format("expected an integer, got {}", w));
  if (h != std::floor(h)) refuse(path, root["height_px"], "height_px", fmt::format("expected an integer, got {}", h));
  m.width = static_cast<int>(w), m.height = static_cast<int>(h);
  if (const YAML::Node v = root["virtual_camera"]) f.virtual_camera = virtual_camera(path, v);
  if (const YAML::Node s = root["sources"]) {
    if (!s.IsMap()) refuse(path, s, "sources", "expected a map (radiometric, polarizer, geometry)");
    for (const auto& kv : s) {
      const std::string k = kv.first.as<std::string>();
      if (!kv.second.IsScalar()) refuse(path, kv.second, "sources." + k, "expected a text");
      if (k == "radiometric") f.radiometric_from = kv.second.Scalar();
      else if (k == "polarizer") f.polarizer_from = kv.second.Scalar();
      else if (k == "geometry") f.geometry_from = kv.second.Scalar();
      else refuse(path, kv.first, "sources." + k, "unknown key (expected radiometric, polarizer, geometry)");
    }
  }
  const YAML::Node cams = child(path, root, "cameras", "cameras", "a list of the four cameras");
  if (!cams.IsSequence() || cams.size() != 4) refuse(path, cams, "cameras", "expected a list of 4 cameras");
  std::array<bool, 4> has_K{}, has_axis{};
  for (std::size_t j = 0; j < 4; ++j) {
    const YAML::Node c = cams[j];
    const std::string at = fmt::format("cameras[{}]", j);
    if (!c.IsMap()) refuse(path, c, at, "expected a map of the camera's keys");
    for (const auto& kv : c)
      if (!kCamera.contains(kv.first.as<std::string>()))
        refuse(path, kv.first, at + "." + kv.first.as<std::string>(), "unknown key");
    const YAML::Node id = child(path, c, "camera", at + ".camera", "its number, 1 to 4 in order");
    if (number(path, id, at + ".camera", {1, 4, "1 to 4"}) != static_cast<double>(j + 1))
      refuse(path, id, at + ".camera", fmt::format("expected {} (the cameras in order), got {}", j + 1, quoted_value(id.Scalar())));
    CameraGeometry& g = m.camera[j];
    const auto req = [&](const char* k, const Range& r) { return number(path, child(path, c, k, at + "." + k, r.why), at + "." + k, r); };
    g.fx = req("fx_px", kFocal);
    g.fy = req("fy_px", kFocal);
    g.cx = number(path, child(path, c, "cx_px", at + ".cx_px", "the principal point's column"), at + ".cx_px",
                  {0, w, "a principal point inside the image: [0, width_px] px"});
    g.cy = number(path, child(path, c, "cy_px", at + ".cy_px", "the principal point's row"), at + ".cy_px",
                  {0, h, "a principal point inside the image: [0, height_px] px"});
    g.k = numbers<4>(path, child(path, c, "k", at + ".k", "the four Kannala-Brandt coefficients"), at + ".k", kK);
    const std::array<double, 3> r = numbers<3>(path, child(path, c, "rvec_deg", at + ".rvec_deg", "R_j1's rotation vector"),
                                               at + ".rvec_deg", kRvec);
    const double angle = std::sqrt(r[0] * r[0] + r[1] * r[1] + r[2] * r[2]);
    if (angle > 180) refuse(path, c["rvec_deg"], at + ".rvec_deg", fmt::format("expected a rotation of at most 180 deg, got {} deg", angle));
    if (j == 0 && angle != 0)
      refuse(path, c["rvec_deg"], at + ".rvec_deg", fmt::format("expected [0, 0, 0]: camera 1 defines the frame, got a {} deg rotation", angle));
    g.R = rotation_from_vector({deg2rad(r[0]), deg2rad(r[1]), deg2rad(r[2])});
    if (const YAML::Node R = c["R_j1"]) f.R_j1[j] = numbers<9>(path, R, at + ".R_j1", kRotationElement);
    if (const YAML::Node p = c["position_mm"]) {
      const std::array<double, 3> q = numbers<3>(path, p, at + ".position_mm", kPosition);
      f.position_mm[j] = {q[0], q[1], q[2]};
    }
    has_K[j] = c["K_DN"] || c["b_DN"];
    if (has_K[j]) {
      m.K[j] = req("K_DN", kGain);
      m.b[j] = req("b_DN", kOffsetDn);
    }
    has_axis[j] = c["polarizer_deg"] || c["eps_deg"] || c["axis_deg"];
    if (has_axis[j]) {
      f.polarizer_deg[j] = req("polarizer_deg", kPolarizer);
      f.eps_deg[j] = req("eps_deg", kEps);
      m.axis_deg[j] = req("axis_deg", kAxis);
      if (std::abs(m.axis_deg[j] - (f.polarizer_deg[j] + f.eps_deg[j])) > 1e-9)
        refuse(path, c["axis_deg"], at + ".axis_deg",
               fmt::format("expected polarizer_deg + eps_deg = {}, got {}", f.polarizer_deg[j] + f.eps_deg[j], m.axis_deg[j]));
    }
  }
  for (std::size_t j = 1; j < 4; ++j) {
    if (has_K[j] != has_K[0])
      refuse(path, cams[j], fmt::format("cameras[{}]", j), "K_DN and b_DN must be given for every camera or for none");
    if (has_axis[j] != has_axis[0])
      refuse(path, cams[j], fmt::format("cameras[{}]", j),
             "polarizer_deg, eps_deg and axis_deg must be given for every camera or for none");
  }
  f.radiometric = has_K[0];
  f.polarizer = has_axis[0];
  if (f.polarizer) {
    try {
      (void)fusion_matrix(m.axis_deg);
    } catch (const std::invalid_argument& e) {
      refuse(path, cams, "cameras[].axis_deg", e.what());
    }
  }
  return f;
}

FourCameraModel read_four_camera_model(const std::filesystem::path& path) {
  const FourCameraCalibrationFile f = read_four_camera_calibration(path);
  if (!f.radiometric || !f.polarizer)
    throw DataError(fmt::format("{}: holds no {} (a geometry-only file?): fusing needs every camera's K_DN, b_DN and "
                                "axis_deg",
                                path.string(), !f.radiometric ? "K_DN, b_DN" : "polarizer_deg, eps_deg, axis_deg"));
  return f.model;
}

}  // namespace polrig
