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
std::vector<DatasetFile> report_adc_limits(const std::filesystem::path& dir,
                                           const std::vector<AdcLimit>& limits, bool plots);

}  // namespace polrig
