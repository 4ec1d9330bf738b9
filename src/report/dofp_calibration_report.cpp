#include "polrig/report/dofp_calibration_report.h"

#include <cmath>
#include <algorithm>
#include <cstdio>
#include <exception>
#include <stdexcept>
#include <string>

#include <fmt/format.h>
#include <tbb/parallel_for.h>

#include "polrig/io/csv.h"
#include "polrig/io/measured.h"
#include "polrig/io/rig_yaml.h"
#include "polrig/rig/rig.h"
#include "polrig/io/dofp_dataset.h"
#include "polrig/io/exr.h"
#include "polrig/io/plot.h"
#include "polrig/units.h"
#include "csv_cells.h"

namespace polrig {

namespace {

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
    t1 += fmt::format("{},{},{},{}\n", r.name, csv_number(r.max_deg), csv_number(r.mean_deg), csv_number(r.std_deg));
  write_text_file(dir / "table1.csv", t1);

  std::string err = "theta_R_deg,raw_deg,step1_deg,step2_deg\n";
  for (std::size_t m = 0; m < c.table1.theta_R_deg.size(); ++m)
    err += fmt::format("{},{},{},{}\n", csv_number(c.table1.theta_R_deg[m]),
                       csv_number(c.table1.rows[0].error_deg[m]), csv_number(c.table1.rows[1].error_deg[m]),
                       csv_number(c.table1.rows[2].error_deg[m]));
  write_text_file(dir / "errors.csv", err);

  // With the view's projection ε_1 is fitted too (no gauge): its column only then, so that the
  // default's file is unchanged.
  const bool eps1 = c.options.step2.view_projection;
  std::string cells = fmt::format(
      "cell_x,cell_y,termination,iterations,rank,observations,initial_rms_deg,final_rms_deg,"
      "psi0_deg,dop,k2,k3,k4,{}eps2_deg,eps3_deg,eps4_deg,message\n", eps1 ? "eps1_deg," : "");
  const bool global = c.step2.scope == DofpStep2Scope::Global;
  for (std::size_t i = 0; i < c.step2.cells.size(); ++i) {
    const DofpCellFit& f = c.step2.cells[i];
    const std::string x = global ? "" : fmt::format("{}", i % c.step2.cells_x);
    const std::string y = global ? "" : fmt::format("{}", i / c.step2.cells_x);
    cells += fmt::format("{},{},{},{},{},{},{},{},{},{},{},{},{},{}{},{},{},{}\n", x, y,
                         termination_name(f.termination), f.iterations, f.rank, f.observations,
                         csv_number(f.initial_rms_deg), csv_number(f.final_rms_deg), csv_number(f.psi0_deg),
                         csv_number(f.dop), csv_number(f.k[1]), csv_number(f.k[2]), csv_number(f.k[3]),
                         eps1 ? csv_number(f.eps_deg[0]) + "," : "", csv_number(f.eps_deg[1]),
                         csv_number(f.eps_deg[2]), csv_number(f.eps_deg[3]), csv_quoted(f.message));
  }
  write_text_file(dir / "cells.csv", cells);

