// The DoFP camera from Python (docs/python.md §9): Rig.dofp_stops, Rig.dofp_frame, Rig.dofp_truth,
// Rig.simulate_frames and polrig.read_dofp_dataset. Thin: each converts its arguments, runs the
// library with the GIL released and hands its vectors to NumPy.
#include <cstring>
#include <optional>
#include <string>

#include <fmt/format.h>
#include <pybind11/stl.h>
#include <pybind11/stl/filesystem.h>

#include "bindings.h"
#include "convert.h"
#include "polrig/io/dofp_dataset.h"
#include "polrig/io/output_dir.h"
#include "polrig/io/plot.h"
#include "polrig/report/dofp_dataset.h"
#include "polrig/sim/dofp_frames.h"
#include "polrig/side_by_side.h"
#include "rig_handle.h"

namespace polrig::python {
namespace {

DofpAnalyzer analyzer_of(const std::string& name) {
  if (name == "image-plane") return DofpAnalyzer::ImagePlane;
  if (name == "in-front") return DofpAnalyzer::InFront;
  throw py::value_error(fmt::format("analyzer='{}' (expected 'image-plane' or 'in-front')", name));
}

// DofpSimulator's refusals as the CLI words them (ValueError here).
DofpSimulator simulator(const LoadedRig& loaded, DofpAnalyzer analyzer) {
  try {
    return DofpSimulator(loaded.rig, analyzer);
  } catch (const std::invalid_argument& e) {
    throw py::value_error(fmt::format("{}: {}", loaded.origin, e.what()));
  }
}

py::dict image_dict(int H, int W, std::initializer_list<std::pair<const char*, std::vector<double>*>> layers) {
  py::dict d;
  for (const auto& [name, v] : layers) d[name] = take(std::move(*v), {H, W});
  return d;
}

constexpr const char* kStopsDoc = R"doc(
The camera's stops (a rig whose instrument takes frames; docs/physics.md §13): first one per
unpolarized level, then every table angle at each intensity. A dict of arrays: stop,
theta_R_deg, t_s, intensity, polarized (bool), frames.
)doc";

constexpr const char* kFrameDoc = R"doc(
One simulated frame of the camera (`polrig simulate`'s frames, bit for bit): raw DN as a
(height, width) uint16 array, top row first. With truth_layers=True a pair (raw, layers), layers a
dict of (height, width) float32 arrays S0, S1, S2, AoP (degrees, image frame), DoP.

  stop: the stop's index (Rig.dofp_stops()); frame: the frame's index at that stop.
  analyzer: 'image-plane' (spec §2.5's default) or 'in-front'.
  {threads}
)doc";

constexpr const char* kTruthDoc = R"doc(
The camera's per-pixel truth (what calibration must recover), a dict of (height, width) float64
arrays K, b, k, eps_deg, alpha_deg (truth.exr of `polrig simulate`).
)doc";

constexpr const char* kSimulateFramesDoc = R"doc(
Writes the camera's dataset into the new folder `out` (the CLI's `polrig simulate RIG -o OUT` for a
camera rig; docs/formats.md) and returns its path.

  frames: 'every' (every frame) or 'mean' (the per-stop mean, stored exactly as the frames' sum).
  truth_layers: also write each stop's S0, S1, S2, AoP, DoP.  analyzer: as dofp_frame.
  force: replace an existing folder.
  plots: also draw the previews (previews/: the first and last stops' AoP, DoP and S0 PNGs; needs
    gnuplot; the CLI draws them unless --no-plots).
  {threads}
  {progress}
)doc";

constexpr const char* kReadDoc = R"doc(
Reads a camera dataset (docs/formats.md §6.14): a dict with width, height, f_c_px, cx, cy,
mosaic_deg (TL, TR, BL, BR), adc_bits (0: not recorded), the truth (dict of (height, width)
arrays K, b, k, eps_deg, alpha_deg; None for a measured dataset without truth.exr, whose camera
comes from its rig.yaml) and the stops (dict of arrays as stops.csv's columns; heading_deg NaN
where unknown). mean_frames=True adds 'mean_frames', an (N, height, width) float64 array of every
stop's mean frame.
)doc";

}  // namespace

