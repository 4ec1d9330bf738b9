#include "polrig/io/dataset.h"

#include "polrig/io/csv.h"

namespace polrig {

std::vector<DatasetFile> write_simulation(const std::filesystem::path& dir, const Simulation& sim) {
  std::vector<std::string> columns{"stop", "theta_R_deg", "theta_deg", "d", "E1_Wm2", "E2_Wm2",
                                   "E3_Wm2", "E4_Wm2", "E5_Wm2", "E6_Wm2", "V1_ideal", "V2_ideal",
                                   "V3_ideal", "V1_ecc", "V2_ecc", "V3_ecc", "V1", "V2", "V3",
                                   "V1_std", "V2_std", "V3_std"};
  // A light that changes during the run (the sky): each stop's time since the first.
  if (sim.time_dependent) columns.insert(columns.begin() + 2, "t_s");
  CsvTable stops(columns);
  for (std::size_t s = 0; s < sim.stops.size(); ++s) {
    const Stop& st = sim.stops[s];
    std::vector<double> row{static_cast<double>(s), st.theta_R_deg, st.light.theta_deg,
                            st.light.d};
    if (sim.time_dependent) row.insert(row.begin() + 2, st.t_s);
    row.insert(row.end(), st.light.E_Wm2.begin(), st.light.E_Wm2.end());
    for (const auto* v : {&st.V_ideal, &st.V_ecc, &st.V_mean, &st.V_std})
      row.insert(row.end(), v->begin(), v->end());
    stops.add_row(row);
  }
  write_text_file(dir / "stops.csv", stops.text());
  std::vector<DatasetFile> files{
      {"stops.csv", 1,
       "one row per table stop: pose, light, ideal/eccentric voltages and the mean and "
       "standard deviation of the quantized noisy samples (volts)"}};

  if (!sim.samples.empty()) {
    CsvTable samples({"stop", "theta_R_deg", "sample", "V1", "V2", "V3"});
    const std::size_t n = static_cast<std::size_t>(sim.samples_per_stop);
    for (std::size_t k = 0; k < sim.samples.size(); ++k) {
      const auto& v = sim.samples[k];
      samples.add_row({static_cast<double>(k / n), sim.stops[k / n].theta_R_deg,
                       static_cast<double>(k % n), v[0], v[1], v[2]});
    }
    write_text_file(dir / "samples.csv", samples.text());
    files.push_back({"samples.csv", 1, "every ADC-quantized noisy sample (volts)"});
  }
  return files;
}

}  // namespace polrig
