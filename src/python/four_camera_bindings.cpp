// W16's four-camera sensor from Python (docs/python.md §10): Rig.four_camera_frames,
// Rig.four_camera_fused, Rig.four_camera_truth, Rig.simulate_four_camera and
// polrig.read_four_camera_dataset. Thin: each converts its arguments, runs the library with the GIL
// released and hands its vectors to NumPy.
#include <cstring>
#include <optional>
#include <string>

#include <fmt/format.h>
#include <pybind11/stl.h>
#include <pybind11/stl/filesystem.h>

#include "bindings.h"
#include "convert.h"
#include "polrig/io/four_camera_dataset.h"
#include "polrig/io/plot.h"
#include "polrig/report/four_camera_dataset.h"
#include "polrig/sim/checkerboard.h"
#include "polrig/sim/four_camera_frames.h"
#include "rig_handle.h"

namespace polrig::python {
namespace {

// FourCameraSimulator's refusals as the CLI words them (ValueError here).
FourCameraSimulator simulator(const LoadedRig& loaded) {
  try {
    if (loaded.rig.checkerboard.views > 0) (void)checkerboard_poses(loaded.rig);  // the board placed
    return FourCameraSimulator(loaded.rig);
  } catch (const std::invalid_argument& e) {
    throw py::value_error(fmt::format("{}: {}", loaded.origin, e.what()));
  }
}

FourCameraLayers layers_of(const std::string& name) {
  if (const std::optional<FourCameraLayers> l = parse_four_camera_layers(name)) return *l;
  throw py::value_error(fmt::format("layers='{}' (expected 'all', 'fused' or 'aop')", name));
}

// One stop's frames and fused image, the GIL released.
struct StopResult {
  int H = 0, W = 0;
  std::array<std::vector<std::uint16_t>, 4> raw;
  FusedImage fused;
};
StopResult run_stop(const LoadedRig& loaded, int stop, bool fuse) {
  StopResult r;
  py::gil_scoped_release release;
  const FourCameraSimulator sim(simulator(loaded));
  if (stop < 0 || static_cast<std::size_t>(stop) >= sim.stops().size()) {
    py::gil_scoped_acquire acquire;
    throw py::index_error(fmt::format("stop={} (the rig has {} stops)", stop, sim.stops().size()));
  }
  r.H = sim.height(), r.W = sim.width();
  r.raw = sim.frames(sim.signal(sim.stops()[static_cast<std::size_t>(stop)]));
  if (fuse) r.fused = sim.fuse(r.raw);
  return r;
}

constexpr const char* kFramesDoc = R"doc(
One stop's raw frames of the four cameras (`polrig simulate`'s cam1 … cam4, bit for bit): a
(4, height, width) uint16 array, camera j − 1 first, top row first (docs/physics.md §16).

  stop: the stop's index (Rig.dofp_stops(): the same stops).
  {threads}
)doc";

constexpr const char* kFusedDoc = R"doc(
One stop's fused image on the virtual camera 1 grid (camera 1's undistorted pinhole image, spec
§3.2 Eqs. 3–5 after co-registration; `polrig simulate`'s layers, bit for bit): a dict of
(height, width) float32 arrays S0, S1, S2, AoP (degrees, camera 1's X towards Y, [0, 180)), DoP, a
uint8 array valid (1 where all four cameras see the pixel), and f_c_px, cx_px, cy_px (the virtual
camera's intrinsics, for the eigenvector method: polrig.sun_vector).

  stop: the stop's index.
  {threads}
)doc";

constexpr const char* kTruthDoc = R"doc(
The four cameras' truth (truth.yaml of `polrig simulate`): a dict of length-4 float64 arrays K, b,
polarizer_deg, eps_deg, axis_deg (φ_j + ε_j), fx_px, fy_px, cx_px, cy_px, a (4, 4) array k
(Kannala–Brandt k1…k4 per camera), a (4, 3, 3) array R_j1 (v_j = R_j1·v_1), a (4, 3) array
position_mm, and the virtual camera's f_c_px, virtual_cx_px, virtual_cy_px.
)doc";

constexpr const char* kSimulateDoc = R"doc(
Writes the four-camera dataset into the new folder `out` (the CLI's `polrig simulate RIG -o OUT`
for a four-camera rig; docs/formats.md "Four-camera dataset") and returns its path.

  layers: 'aop' (AoP, DoP and valid: what locate reads), 'fused' (also S0, S1, S2) or 'all'
  (also the raw frames, which the calibration reads); None (the default): 'all' for a
  calibration rig (unpolarized levels or checkerboard views), else 'aop', as the CLI.
  force: replace an existing folder.
  plots: also draw the previews (previews/: the first and last stops' fused AoP, DoP and S0 PNGs;
    needs gnuplot; the CLI draws them unless --no-plots).
  {threads}
  {progress}
)doc";

