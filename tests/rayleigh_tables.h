#pragma once
// The exact tables of data/rayleigh-tables (Natraj, Li & Yung 2009; a copy of shared's development
// set): one file's blocks (one per ground albedo) of rows (μ₀, μ, the value at φ = 0, 30, …, 180°).
#include <fstream>
#include <sstream>
#include <string>
#include <vector>

#include <gtest/gtest.h>

namespace polrig::test {

struct TableRow {
  double mu0 = 0, mu = 0;
  double v[7] = {};
};
using TableBlocks = std::vector<std::vector<TableRow>>;

inline TableBlocks read_rayleigh_table(const std::string& name) {
  const std::string path = std::string(POLRIG_SOURCE_DIR) + "/data/rayleigh-tables/" + name;
  std::ifstream in(path);
  EXPECT_TRUE(in) << path;
  TableBlocks blocks;
  std::string line;
  while (std::getline(in, line)) {
    if (line.find("albedo") != std::string::npos) {
      blocks.emplace_back();
      continue;
    }
    std::istringstream is(line);
    TableRow r;
    if (!(is >> r.mu0 >> r.mu)) continue;
    for (double& x : r.v) is >> x;
    if (!blocks.empty()) blocks.back().push_back(r);
  }
  return blocks;
}

}  // namespace polrig::test