  std::string summary = "quantity,value\n";
  summary += fmt::format("scope,{}\n", dofp_scope_name(c.step2.scope));
  summary += fmt::format("table_sense,{}\n", csv_number(c.options.step2.table_sense));
  if (c.options.step2.view_projection) {  // only when on: the default's file is unchanged
    const FitSummary& f = c.step2.psi0_fit;
    summary += fmt::format("view_projection_focal_px,{}\n", csv_number(c.options.step2.focal_px));
    summary += fmt::format("psi0_deg,{}\n", csv_number(c.step2.psi0_deg));
    summary += fmt::format("psi0_termination,{}\n", termination_name(f.termination));
    summary += fmt::format("psi0_iterations,{}\n", f.iterations);
    summary += fmt::format("psi0_passes,{}\n", f.evaluations);
    summary += fmt::format("psi0_initial_cost_rad2,{}\n", csv_number(f.initial_cost));
    summary += fmt::format("psi0_final_cost_rad2,{}\n", csv_number(f.final_cost));
    summary += fmt::format("psi0_message,{}\n", csv_quoted(f.message));
  }
  summary += fmt::format("pixels,{}\n", static_cast<long long>(W) * H);
  summary += fmt::format("step1_rank_deficient_pixels,{}\n", c.step1.rank_deficient_pixels);
  summary += fmt::format("step2_fits,{}\n", c.step2.cells.size());
  summary += fmt::format("step2_usable_fits,{}\n", c.step2.usable_cells);
  summary += fmt::format("table1_intensity,{}\n", csv_number(c.table1.intensity));
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
  e.series = {{"errors.csv", "$theta_R_deg:$raw_deg", "raw", "linespoints lw 1.5 pt 6 ps 0.7 lc rgb '#d62728'"},
              {"errors.csv", "$theta_R_deg:$step1_deg", "after step 1", "linespoints lw 1.5 pt 4 ps 0.7 lc rgb '#1f77b4'"},
              {"errors.csv", "$theta_R_deg:$step2_deg", "after step 2", "linespoints lw 2 pt 7 ps 0.7 lc rgb '#000000'"}};
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
  const char* gauge = c.options.step2.view_projection ? "step 2's gauge k_1 = 1; ε_1 fitted with the view's projection"
                                                      : "step 2's gauge k_1 = 1, ε_1 = 0, Eq. 25";
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
    // Axes in image pixels (a pixel (col, row) from col to col + 1): each cell's value drawn over
    // its 2 × 2 pixels. The reference pixel of every cell is its TL (mosaic position
    // 1: step 2's gauge k_1 = 1, ε_1 = 0, Eq. 25; ε_1 fitted with the view's projection), marked
    // in its panel's title.
    script += fmt::format(
        "reset session\nset terminal pngcairo size 1200,1000 enhanced font 'DejaVu Sans,10'\n"
        "set output '{}'\nset multiplot layout 2,2 title \"{} by mosaic position (one value per 2 × 2 "
        "cell, drawn over its pixels; image rows downward)\\nreference pixel: each cell's TL ({})\" noenhanced\n"
        "set palette defined (0 '#440154', 0.25 '#3b528b', 0.5 '#21918c', 0.75 '#5ec962', 1 '#fde725')\n"
        "set xrange [0:{}]\nset yrange [{}:0]\nset size ratio -1\nset tics out\n"
        "set xlabel 'pixel column'\nset ylabel 'pixel row'\nset format cb '%g'\n",
        png, m.label, gauge, W, H);
    for (int j = 0; j < 4; ++j)
      script += fmt::format(
          "set title '{}' tc rgb '{}'\nplot '{}' binary array=({},{}) dx=2 dy=2 origin=(1,1) format='%float32' "
          "skip={} endian=little with image notitle\n",
          j == 0 ? "TL: the reference pixel" : pos[j], j == 0 ? "#d62728" : "black", bin, cw, ch,
          static_cast<long long>(j) * cw * ch * 4);
    script += "unset multiplot\nunset output\n";
  }
  run_gnuplot(dir, "maps.gp", script, pngs);
  for (const std::string& png : pngs)
    files.push_back({png, 1, "a map of the parameter by mosaic position"});
  files.push_back({"maps.gp", 1, "the gnuplot script of the maps"});
  return files;
}