constexpr const char* kReadDoc = R"doc(
Reads a four-camera dataset (docs/formats.md): a dict with width, height, f_c_px, cx_px, cy_px (the
virtual camera 1) and stops (a dict of arrays: stop, t_s, theta_R_deg, heading_deg (NaN where
unknown), sun_camera1 (N, 3; NaN where unknown), and a list utc). With stop=k, also the stop's fused
'aop_deg' and 'dop' as (height, width) float64 arrays, NaN where not valid; with raw=True its
frames 'raw' (4, height, width) uint16.
)doc";

}  // namespace

void bind_four_camera(py::module_& m) {
  auto rig = rig_class(m);

  rig.def("four_camera_frames", [](const PyRig& self, int stop, std::optional<int> threads) {
    const LoadedRig loaded = self.loaded;
    const ThreadLimit limit(threads);
    StopResult r = run_stop(loaded, stop, false);
    std::vector<std::uint16_t> all;
    all.reserve(4 * r.raw[0].size());
    for (auto& f : r.raw) all.insert(all.end(), f.begin(), f.end());
    return take(std::move(all), {4, r.H, r.W});
  }, with_shared(kFramesDoc).c_str(), py::arg("stop"), py::kw_only(), py::arg("threads") = py::none());

  rig.def("four_camera_fused", [](const PyRig& self, int stop, std::optional<int> threads) {
    const LoadedRig loaded = self.loaded;
    const ThreadLimit limit(threads);
    StopResult r = run_stop(loaded, stop, true);
    py::dict d;
    d["S0"] = take(std::move(r.fused.S0), {r.H, r.W});
    d["S1"] = take(std::move(r.fused.S1), {r.H, r.W});
    d["S2"] = take(std::move(r.fused.S2), {r.H, r.W});
    d["AoP"] = take(std::move(r.fused.AoP), {r.H, r.W});
    d["DoP"] = take(std::move(r.fused.DoP), {r.H, r.W});
    d["valid"] = take(std::move(r.fused.valid), {r.H, r.W});
    d["f_c_px"] = r.fused.grid.f_c, d["cx_px"] = r.fused.grid.cx, d["cy_px"] = r.fused.grid.cy;
    return d;
  }, with_shared(kFusedDoc).c_str(), py::arg("stop"), py::kw_only(), py::arg("threads") = py::none());

  rig.def("four_camera_truth", [](const PyRig& self) {
    const LoadedRig loaded = self.loaded;
    const FourCameraSimulator sim(simulator(loaded));
    const FourCameraModel& t = sim.truth();
    const FourCameraSpec& spec = loaded.rig.four_camera;
    std::vector<double> K, b, pol, eps, axis, fx, fy, cx, cy, k, R, pos;
    for (std::size_t j = 0; j < 4; ++j) {
      const CameraGeometry& c = t.camera[j];
      K.push_back(t.K[j]), b.push_back(t.b[j]), pol.push_back(spec.polarizer_deg[j]), eps.push_back(spec.eps_deg[j]);
      axis.push_back(t.axis_deg[j]), fx.push_back(c.fx), fy.push_back(c.fy), cx.push_back(c.cx), cy.push_back(c.cy);
      k.insert(k.end(), c.k.begin(), c.k.end());
      R.insert(R.end(), c.R.begin(), c.R.end());
      const Vec3 p = camera_position_mm(spec, static_cast<int>(j));
      pos.insert(pos.end(), p.begin(), p.end());
    }
    py::dict d;
    d["K"] = take(std::move(K)), d["b"] = take(std::move(b)), d["polarizer_deg"] = take(std::move(pol));
    d["eps_deg"] = take(std::move(eps)), d["axis_deg"] = take(std::move(axis));
    d["fx_px"] = take(std::move(fx)), d["fy_px"] = take(std::move(fy)), d["cx_px"] = take(std::move(cx));
    d["cy_px"] = take(std::move(cy)), d["k"] = take(std::move(k), {4, 4}), d["R_j1"] = take(std::move(R), {4, 3, 3});
    d["position_mm"] = take(std::move(pos), {4, 3});
    const VirtualCamera g = sim.fusion().grid();
    // The virtual camera's principal point under its own names: cx_px, cy_px are the cameras'.
    d["f_c_px"] = g.f_c, d["virtual_cx_px"] = g.cx, d["virtual_cy_px"] = g.cy;
    return d;
  }, kTruthDoc);

  rig.def("simulate_four_camera", [](const PyRig& self, const std::filesystem::path& out,
                                     const std::optional<std::string>& layers,
                                     bool force, bool plots, std::optional<int> threads, const py::object& progress) {
    if (plots && !gnuplot_available())
      throw std::runtime_error("plots=True needs gnuplot, which was not found; install it "
                               "(scripts/setup-deps.sh) or pass plots=False");
    const LoadedRig loaded = self.loaded;
    FourCameraDatasetOptions o;
    o.layers = layers ? layers_of(*layers) : default_four_camera_layers(loaded.rig);
    o.previews = plots;
    simulator(loaded);  // refused before the folder is made
    const ThreadLimit limit(threads);
    const Progress p = progress_from(progress);
    const std::string command = fmt::format("python: polrig.Rig({}).simulate_four_camera(out='{}', layers='{}'{})",
                                            loaded.origin, out.string(), four_camera_layers_name(o.layers),
                                            plots ? ", plots=True" : "");
    {
      py::gil_scoped_release release;
      write_four_camera_dataset(loaded, out, o, command, force, p);
    }
    return out;
  }, with_shared(kSimulateDoc).c_str(), py::arg("out"), py::kw_only(),
     py::arg("layers") = py::none(), py::arg("force") = false, py::arg("plots") = false, py::arg("threads") = py::none(),
     py::arg("progress") = py::none());

  m.def("read_four_camera_dataset", [](const std::filesystem::path& dir, std::optional<int> stop, bool raw) {
    FourCameraDataset d;
    FusedAopDop fused;
    std::array<std::vector<std::uint16_t>, 4> frames;
    {
      py::gil_scoped_release release;
      try {
        d = read_four_camera_dataset(dir);
        if (stop) {
          if (*stop < 0) throw std::runtime_error(fmt::format("stop={} (expected ≥ 0)", *stop));
          fused = read_four_camera_fused(d, static_cast<std::size_t>(*stop));
          if (raw) frames = read_four_camera_raw(d, static_cast<std::size_t>(*stop));
        }
      } catch (const std::runtime_error& e) {
        py::gil_scoped_acquire acquire;
        throw py::value_error(e.what());
      }
    }
    py::dict out;
    out["width"] = d.width, out["height"] = d.height;
    if (d.camera) {
      out["f_c_px"] = d.camera->f_c_px, out["cx_px"] = d.camera->x_c_px, out["cy_px"] = d.camera->y_c_px;
    } else {
      out["f_c_px"] = py::none(), out["cx_px"] = py::none(), out["cy_px"] = py::none();  // measured raw frames
    }
    std::vector<double> index, t, theta, heading, sun;
    py::list utc;
    const double nan = std::numeric_limits<double>::quiet_NaN();
    for (const FourCameraDatasetStop& s : d.stops) {
      index.push_back(s.stop), t.push_back(s.t_s), theta.push_back(s.theta_R_deg);
      heading.push_back(s.heading_deg.value_or(nan));
      const Vec3 v = s.sun_camera1.value_or(Vec3{nan, nan, nan});
      sun.insert(sun.end(), v.begin(), v.end());
      utc.append(s.utc);
    }
    const auto n = static_cast<py::ssize_t>(d.stops.size());
    py::dict stops;
    stops["stop"] = take(std::move(index)), stops["t_s"] = take(std::move(t));
    stops["theta_R_deg"] = take(std::move(theta)), stops["heading_deg"] = take(std::move(heading));
    stops["sun_camera1"] = take(std::move(sun), {n, 3}), stops["utc"] = utc;
    out["stops"] = stops;
    if (stop) {
      out["aop_deg"] = take(std::move(fused.aop_deg), {d.height, d.width});
      out["dop"] = take(std::move(fused.dop), {d.height, d.width});
      if (raw) {
        std::vector<std::uint16_t> all;
        for (auto& f : frames) all.insert(all.end(), f.begin(), f.end());
        out["raw"] = take(std::move(all), {4, d.height, d.width});
      }
    }
    return out;
  }, kReadDoc, py::arg("dir"), py::kw_only(), py::arg("stop") = py::none(), py::arg("raw") = false);
}

}  // namespace polrig::python
