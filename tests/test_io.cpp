// Output plumbing: CSV text, folders that appear whole or not at all, manifests.
#include <gtest/gtest.h>

#include <cmath>
#include <filesystem>
#include <limits>
#include <stdexcept>
#include <string>

#include "polrig/io/csv.h"
#include "polrig/io/manifest.h"
#include "polrig/io/output_dir.h"
#include "support.h"

namespace polrig {
namespace {
namespace fs = std::filesystem;
using test::read_file;

fs::path fresh_dir(const std::string& name) {
  const fs::path p = fs::temp_directory_path() / ("polrig-test-io-" + name);
  fs::remove_all(p);
  return p;
}

TEST(Csv, WritesShortestExactNumbers) {
  CsvTable t({"a", "b", "c"});
  t.add_row({1.0, 0.1, 1.0 / 3.0});
  t.add_row({-2.5e-7, 360.0, 0.30000000000000004});
  EXPECT_EQ(t.text(), "a,b,c\n1,0.1,0.3333333333333333\n-2.5e-07,360,0.30000000000000004\n");
  EXPECT_EQ(t.rows(), 2u);
  EXPECT_THROW(t.add_row({1.0}), std::logic_error);
}

// The writers' last guard: no NaN or infinity leaves in a CSV, except NaN in a column declared
// to mean "not defined"; the message names the column, the row and the value.
TEST(Csv, RefusesNonFiniteValuesNamingTheColumnAndRow) {
  const double inf = std::numeric_limits<double>::infinity();
  const double nan = std::numeric_limits<double>::quiet_NaN();
  CsvTable t({"pair", "bsd_mV", "ratio_pct"});
  t.add_row({1, 0.5, 2});
  for (double bad : {inf, -inf, nan}) {
    try {
      t.add_row({2, bad, 1});
      FAIL() << "accepted " << bad;
    } catch (const std::runtime_error& e) {
      const std::string msg = e.what();
      EXPECT_NE(msg.find("column 'bsd_mV' of row 2 (pair = 2) is "), std::string::npos) << msg;
      EXPECT_NE(msg.find(std::isnan(bad) ? "is nan" : bad > 0 ? "is inf" : "is -inf"), std::string::npos) << msg;
    }
  }
  EXPECT_EQ(t.rows(), 1u);  // a refused row is not kept
  EXPECT_THROW(t.add_row({2, 1, nan}), std::runtime_error);
  t.allow_undefined("ratio_pct");
  t.add_row({2, 1, nan});
  EXPECT_THROW(t.add_row({3, 1, inf}), std::runtime_error);  // undefined is NaN, never infinity
  EXPECT_EQ(t.text(), "pair,bsd_mV,ratio_pct\n1,0.5,2\n2,1,nan\n");
}

TEST(OutputDir, AppearsOnlyOnCommit) {
  const fs::path base = fresh_dir("commit");
  const fs::path dest = base / "nested" / "out";
  {
    OutputDir out(dest, false);
    write_text_file(out.staging() / "x.csv", "x\n1\n");
    EXPECT_FALSE(fs::exists(dest));
    out.commit();
  }
  EXPECT_EQ(read_file(dest / "x.csv"), "x\n1\n");
  for (const auto& e : fs::directory_iterator(dest.parent_path()))
    EXPECT_EQ(e.path().filename(), "out");  // no staging folder left beside it
  fs::remove_all(base);
}

TEST(OutputDir, LeavesNothingWhenAbandoned) {
  const fs::path base = fresh_dir("abandon");
  const fs::path dest = base / "a" / "b" / "out";
  try {
    OutputDir out(dest, false);
    write_text_file(out.staging() / "half.csv", "x\n");
    throw std::runtime_error("simulated failure mid-way");
  } catch (const std::runtime_error&) {
  }
  EXPECT_FALSE(fs::exists(dest));
  EXPECT_FALSE(fs::exists(base / "a"));  // parents it created are removed again
  fs::remove_all(base);
}

TEST(OutputDir, RefusesToReplaceWithoutForce) {
  const fs::path base = fresh_dir("replace");
  const fs::path dest = base / "out";
  fs::create_directories(dest);
  write_text_file(dest / "old.txt", "old");
  EXPECT_THROW(OutputDir(dest, false), std::runtime_error);
  EXPECT_EQ(read_file(dest / "old.txt"), "old");
  {
    OutputDir out(dest, true);
    write_text_file(out.staging() / "new.txt", "new");
    EXPECT_EQ(read_file(dest / "old.txt"), "old");  // untouched until commit
    out.commit();
  }
  EXPECT_FALSE(fs::exists(dest / "old.txt"));
  EXPECT_EQ(read_file(dest / "new.txt"), "new");
  fs::remove_all(base);
}

TEST(Manifest, NamesEveryFileWithItsSchema) {
  const fs::path dir = fresh_dir("manifest");
  fs::create_directories(dir);
  write_manifest(dir, {"polrig study adc -o x", nullptr, {{"accuracy_limit.csv", 1, "limits"}}});
  const std::string m = read_file(dir / "manifest.yaml");
  EXPECT_NE(m.find("accuracy_limit.csv:"), std::string::npos);
  EXPECT_NE(m.find("schema: 1"), std::string::npos);
  EXPECT_NE(m.find("git_revision:"), std::string::npos);
  EXPECT_NE(m.find("command: polrig study adc -o x"), std::string::npos);
  EXPECT_FALSE(fs::exists(dir / "rig.yaml"));  // no rig, no rig file
  fs::remove_all(dir);
}

}  // namespace
}  // namespace polrig