namespace {

// The mean frames of the stops `which` (rows [first_row, first_row + rows), or whole with rows < 0),
// read in parallel; a failure is the first failing stop's, as a loop in order would throw it.
std::vector<std::vector<double>> read_mean_rows(const DofpDataset& dataset, const std::vector<std::size_t>& which,
                                                int first_row, int rows, const Progress& progress = {}) {
  std::vector<std::vector<double>> out(which.size());
  std::vector<std::exception_ptr> errors(which.size());
  tbb::parallel_for(std::size_t{0}, which.size(), [&](std::size_t i) {
    try {
      out[i] = rows < 0 ? read_dofp_mean_frame(dataset, which[i]) : read_dofp_mean_rows(dataset, which[i], first_row, rows);
      progress.advance(1);
    } catch (...) {
      errors[i] = std::current_exception();
    }
  });
  for (const std::exception_ptr& e : errors)
    if (e) std::rethrow_exception(e);
  return out;
}

// Rows per band: every stop's band of rows (as doubles) within kBandBytes, in whole 32-row blocks
// (PIZ's, two of ZIP's: each band decompresses only its own blocks) when that fits, and even
// (whole cells) in any case.
constexpr double kBandBytes = 128e6;
int band_rows_for(const DofpDataset& dataset) {
  const double row_bytes = 8.0 * dataset.width * static_cast<double>(std::max<std::size_t>(dataset.stops.size(), 1));
  const int fit = static_cast<int>(std::min(kBandBytes / row_bytes, 1e6));
  return fit >= 32 ? fit / 32 * 32 : std::max(2, fit / 2 * 2);
}

DofpCalibration calibrate_whole(const DofpDataset& dataset, const DofpCalibrationOptions& options,
                                const Progress& progress) {
  std::vector<std::size_t> all(dataset.stops.size());
  for (std::size_t s = 0; s < all.size(); ++s) all[s] = s;
  progress.begin("dofp: reading frames", static_cast<long long>(all.size()));
  const std::vector<std::vector<double>> frames = read_mean_rows(dataset, all, 0, -1, progress);
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
  return calibrate_dofp(dataset.width, dataset.height, levels, stops, options, progress);
}

}  // namespace

