// polrig.calibrate_dofp: H17's two-step DoFP calibration (calib/dofp.h) on NumPy arrays.
#include <cmath>
#include <optional>
#include <string>

#include <fmt/format.h>
#include <pybind11/stl.h>
#include <pybind11/stl/filesystem.h>

#include "bindings.h"
#include "convert.h"
#include "polrig/calib/dofp.h"
#include "polrig/calib/dofp_polarization.h"
#include "polrig/report/dofp_calibration_report.h"

namespace polrig::python {

namespace {

py::array_t<double> image(std::vector<double>&& v, int W, int H) {
  return take(std::move(v), {static_cast<py::ssize_t>(H), static_cast<py::ssize_t>(W)});
}

py::dict row_dict(const DofpOrientationRow& r) {
  py::dict d;
  d["max_deg"] = r.max_deg;
  d["mean_deg"] = r.mean_deg;
  d["std_deg"] = r.std_deg;
  d["error_deg"] = take(std::vector<double>(r.error_deg));
  return d;
}

// calibrate_dofp's dict: per-pixel maps, per-cell summaries, Table 1.
py::dict calibration_dict(const DofpCalibration& c) {
  std::vector<std::uint8_t> usable;
  DofpTruth maps = dofp_parameter_maps(c, &usable);
  const int w = c.step1.width, h = c.step1.height;
  py::dict out;
  out["K"] = image(std::move(maps.K), w, h);
  out["b"] = image(std::move(maps.b), w, h);
  out["k"] = image(std::move(maps.k), w, h);
  out["eps_deg"] = image(std::move(maps.eps_deg), w, h);
  out["usable"] = take(std::move(usable), {h, w});
  out["step1_rank"] = take(std::vector<std::uint8_t>(c.step1.rank), {h, w});
  out["step1_residual_DN"] = image(std::vector<double>(c.step1.residual_rms_DN), w, h);
  const std::size_t n = c.step2.cells.size();
  std::vector<double> k(4 * n), eps(4 * n), psi0(n), dop(n), rms0(n), rms(n);
  std::vector<int> iterations(n), rank(n), observations(n);
  py::list termination, message;
  for (std::size_t i = 0; i < n; ++i) {
    const DofpCellFit& f = c.step2.cells[i];
    for (int j = 0; j < 4; ++j) {
      k[4 * i + j] = f.k[j];
      eps[4 * i + j] = f.eps_deg[j];
    }
    psi0[i] = f.psi0_deg;
    dop[i] = f.dop;
    rms0[i] = f.initial_rms_deg;
    rms[i] = f.final_rms_deg;
    iterations[i] = f.iterations;
    rank[i] = f.rank;
    observations[i] = f.observations;
    termination.append(std::string(termination_name(f.termination)));
    message.append(f.message);
  }
  const auto ni = static_cast<py::ssize_t>(n);
  py::dict cells;
  cells["scope"] = dofp_scope_name(c.step2.scope);
  cells["shape"] = py::make_tuple(c.step2.cells_y, c.step2.cells_x);
  cells["termination"] = termination;
  cells["message"] = message;
  cells["iterations"] = take(std::move(iterations));
  cells["rank"] = take(std::move(rank));
  cells["observations"] = take(std::move(observations));
  cells["k"] = take(std::move(k), {ni, 4});
  cells["eps_deg"] = take(std::move(eps), {ni, 4});
  cells["psi0_deg"] = take(std::move(psi0));
  cells["dop"] = take(std::move(dop));
  cells["initial_rms_deg"] = take(std::move(rms0));
  cells["final_rms_deg"] = take(std::move(rms));
  out["cells"] = cells;
  py::dict t1;
  t1["intensity"] = c.table1.intensity;
  t1["cells_used"] = c.table1.cells_used;
  t1["theta_R_deg"] = take(std::vector<double>(c.table1.theta_R_deg));
  for (const DofpOrientationRow& r : c.table1.rows) t1[py::str(r.name)] = row_dict(r);
  out["table1"] = t1;
  return out;
}

}  // namespace

void bind_dofp_calibration(py::module_& m) {
  m.def(
      "calibrate_dofp",
      [](const ArrayLike& level_intensity, const ArrayLike& level_frames, const ArrayLike& theta_R_deg,
         const ArrayLike& stop_intensity, const ArrayLike& stop_frames,
         const std::array<double, 4>& mosaic_deg, double table_sense, const std::string& scope,
         double dop_weight, double fit_weight, bool weight_by_intensity,
         std::optional<double> saturation_DN, double table1_intensity, bool view_projection,
         double focal_px, std::optional<std::pair<double, double>> principal_point,
         std::optional<int> threads, const py::object& progress) {
        const DoubleArray li = as_array(level_intensity.obj, "level_intensity", 1);
        const DoubleArray lf = as_array(level_frames.obj, "level_frames", 3);
        const DoubleArray th = as_array(theta_R_deg.obj, "theta_R_deg", 1);
        const DoubleArray si = as_array(stop_intensity.obj, "stop_intensity", 1);
        const DoubleArray sf = as_array(stop_frames.obj, "stop_frames", 3);
        const py::ssize_t H = lf.shape(1), W = lf.shape(2);
        if (lf.shape(0) != li.shape(0))
          throw py::value_error(fmt::format("level_frames: {} frames for {} level intensities",
                                            lf.shape(0), li.shape(0)));
        if (sf.shape(0) != th.shape(0) || si.shape(0) != th.shape(0))
          throw py::value_error(fmt::format(
              "stop_frames, theta_R_deg, stop_intensity: {}, {} and {} stops; they must agree",
              sf.shape(0), th.shape(0), si.shape(0)));
        if (sf.shape(1) != H || sf.shape(2) != W)
          throw py::value_error(fmt::format("stop_frames: frames of {} × {}, level_frames {} × {}",
                                            sf.shape(2), sf.shape(1), W, H));
        const std::size_t N = static_cast<std::size_t>(W * H);
        std::vector<DofpUnpolarizedLevel> levels(static_cast<std::size_t>(li.shape(0)));
        for (std::size_t i = 0; i < levels.size(); ++i)
          levels[i] = {li.data()[i], std::span<const double>(lf.data() + i * N, N)};
        std::vector<DofpPolarizedStop> stops(static_cast<std::size_t>(th.shape(0)));
        for (std::size_t i = 0; i < stops.size(); ++i)
          stops[i] = {th.data()[i], si.data()[i], std::span<const double>(sf.data() + i * N, N)};
        DofpCalibrationOptions o;
        if (saturation_DN) o.step1.saturation_DN = *saturation_DN;
        o.step2.mosaic_deg = mosaic_deg;
        o.step2.table_sense = table_sense;
        o.step2.dop_weight = dop_weight;
        o.step2.fit_weight = fit_weight;
        o.step2.weight_by_intensity = weight_by_intensity;
        o.table1_intensity = table1_intensity;
        o.step2.view_projection = view_projection;
        o.step2.focal_px = focal_px;
        if (principal_point) {
          o.step2.principal_x_px = principal_point->first;
          o.step2.principal_y_px = principal_point->second;
        }
        DofpCalibration c;
        const Progress p = progress_from(progress);
        ThreadLimit limit(threads);
        try {
          o.step2.scope = parse_dofp_scope(scope);
          py::gil_scoped_release release;
          c = calibrate_dofp(static_cast<int>(W), static_cast<int>(H), levels, stops, o, p);
        } catch (const std::invalid_argument& e) {
          throw py::value_error(e.what());
        }
        return calibration_dict(c);
      },
      py::arg("level_intensity"), py::arg("level_frames"), py::arg("theta_R_deg"),
      py::arg("stop_intensity"), py::arg("stop_frames"), py::kw_only(),
      py::arg("mosaic_deg") = std::array<double, 4>{0, 90, 45, 135},
      py::arg("table_sense") = kDofpTableSense, py::arg("scope") = "per-cell",
      py::arg("dop_weight") = 0.5, py::arg("fit_weight") = 1.0,
      py::arg("weight_by_intensity") = true, py::arg("saturation_DN") = py::none(),
      py::arg("table1_intensity") = 0.0, py::arg("view_projection") = false,
      py::arg("focal_px") = 0.0, py::arg("principal_point") = py::none(),
      py::arg("threads") = py::none(), py::arg("progress") = py::none(),
      (std::string(
           "H17's two-step calibration of a DoFP camera (docs/physics.md §14).\n\n"
           "level_intensity (L,), level_frames (L, H, W): step 1's unpolarized levels (relative "
           "intensity, mean frame in DN). theta_R_deg, stop_intensity (S,), stop_frames (S, H, W): "
           "step 2's polarized stops. Returns a dict: per-pixel maps K, b, k, eps_deg, usable, "
           "step1_rank, step1_residual_DN (H, W); 'cells' (per-cell fit summaries: termination, "
           "message, iterations, rank, observations, k and eps_deg (n, 4), psi0_deg, dop, "
           "initial_rms_deg, final_rms_deg; NaN where a quantity does not exist); 'table1' (raw, "
           "step1, step2: max_deg, mean_deg, std_deg, error_deg; theta_R_deg, intensity, "
           "cells_used). scope: 'per-cell' or 'global'. view_projection: step 2's cells see the "
           "port polarizer along their views and Table 1 maps each cell's AoP back to the port "
           "plane (needs focal_px > 0; principal_point (x, y) in px, default the image centre); "
           "off: H17's model. ValueError for bad input.\n") +
       kThreadsDoc + "\n" + kProgressDoc)
          .c_str());
}


void bind_dofp_dataset_calibration(py::module_& m) {
  m.def(
      "calibrate_dofp_dataset",
      [](const std::filesystem::path& dir, bool view_projection, std::optional<int> threads,
         const py::object& progress) {
        const Progress p = progress_from(progress);
        ThreadLimit limit(threads);
        DofpCalibration c;
        DofpCalibrationOptions o;
        o.step2.view_projection = view_projection;
        {
          py::gil_scoped_release release;
          c = calibrate_dofp_folder(dir, o, p);
        }
        return calibration_dict(c);
      },
      py::arg("dir"), py::kw_only(), py::arg("view_projection") = false, py::arg("threads") = py::none(),
      py::arg("progress") = py::none(),
      (std::string("`polrig calibrate DIR --method dofp`'s computation (report/dofp_calibration_report.h): "
                   "both steps and Table 1 on a DoFP camera dataset (its unpolarized stops for step 1, "
                   "its polarized stops for step 2, the dataset's mosaic). view_projection: as "
                   "`--view-projection` (the dataset's focal length and principal point). Returns calibrate_dofp's dict. "
                   "Raises RigError for a rig without frames, DataError for a file that cannot be read, "
                   "CalibrationError when Table 1 cannot be formed.\n") +
       kThreadsDoc + "\n" + kProgressDoc)
          .c_str());
}

void bind_dofp_polarization(py::module_& m) {
  m.def(
      "dofp_cell_polarization",
      [](const ArrayLike& frame, const std::array<double, 4>& mosaic_deg, const py::object& K,
         const py::object& b, const py::object& k, const py::object& eps_deg) {
        const DoubleArray f = as_array(frame.obj, "frame", 2);
        const int H = static_cast<int>(f.shape(0)), W = static_cast<int>(f.shape(1));
        DofpTruth p;
        try {
          p = nominal_dofp_parameters(W, H, mosaic_deg);
        } catch (const std::invalid_argument& e) {
          throw py::value_error(e.what());
        }
        const auto map = [&](const py::object& o, const char* name, std::vector<double>& into) {
          if (o.is_none()) return;
          const DoubleArray a = as_array(o, name, 2);
          if (a.shape(0) != H || a.shape(1) != W)
            throw py::value_error(fmt::format("{}: a map of {} × {} for a frame of {} × {}", name, a.shape(1),
                                              a.shape(0), W, H));
          into.assign(a.data(), a.data() + a.size());
        };
        map(K, "K", p.K);
        map(b, "b", p.b);
        map(k, "k", p.k);
        map(eps_deg, "eps_deg", p.eps_deg);
        DofpCellPolarization c;
        try {
          py::gil_scoped_release release;
          c = dofp_cell_polarization(std::span<const double>(f.data(), static_cast<std::size_t>(f.size())), p);
        } catch (const std::invalid_argument& e) {
          throw py::value_error(e.what());
        }
        const std::vector<py::ssize_t> shape = {c.cells_y, c.cells_x};
        py::dict out;
        out["S0"] = take(std::move(c.S0), shape);
        out["aop_deg"] = take(std::move(c.aop_deg), shape);
        out["dop"] = take(std::move(c.dop), shape);
        return out;
      },
      py::arg("frame"), py::kw_only(), py::arg("mosaic_deg") = std::array<double, 4>{0, 90, 45, 135},
      py::arg("K") = py::none(), py::arg("b") = py::none(), py::arg("k") = py::none(),
      py::arg("eps_deg") = py::none(),
      "The polarization each 2 × 2 cell of a DoFP frame measures (H17 Eqs. 3–5; with per-pixel "
      "parameters, Eqs. 20–22; docs/physics.md §14). frame (H, W) in DN; K, b, k, eps_deg: "
      "per-pixel maps (H, W), e.g. calibrate_dofp's (None: the nominal 1, 0, 1, 0). Returns a dict "
      "of (H/2, W/2) arrays: S0 (2·q̃3), aop_deg (image frame, [0, 180), NaN without polarization), "
      "dop. ValueError for bad input.");
}

}  // namespace polrig::python