void bind_dofp(py::module_& m) {
  auto rig = rig_class(m);

  rig.def("dofp_stops", [](const PyRig& self) {
    const std::vector<DofpStop> stops = dofp_stops(self.rig().schedule);
    std::vector<double> index, theta, t, intensity, frames;
    std::vector<bool> polarized;
    for (const DofpStop& s : stops) {
      index.push_back(s.index), theta.push_back(s.theta_R_deg), t.push_back(s.t_s);
      intensity.push_back(s.intensity), frames.push_back(s.frames), polarized.push_back(s.polarized);
    }
    py::dict d;
    d["stop"] = take(std::move(index));
    d["theta_R_deg"] = take(std::move(theta));
    d["t_s"] = take(std::move(t));
    d["intensity"] = take(std::move(intensity));
    d["polarized"] = py::array(py::cast(polarized)).attr("astype")("bool");
    d["frames"] = take(std::move(frames));
    return d;
  }, kStopsDoc);

  rig.def("dofp_frame", [](const PyRig& self, int stop, int frame, bool truth_layers, const std::string& analyzer,
                           std::optional<int> threads) -> py::object {
    const DofpAnalyzer a = analyzer_of(analyzer);
    const LoadedRig loaded = self.loaded;  // the GIL is released below: nothing of self is read then
    const ThreadLimit limit(threads);
    std::vector<std::uint16_t> raw;
    DofpTruthLayers layers;
    int H = 0, W = 0;
    {
      py::gil_scoped_release release;
      const DofpSimulator sim(simulator(loaded, a));
      if (stop < 0 || static_cast<std::size_t>(stop) >= sim.stops().size()) {
        py::gil_scoped_acquire acquire;
        throw py::index_error(fmt::format("stop={} (the rig has {} stops)", stop, sim.stops().size()));
      }
      const DofpStop& s = sim.stops()[static_cast<std::size_t>(stop)];
      if (frame < 0) {
        py::gil_scoped_acquire acquire;
        throw py::index_error(fmt::format("frame={} (expected ≥ 0)", frame));
      }
      H = sim.height(), W = sim.width();
      raw = sim.frame(s, frame, truth_layers ? &layers : nullptr);
    }
    py::array out = take(std::move(raw), {H, W});
    if (!truth_layers) return out;
    py::dict d;
    d["S0"] = take(std::move(layers.S0), {H, W});
    d["S1"] = take(std::move(layers.S1), {H, W});
    d["S2"] = take(std::move(layers.S2), {H, W});
    d["AoP"] = take(std::move(layers.AoP), {H, W});
    d["DoP"] = take(std::move(layers.DoP), {H, W});
    return py::make_tuple(out, d);
  }, with_shared(kFrameDoc).c_str(), py::arg("stop"), py::arg("frame") = 0, py::kw_only(),
     py::arg("truth_layers") = false, py::arg("analyzer") = "image-plane", py::arg("threads") = py::none());

  rig.def("dofp_truth", [](const PyRig& self) {
    DofpTruth t;
    const LoadedRig loaded = self.loaded;
    {
      py::gil_scoped_release release;
      t = simulator(loaded, DofpAnalyzer::ImagePlane).truth();
    }
    return image_dict(t.height, t.width, {{"K", &t.K}, {"b", &t.b}, {"k", &t.k}, {"eps_deg", &t.eps_deg}, {"alpha_deg", &t.alpha_deg}});
  }, kTruthDoc);

  rig.def("simulate_frames", [](const PyRig& self, const std::filesystem::path& out, const std::string& frames,
                                bool truth_layers, const std::string& analyzer, bool force, bool plots,
                                std::optional<int> threads, const py::object& progress) {
    if (plots && !gnuplot_available())
      throw std::runtime_error("plots=True needs gnuplot, which was not found; install it "
                               "(scripts/setup-deps.sh) or pass plots=False");
    DofpDatasetOptions o;
    o.previews = plots;
    if (frames != "every" && frames != "mean")
      throw py::value_error(fmt::format("frames='{}' (expected 'every' or 'mean')", frames));
    o.storage = frames == "mean" ? DofpFrameStorage::Sum : DofpFrameStorage::Every;
    o.truth_layers = truth_layers;
    o.analyzer = analyzer_of(analyzer);
    const LoadedRig loaded = self.loaded;
    simulator(loaded, o.analyzer);  // refused before the folder is made
    const ThreadLimit limit(threads);
    const Progress p = progress_from(progress);
    const std::string command = fmt::format("python: polrig.Rig({}).simulate_frames(out='{}', frames='{}', "
                                            "truth_layers={}, analyzer='{}'{})",
                                            loaded.origin, out.string(), frames, truth_layers ? "True" : "False", analyzer,
                                            plots ? ", plots=True" : "");
    {
      py::gil_scoped_release release;
      write_dofp_dataset(loaded, out, o, command, force, p);
    }
    return out;
  }, with_shared(kSimulateFramesDoc).c_str(), py::arg("out"), py::kw_only(), py::arg("frames") = "every",
     py::arg("truth_layers") = false, py::arg("analyzer") = "image-plane", py::arg("force") = false,
     py::arg("plots") = false, py::arg("threads") = py::none(), py::arg("progress") = py::none());

  m.def("read_dofp_dataset", [](const std::filesystem::path& dir, bool mean_frames) {
    DofpDataset d;
    std::vector<double> means;
    {
      py::gil_scoped_release release;
      d = read_dofp_dataset(dir);
      if (mean_frames)  // side by side, each on its own thread, appended in stop order
        side_by_side_in_order(
            d.stops.size(), [&](std::size_t s) { return read_dofp_mean_frame(d, s); },
            [&](std::vector<double>&& f) { means.insert(means.end(), f.begin(), f.end()); });
    }
    py::dict out;
    out["width"] = d.width, out["height"] = d.height, out["f_c_px"] = d.f_c_px, out["cx"] = d.cx, out["cy"] = d.cy;
    out["mosaic_deg"] = py::make_tuple(d.mosaic_deg[0], d.mosaic_deg[1], d.mosaic_deg[2], d.mosaic_deg[3]);
    out["adc_bits"] = d.adc_bits;
    if (d.truth)
      out["truth"] = image_dict(d.height, d.width, {{"K", &d.truth->K}, {"b", &d.truth->b}, {"k", &d.truth->k},
                                                    {"eps_deg", &d.truth->eps_deg}, {"alpha_deg", &d.truth->alpha_deg}});
    else
      out["truth"] = py::none();
    std::vector<double> stop, theta, t, intensity, heading, frames;
    std::vector<bool> polarized;
    py::list utc, file;
    for (const DofpDatasetStop& s : d.stops) {
      stop.push_back(s.stop), theta.push_back(s.theta_R_deg), t.push_back(s.t_s), intensity.push_back(s.intensity);
      heading.push_back(s.heading_deg ? *s.heading_deg : std::nan("")), frames.push_back(s.frames);
      polarized.push_back(s.polarized), utc.append(s.utc), file.append(s.file);
    }
    py::dict stops;
    stops["stop"] = take(std::move(stop)), stops["theta_R_deg"] = take(std::move(theta)), stops["t_s"] = take(std::move(t));
    stops["utc"] = utc, stops["intensity"] = take(std::move(intensity));
    stops["polarized"] = py::array(py::cast(polarized)).attr("astype")("bool");
    stops["heading_deg"] = take(std::move(heading)), stops["frames"] = take(std::move(frames)), stops["file"] = file;
    out["stops"] = stops;
    if (mean_frames)
      out["mean_frames"] = take(std::move(means), {static_cast<py::ssize_t>(d.stops.size()), d.height, d.width});
    return out;
  }, kReadDoc, py::arg("dir"), py::kw_only(), py::arg("mean_frames") = false);
}

}  // namespace polrig::python