DofpCalibration calibrate_dofp_dataset(const DofpDataset& dataset, DofpCalibrationOptions options,
                                       const Progress& progress, int band_rows) {
  const int W = dataset.width, H = dataset.height;
  if (W < 2 || H < 2) throw std::invalid_argument(fmt::format("{}: no frame", dataset.dir.string()));
  options.step2.mosaic_deg = dataset.mosaic_deg;
  // The view's projection takes the camera's pinhole from the dataset unless given.
  if (options.step2.view_projection && !(options.step2.focal_px > 0)) {
    options.step2.focal_px = dataset.f_c_px;
    options.step2.principal_x_px = dataset.cx;
    options.step2.principal_y_px = dataset.cy;
  }
  // A mean frame at the ADC's top was clipped: step 1 leaves it out (Eq. 19 is linear below it).
  if (dataset.adc_bits > 0 && !std::isfinite(options.step1.saturation_DN))
    options.step1.saturation_DN = std::ldexp(1.0, dataset.adc_bits) - 1.0;
  // The global fit sums over every cell at once; odd sizes are calibrate_dofp's error to report.
  if (options.step2.scope == DofpStep2Scope::Global || W % 2 || H % 2) return calibrate_whole(dataset, options, progress);

  // Step 1 fits each pixel and step 2 each cell from their own rows alone, so both run on bands
  // of rows: only a band of every stop's frame is held at once (the whole frames as doubles were
  // 1.2 GB for the han2017 indoor run), and the results are those of whole frames, bit for bit.
  if (band_rows <= 0) band_rows = band_rows_for(dataset);
  if (band_rows % 2) throw std::invalid_argument(fmt::format("bands of {} rows: not whole cells", band_rows));
  std::vector<std::size_t> level_ix, stop_ix;
  for (std::size_t s = 0; s < dataset.stops.size(); ++s) (dataset.stops[s].polarized ? stop_ix : level_ix).push_back(s);
  const std::size_t N = static_cast<std::size_t>(W) * static_cast<std::size_t>(H);
  const int cells_x = W / 2;
  DofpCalibration c;
  c.options = options;
  DofpStep1& s1 = c.step1;
  s1.width = W, s1.height = H;
  s1.K.resize(N), s1.b.resize(N), s1.residual_rms_DN.resize(N), s1.rank.resize(N), s1.levels_used.resize(N);
  DofpStep2& s2 = c.step2;
  s2.scope = options.step2.scope;
  s2.cells_x = cells_x, s2.cells_y = H / 2;
  s2.cells.resize(static_cast<std::size_t>(s2.cells_x) * static_cast<std::size_t>(s2.cells_y));
  // A band's stops (rows [row0, row0 + rows) of each) and its step 1.
  struct Band {
    std::vector<std::vector<double>> stop_rows;
    std::vector<DofpPolarizedStop> stops;
    DofpStep1 step1;
  };
  const auto read_band = [&](int row0, int rows, Band& band) {
    const std::vector<std::vector<double>> level_rows = read_mean_rows(dataset, level_ix, row0, rows);
    band.stop_rows = read_mean_rows(dataset, stop_ix, row0, rows);
    std::vector<DofpUnpolarizedLevel> levels;
    band.stops.clear();
    for (std::size_t i = 0; i < level_ix.size(); ++i) levels.push_back({dataset.stops[level_ix[i]].intensity, level_rows[i]});
    for (std::size_t i = 0; i < stop_ix.size(); ++i) {
      const DofpDatasetStop& st = dataset.stops[stop_ix[i]];
      band.stops.push_back({st.theta_R_deg, st.intensity, band.stop_rows[i]});
    }
    band.step1 = calibrate_dofp_step1(W, rows, levels, options.step1);
  };
  const auto keep_step1 = [&](int row0, const DofpStep1& b1) {
    const std::size_t p0 = static_cast<std::size_t>(row0) * static_cast<std::size_t>(W);
    std::copy(b1.K.begin(), b1.K.end(), s1.K.begin() + static_cast<std::ptrdiff_t>(p0));
    std::copy(b1.b.begin(), b1.b.end(), s1.b.begin() + static_cast<std::ptrdiff_t>(p0));
    std::copy(b1.residual_rms_DN.begin(), b1.residual_rms_DN.end(), s1.residual_rms_DN.begin() + static_cast<std::ptrdiff_t>(p0));
    std::copy(b1.rank.begin(), b1.rank.end(), s1.rank.begin() + static_cast<std::ptrdiff_t>(p0));
    std::copy(b1.levels_used.begin(), b1.levels_used.end(), s1.levels_used.begin() + static_cast<std::ptrdiff_t>(p0));
    s1.rank_deficient_pixels += b1.rank_deficient_pixels;
  };
  const auto keep_step2 = [&](int row0, const DofpStep1& b1, DofpStep2& b2) {
    for (std::size_t i = 0; i < b2.cells.size(); ++i) {
      DofpCellFit& fit = b2.cells[i];
      // Step 2 names an undetermined pixel by its row in the band: the same message with the
      // frame's row (calibrate_dofp_step2's, for the first such pixel of the cell).
      const int cx = static_cast<int>(i % static_cast<std::size_t>(cells_x)), cy = static_cast<int>(i / static_cast<std::size_t>(cells_x));
      for (int j = 0; j < 4; ++j) {
        const std::size_t p = static_cast<std::size_t>(2 * cy + j / 2) * static_cast<std::size_t>(W) + static_cast<std::size_t>(2 * cx + j % 2);
        if (b1.rank[p] < 2) {
          fit.message = fmt::format("step 1 left pixel (column {}, row {}) undetermined (rank {})", 2 * cx + j % 2,
                                    row0 + 2 * cy + j / 2, int{b1.rank[p]});
          break;
        }
      }
      s2.cells[static_cast<std::size_t>(row0 / 2) * static_cast<std::size_t>(cells_x) + i] = std::move(fit);
    }
  };
  // A band's cells see the views of their rows in the whole frame: the principal point in the
  // band's own rows (NaN, the frame's centre, only matters with the view's projection on).
  const auto band_options = [&](int row0) {
    DofpStep2Options band_step2 = options.step2;
    if (band_step2.view_projection)
      band_step2.principal_y_px = (std::isfinite(band_step2.principal_y_px) ? band_step2.principal_y_px : 0.5 * H) - row0;
    return band_step2;
  };
  if (options.step2.view_projection) {
    // One ψ_0 for the whole image: step 1 and the start by bands, then each pass of the ψ_0 fit
    // (dofp_fit_psi0) fits every band's cells at its ψ_0.
    // The sums per cell row, added in row order: the whole frame's bits (calibrate_dofp_step2).
    std::vector<std::array<double, 2>> start;
    progress.begin("calibrate dofp: step 1 by bands of rows", H);
    for (int row0 = 0; row0 < H; row0 += band_rows) {
      Band band;
      read_band(row0, std::min(band_rows, H - row0), band);
      keep_step1(row0, band.step1);
      for (const std::array<double, 2>& r : dofp_psi0_start_rows(band.step1, band.stops, band_options(row0)))
        start.push_back(r);
      progress.advance(band.step1.height);
    }
    progress.finish();
    bool first = true;
    const auto pass = [&](double psi0_deg) {
      s2.psi0_rows.clear();
      progress.begin(fmt::format("calibrate dofp: step 2 by bands of rows at psi0 = {:.9g} deg", psi0_deg), H);
      for (int row0 = 0; row0 < H; row0 += band_rows) {
        Band band;
        read_band(row0, std::min(band_rows, H - row0), band);
        DofpStep2Options o = band_options(row0);
        o.psi0_deg = psi0_deg;
        const std::size_t c0 = static_cast<std::size_t>(row0 / 2) * static_cast<std::size_t>(cells_x);
        if (!first)  // each pass starts at the last one's fits
          o.start_cells = std::span<const DofpCellFit>(s2.cells).subspan(c0, static_cast<std::size_t>(band.step1.height / 2) * cells_x);
        DofpStep2 b2 = calibrate_dofp_step2(band.step1, band.stops, o);
        s2.psi0_rows.insert(s2.psi0_rows.end(), b2.psi0_rows.begin(), b2.psi0_rows.end());
        keep_step2(row0, band.step1, b2);
        progress.advance(band.step1.height);
      }
      progress.finish();
      first = false;
      return s2.psi0_pass = dofp_sum(s2.psi0_rows);
    };
    s2.psi0_fit = dofp_fit_psi0(pass, dofp_psi0_start_deg(start), options.step2, s2.psi0_deg);
    for (const DofpCellFit& fit : s2.cells) s2.usable_cells += fit.usable();
  } else {
    progress.begin("calibrate dofp: steps 1 and 2 by bands of rows", H);
    for (int row0 = 0; row0 < H; row0 += band_rows) {
      Band band;
      read_band(row0, std::min(band_rows, H - row0), band);
      DofpStep2 b2 = calibrate_dofp_step2(band.step1, band.stops, band_options(row0));
      keep_step1(row0, band.step1);
      keep_step2(row0, band.step1, b2);
      progress.advance(band.step1.height);
    }
    progress.finish();
    for (const DofpCellFit& fit : s2.cells) s2.usable_cells += fit.usable();
  }

  // Table 1 from whole frames of its stops only (those of its intensity: the largest unless chosen).
  double intensity = options.table1_intensity;
  if (!(intensity > 0))
    for (std::size_t s : stop_ix) intensity = std::max(intensity, dataset.stops[s].intensity);
  std::vector<std::size_t> table_ix;
  for (std::size_t s : stop_ix)
    if (dataset.stops[s].intensity == intensity) table_ix.push_back(s);
  const std::vector<std::vector<double>> table_frames = read_mean_rows(dataset, table_ix, 0, -1);
  std::vector<DofpPolarizedStop> table_stops;
  for (std::size_t i = 0; i < table_ix.size(); ++i) {
    const DofpDatasetStop& st = dataset.stops[table_ix[i]];
    table_stops.push_back({st.theta_R_deg, st.intensity, table_frames[i]});
  }
  c.table1 = dofp_table1(s1, s2, table_stops, options.step2, intensity);
  return c;
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
