#pragma once
// What each study writes into its folder: CSV tables (docs/formats.md) and, when asked, PNG
// plots modelled on the paper's figures. Each function returns the manifest entries.
#include <array>
#include <filesystem>
#include <span>
#include <vector>

#include "polrig/io/csv.h"
#include "polrig/io/manifest.h"
#include "polrig/sim/simulate.h"
#include "polrig/study/adc_limit.h"
#include "polrig/study/cs.h"
#include "polrig/study/sweep.h"

namespace polrig {

std::vector<DatasetFile> report_simulation(const std::filesystem::path& dir,
                                           const Simulation& sim, bool plots);
std::vector<DatasetFile> report_cs_study(const std::filesystem::path& dir, const CsStudy& study,
                                         bool plots);
// sweep.csv, written as the sweep runs (a SweepSink): rows in grid order, a block at a time, so
// memory does not grow with the grid. finish() closes it and draws the plots from it.
class SweepReport {
 public:
  // `eq6`: the rig's source has Eq. 6 in closed form (Source::kClosedFormEq6); else it is written as nan.
  SweepReport(const std::filesystem::path& dir, std::vector<GridAxis> axes, bool eq6);
  void write(std::size_t first, std::span<const CsSummary> block);
  std::vector<DatasetFile> finish(bool plots);

 private:
  std::filesystem::path dir_;
  std::vector<GridAxis> axes_;
  CsvTable table_;
  TextFileWriter file_;
  std::size_t rows_ = 0;
  std::array<bool, 3> ratio_defined_{};  // some row has BSD above rounding (pair i)
};
std::vector<DatasetFile> report_adc_limits(const std::filesystem::path& dir,
                                           const std::vector<AdcLimit>& limits, bool plots);

}  // namespace polrig
