#pragma once
// What `polrig navigate` writes (docs/formats.md §6.18): solution.csv (every mode's position and
// attitude per compass reading, and its errors when the dataset has a truth), filter.csv (the
// integrated filter's measurements, innovations, NIS and σ), summary.csv (Z21 §5's MAE, RMSE and
// STD of latitude and longitude per mode; with a truth only), filter_summary.yaml and plots like
// Z21 Figs. 8–13.
#include <filesystem>
#include <vector>

#include "polrig/io/manifest.h"
#include "polrig/study/navigation.h"

namespace polrig {

// One row of summary.csv.
struct ModeErrorSummary {
  NavigationMode mode = NavigationMode::Sins;
  ErrorStatistics lat, lon;       // degrees
  double final_north_m = 0, final_east_m = 0;
};
// Per mode of the run, against the dataset's truth (empty without one).
std::vector<ModeErrorSummary> summarize_navigation(const NavigationDataset& data, const NavigationRun& run);

std::vector<DatasetFile> report_navigation(const std::filesystem::path& dir, const NavigationDataset& data,
                                           const NavigationRun& run, const Rig& rig, bool plots);

}  // namespace polrig
