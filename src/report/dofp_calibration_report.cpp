#include "polrig/report/dofp_calibration_report.h"

#include <cmath>
#include <cstdio>
#include <stdexcept>
#include <string>

#include <fmt/format.h>

#include "polrig/io/csv.h"
#include "polrig/io/measured.h"
#include "polrig/io/rig_yaml.h"
#include "polrig/rig/rig.h"
#include "polrig/io/dofp_dataset.h"
#include "polrig/io/exr.h"
#include "polrig/io/plot.h"

namespace polrig {

namespace {

// A number for a CSV cell: shortest round trip, empty for NaN (a quantity that does not exist,
// e.g. the DoP of a fit without the DoP residual); never "nan" or "inf".
std::string num(double v) {
  if (std::isnan(v)) return "";
  if (!std::isfinite(v)) throw std::runtime_error("DoFP report: a non-finite value");
  return fmt::format("{}", v);
}

std::string quoted(const std::string& s) {
  std::string q = "\"";
  for (char c : s) q += c == '"' ? std::string("\"\"") : std::string(1, c);
  return q + "\"";
}

std::vector<float> as_float(const std::vector<double>& v) {
  return std::vector<float>(v.begin(), v.end());
}

// The four mosaic positions' maps of one per-pixel quantity, each cells_x × cells_y, stacked
// TL, TR, BL, BR, as raw little-endian float32 for gnuplot's `binary array`.
void write_position_maps(const std::filesystem::path& path, const std::vector<double>& v, int W,
                         int H) {
  std::vector<float> out;
  out.reserve(v.size());
  for (int j = 0; j < 4; ++j)
    for (int cy = 0; cy < H / 2; ++cy)
      for (int cx = 0; cx < W / 2; ++cx)
        out.push_back(static_cast<float>(v[static_cast<std::size_t>(2 * cy + j / 2) * W + 2 * cx + j % 2]));
  std::FILE* f = std::fopen(path.c_str(), "wb");
  if (!f) throw std::runtime_error(fmt::format("{}: cannot write", path.string()));
  const std::size_t n = std::fwrite(out.data(), sizeof(float), out.size(), f);
  if (std::fclose(f) != 0 || n != out.size())
    throw std::runtime_error(fmt::format("{}: write failed", path.string()));
}

}  // namespace

std::vector<DatasetFile> report_dofp_calibration(const std::filesystem::path& dir,
                                                 const DofpCalibration& c, bool plots) {
  const int W = c.step1.width, H = c.step1.height;
  std::vector<std::uint8_t> usable;
  const DofpTruth p = dofp_parameter_maps(c, &usable);
  std::vector<double> usable_d(usable.begin(), usable.end()), rank_d(c.step1.rank.begin(),
                                                                       c.step1.rank.end());
  write_exr(dir / "params.exr", W, H,
            {{"K", as_float(p.K)},
             {"b", as_float(p.b)},
             {"k", as_float(p.k)},
             {"eps_deg", as_float(p.eps_deg)},
             {"usable", as_float(usable_d)},
             {"step1_rank", as_float(rank_d)},
             {"step1_residual_DN", as_float(c.step1.residual_rms_DN)}});

  std::string t1 = "row,max_deg,mean_deg,std_deg\n";
  for (const DofpOrientationRow& r : c.table1.rows)
    t1 += fmt::format("{},{},{},{}\n", r.name, num(r.max_deg), num(r.mean_deg), num(r.std_deg));
  write_text_file(dir / "table1.csv", t1);

  std::string err = "theta_R_deg,raw_deg,step1_deg,step2_deg\n";
  for (std::size_t m = 0; m < c.table1.theta_R_deg.size(); ++m)
    err += fmt::format("{},{},{},{}\n", num(c.table1.theta_R_deg[m]),
                       num(c.table1.rows[0].error_deg[m]), num(c.table1.rows[1].error_deg[m]),
                       num(c.table1.rows[2].error_deg[m]));
  write_text_file(dir / "errors.csv", err);

  std::string cells =
      "cell_x,cell_y,termination,iterations,rank,observations,initial_rms_deg,final_rms_deg,"
      "psi0_deg,dop,k2,k3,k4,eps2_deg,eps3_deg,eps4_deg,message\n";
  const bool global = c.step2.scope == DofpStep2Scope::Global;
  for (std::size_t i = 0; i < c.step2.cells.size(); ++i) {
    const DofpCellFit& f = c.step2.cells[i];
    const std::string x = global ? "" : fmt::format("{}", i % c.step2.cells_x);
    const std::string y = global ? "" : fmt::format("{}", i / c.step2.cells_x);
    cells += fmt::format("{},{},{},{},{},{},{},{},{},{},{},{},{},{},{},{},{}\n", x, y,
                         termination_name(f.termination), f.iterations, f.rank, f.observations,
                         num(f.initial_rms_deg), num(f.final_rms_deg), num(f.psi0_deg),
                         num(f.dop), num(f.k[1]), num(f.k[2]), num(f.k[3]), num(f.eps_deg[1]),
                         num(f.eps_deg[2]), num(f.eps_deg[3]), quoted(f.message));
  }
  write_text_file(dir / "cells.csv", cells);

  std::string summary = "quantity,value\n";
  summary += fmt::format("scope,{}\n", dofp_scope_name(c.step2.scope));
  summary += fmt::format("table_sense,{}\n", num(c.options.step2.table_sense));
  summary += fmt::format("pixels,{}\n", static_cast<long long>(W) * H);
  summary += fmt::format("step1_rank_deficient_pixels,{}\n", c.step1.rank_deficient_pixels);
  summary += fmt::format("step2_fits,{}\n", c.step2.cells.size());
  summary += fmt::format("step2_usable_fits,{}\n", c.step2.usable_cells);
  summary += fmt::format("table1_intensity,{}\n", num(c.table1.intensity));
  summary += fmt::format("table1_cells_used,{}\n", c.table1.cells_used);
  write_text_file(dir / "summary.csv", summary);

  std::vector<DatasetFile> files{
      {"params.exr", 1, "per pixel: K (DN per unit intensity), b (DN), k, eps_deg, usable (1/0), "
                        "step1_rank (0-2), step1_residual_DN"},
      {"table1.csv", 1, "Table 1: max |error|, mean and SD of the indoor orientation error, raw / "
                        "after step 1 / after step 2"},
      {"errors.csv", 1, "the orientation error per table angle of the three rows"},
      {"cells.csv", 1, "per-cell step 2 fit summaries (termination, iterations, rank, residuals, "
                       "parameters)"},
      {"summary.csv", 1, "counts: scope, pixels, rank-deficient pixels, usable fits, Table 1's "
                         "intensity and cells"}};
  if (!plots) return files;

  Plot e{"errors.png", "Indoor orientation error (Table 1)", "table angle θ_R (°)",
         "orientation error (°)"};
  e.series = {{"errors.csv", "1:2", "raw", "linespoints lw 1.5 pt 6 ps 0.7 lc rgb '#d62728'"},
              {"errors.csv", "1:3", "after step 1", "linespoints lw 1.5 pt 4 ps 0.7 lc rgb '#1f77b4'"},
              {"errors.csv", "1:4", "after step 2", "linespoints lw 2 pt 7 ps 0.7 lc rgb '#000000'"}};
  e.extra = "set key top right opaque box\nset grid\nset xrange [0:360]\nset xtics 45";
  render_plots(dir, "plots.gp", {e});
  files.push_back({"errors.png", 1, "the orientation error curves of Table 1's three rows"});

  struct MapSpec {
    const char* name;
    const char* label;
    const std::vector<double>* v;
  };
  const MapSpec maps[4] = {{"K", "K (DN per unit intensity)", &p.K},
                           {"b", "b (DN)", &p.b},
                           {"k", "k", &p.k},
                           {"eps_deg", "ε (°)", &p.eps_deg}};
  const int cw = W / 2, ch = H / 2;
  const char* pos[4] = {"TL", "TR", "BL", "BR"};
  std::string script;
  std::vector<std::string> pngs;
  for (const MapSpec& m : maps) {
    const std::string bin = fmt::format("map_{}.f32", m.name);
    write_position_maps(dir / bin, *m.v, W, H);
    files.push_back({bin, 1, fmt::format("{} per cell for TL, TR, BL, BR, {} × {} float32 each, "
                                         "stacked, rows top first (for map_{}.png)",
                                         m.name, cw, ch, m.name)});
    const std::string png = fmt::format("map_{}.png", m.name);
    pngs.push_back(png);
    script += fmt::format(
        "reset session\nset terminal pngcairo size 1200,980 enhanced font 'DejaVu Sans,10'\n"
        "set output '{}'\nset multiplot layout 2,2 title \"{} by mosaic position (cells; "
        "image rows downward)\" noenhanced\n"
        "set palette defined (0 '#440154', 0.25 '#3b528b', 0.5 '#21918c', 0.75 '#5ec962', 1 '#fde725')\n"
        "set xrange [-0.5:{}]\nset yrange [{}:-0.5]\nset size ratio -1\nset tics out\n"
        "set format cb '%g'\n",
        png, m.label, cw - 0.5, ch - 0.5);
    for (int j = 0; j < 4; ++j)
      script += fmt::format(
          "set title '{}'\nplot '{}' binary array=({},{}) format='%float32' skip={} "
          "endian=little with image notitle\n",
          pos[j], bin, cw, ch, static_cast<long long>(j) * cw * ch * 4);
    script += "unset multiplot\nunset output\n";
  }
  run_gnuplot(dir, "maps.gp", script, pngs);
  for (const std::string& png : pngs)
    files.push_back({png, 1, "a map of the parameter by mosaic position"});
  files.push_back({"maps.gp", 1, "the gnuplot script of the maps"});
  return files;
}

DofpCalibration calibrate_dofp_dataset(const DofpDataset& dataset, DofpCalibrationOptions options,
                                       const Progress& progress) {
  const int W = dataset.width;
  if (W < 2 || dataset.height < 2) throw std::invalid_argument(fmt::format("{}: no frame", dataset.dir.string()));
  for (int j = 0; j < 4; ++j)  // the first cell's TL, TR, BL, BR
    options.step2.mosaic_deg[static_cast<std::size_t>(j)] =
        dataset.truth.alpha_deg[static_cast<std::size_t>((j / 2) * W + j % 2)];
  // A mean frame at the ADC's top was clipped: step 1 leaves it out (Eq. 19 is linear below it).
  if (dataset.adc_bits > 0 && !std::isfinite(options.step1.saturation_DN))
    options.step1.saturation_DN = std::ldexp(1.0, dataset.adc_bits) - 1.0;
  std::vector<std::vector<double>> frames(dataset.stops.size());
  progress.begin("dofp: reading frames", static_cast<long long>(frames.size()));
  for (std::size_t s = 0; s < frames.size(); ++s) {
    frames[s] = read_dofp_mean_frame(dataset, s);
    progress.advance(1);
  }
  progress.finish();
  std::vector<DofpUnpolarizedLevel> levels;
  std::vector<DofpPolarizedStop> stops;
  for (std::size_t s = 0; s < frames.size(); ++s) {
    const DofpDatasetStop& st = dataset.stops[s];
    if (st.polarized)
      stops.push_back({st.theta_R_deg, st.intensity, frames[s]});
    else
      levels.push_back({st.intensity, frames[s]});
  }
  return calibrate_dofp(W, dataset.height, levels, stops, options, progress);
}

DofpCalibration calibrate_dofp_folder(const std::filesystem::path& dir, const DofpCalibrationOptions& options,
                                      const Progress& progress) {
  if (std::filesystem::exists(dir / "rig.yaml")) {
    const LoadedRig r = load_rig(dir / "rig.yaml");
    require_instrument(r.rig, Instrument::kMosaic, "calibrate --method dofp", r.origin);
  }
  DofpDataset dataset;
  try {
    dataset = read_dofp_dataset(dir);
  } catch (const std::runtime_error& e) {
    throw DataError(e.what());
  }
  try {
    return calibrate_dofp_dataset(dataset, options, progress);
  } catch (const std::invalid_argument& e) {
    throw DataError(fmt::format("{}: {}", dir.string(), e.what()));
  } catch (const std::runtime_error& e) {
    if (dynamic_cast<const CalibrationError*>(&e)) throw;
    throw DataError(e.what());  // a stop's frame file
  }
}

}  // namespace polrig
