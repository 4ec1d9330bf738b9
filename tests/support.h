// Helpers shared by the test programs: files and temporary folders, CSV text, substring
// assertions and running the polrig executable. Header-only; tests/CMakeLists.txt defines
// POLRIG_EXE and POLRIG_SOURCE_DIR for every test target.
#pragma once

#include <gtest/gtest.h>
#include <sys/wait.h>
#include <unistd.h>

#include <cctype>
#include <cmath>
#include <cstdint>
#include <cstdlib>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <string>
#include <system_error>
#include <utility>
#include <vector>

namespace polrig::test {

namespace fs = std::filesystem;

// The polrig executable under test, and the shipped rig file of the default (indoor) rig.
inline const std::string kPolrigExe = POLRIG_EXE;
inline const std::string kDefaultRigFile = POLRIG_SOURCE_DIR "/rigs/wang2019-indoor.yaml";

// ---------------------------------------------------------------------------------------------
// Files and folders
// ---------------------------------------------------------------------------------------------

// The bytes of file `p` ("" if it cannot be read).
inline std::string read_file(const fs::path& p) {
  std::ifstream in(p, std::ios::binary);
  std::stringstream s;
  s << in.rdbuf();
  return s.str();
}

// Replaces (or creates) file `p` with exactly `text`.
inline void write_file(const fs::path& p, const std::string& text) {
  std::ofstream out(p, std::ios::binary);
  out << text;
}

// A fresh folder under the system temp folder, named after `prefix`, the running test, the
// process and a counter; removed with the object.
class TempDir {
 public:
  explicit TempDir(const std::string& prefix) {
    static int counter = 0;
    const auto* info = ::testing::UnitTest::GetInstance()->current_test_info();
    path_ = fs::temp_directory_path() /
            (prefix + std::string(info ? info->name() : "x") + "_" + std::to_string(::getpid()) +
             "_" + std::to_string(counter++));
    fs::remove_all(path_);
    fs::create_directories(path_);
  }
  ~TempDir() {
    std::error_code ec;
    fs::remove_all(path_, ec);
  }
  TempDir(const TempDir&) = delete;
  TempDir& operator=(const TempDir&) = delete;

  const fs::path& path() const { return path_; }

 private:
  fs::path path_;
};

// The names of the entries of folder `parent` for which `keep(name)` holds (none if `parent`
// does not exist).
template <class Keep>
std::vector<std::string> entries_where(const fs::path& parent, Keep keep) {
  std::vector<std::string> found;
  std::error_code ec;
  if (!fs::exists(parent, ec)) return found;
  for (const auto& e : fs::directory_iterator(parent)) {
    const std::string f = e.path().filename().string();
    if (keep(f)) found.push_back(f);
  }
  return found;
}

// True if file `p` starts with the 8-byte PNG signature (and has more after it).
inline bool starts_with_png_signature(const fs::path& p) {
  const std::string data = read_file(p);
  return data.size() > 8 && data.compare(0, 8, std::string("\x89PNG\r\n\x1a\n", 8)) == 0;
}

// Rewrites the data window in the header of the OpenEXR file `p` to claim `width` × `height`
// pixels (its pixels left as they are): a forged header, as an adversary's file would have.
inline void claim_exr_size(const fs::path& p, int width, int height) {
  std::string bytes = read_file(p);
  const std::string tag("dataWindow\0box2i\0", 17);
  const std::size_t at = bytes.find(tag);
  ASSERT_NE(at, std::string::npos) << p << " has no dataWindow";
  const std::size_t box = at + tag.size() + 4;  // past the attribute's size
  std::int32_t v[4];
  std::memcpy(v, bytes.data() + box, sizeof v);  // x_min, y_min, x_max, y_max (little endian)
  v[2] = v[0] + width - 1;
  v[3] = v[1] + height - 1;
  std::memcpy(bytes.data() + box, v, sizeof v);
  write_file(p, bytes);
}

// ---------------------------------------------------------------------------------------------
// Text and CSV
// ---------------------------------------------------------------------------------------------

// The lines of `text`, without their '\n'.
inline std::vector<std::string> lines_of(const std::string& text) {
  std::vector<std::string> out;
  std::stringstream ss(text);
  for (std::string line; std::getline(ss, line);) out.push_back(line);
  return out;
}

// The fields of one CSV line (no quoting), keeping a trailing empty field.
inline std::vector<std::string> split(const std::string& line, char sep = ',') {
  std::vector<std::string> out;
  std::stringstream ss(line);
  for (std::string f; std::getline(ss, f, sep);) out.push_back(f);
  if (!line.empty() && line.back() == sep) out.emplace_back();
  return out;
}

// A CSV file as text cells: the header and the data rows.
struct Csv {
  std::vector<std::string> header;
  std::vector<std::vector<std::string>> rows;

  // The index of column `name`; a test failure (and 0) if there is none.
  std::size_t col(const std::string& name) const {
    for (std::size_t c = 0; c < header.size(); ++c)
      if (header[c] == name) return c;
    ADD_FAILURE() << "no column " << name;
    return 0;
  }
};

// File `p` as a Csv: its first line is the header (an empty Csv for an empty or missing file).
inline Csv read_csv(const fs::path& p) {
  Csv csv;
  const std::vector<std::string> lines = lines_of(read_file(p));
  if (lines.empty()) return csv;
  csv.header = split(lines[0]);
  for (std::size_t i = 1; i < lines.size(); ++i) csv.rows.push_back(split(lines[i]));
  return csv;
}

// ---------------------------------------------------------------------------------------------
// Substring assertions: EXPECT_HAS, EXPECT_LACKS, EXPECT_STARTS
// ---------------------------------------------------------------------------------------------

// gtest predicate-formatter: `hay` contains `needle`, with the whole text on failure.
inline ::testing::AssertionResult HasText(const char* hay_expr, const char* needle_expr,
                                          const std::string& hay, const std::string& needle) {
  if (hay.find(needle) != std::string::npos) return ::testing::AssertionSuccess();
  return ::testing::AssertionFailure() << hay_expr << " does not contain " << needle_expr
                                       << "\n  text:     \"" << hay << "\"\n  expected: \""
                                       << needle << "\"";
}

// gtest predicate-formatter: `hay` does not contain `needle`.
inline ::testing::AssertionResult LacksText(const char* hay_expr, const char* needle_expr,
                                            const std::string& hay, const std::string& needle) {
  if (hay.find(needle) == std::string::npos) return ::testing::AssertionSuccess();
  return ::testing::AssertionFailure() << hay_expr << " contains " << needle_expr
                                       << " but should not\n  text: \"" << hay << "\"";
}

// gtest predicate-formatter: `hay` starts with `prefix`.
inline ::testing::AssertionResult StartsWith(const char* hay_expr, const char* prefix_expr,
                                             const std::string& hay, const std::string& prefix) {
  if (hay.rfind(prefix, 0) == 0) return ::testing::AssertionSuccess();
  return ::testing::AssertionFailure() << hay_expr << " does not start with " << prefix_expr
                                       << "\n  text:     \"" << hay << "\"\n  expected: \""
                                       << prefix << "...\"";
}

#define EXPECT_HAS(hay, needle) EXPECT_PRED_FORMAT2(::polrig::test::HasText, hay, needle)
#define EXPECT_LACKS(hay, needle) EXPECT_PRED_FORMAT2(::polrig::test::LacksText, hay, needle)
#define EXPECT_STARTS(hay, prefix) EXPECT_PRED_FORMAT2(::polrig::test::StartsWith, hay, prefix)

// ---------------------------------------------------------------------------------------------
// Running the polrig executable
// ---------------------------------------------------------------------------------------------

// `s` single-quoted for sh.
inline std::string shell_quote(const std::string& s) {
  std::string out = "'";
  for (char c : s) out += (c == '\'') ? std::string("'\\''") : std::string(1, c);
  return out + "'";
}
inline std::string shell_quote(const fs::path& p) { return shell_quote(p.string()); }

// True if `gnuplot` runs (the plotting commands need it).
inline bool gnuplot_present() { return std::system("gnuplot --version >/dev/null 2>&1") == 0; }

// What gnuplot plotted, read back through its `set table`: per PNG of a script (render_plots'),
// per curve title, the rows of numbers it tabulated ("nan" as NaN; a pixel type letter dropped).
using TabulatedCurves = std::vector<std::pair<std::string, std::vector<std::vector<double>>>>;
inline std::vector<std::pair<std::string, TabulatedCurves>> tabulate_script(const fs::path& dir,
                                                                            const std::string& script_name) {
  std::string script;
  std::vector<std::string> pngs;
  for (const std::string& line : lines_of(read_file(dir / script_name))) {
    // The table prints numbers in the axes' tic format: gnuplot's default (6 digits) instead.
    if (line.rfind("set terminal", 0) == 0 || line.rfind("set format", 0) == 0) continue;
    if (line.rfind("set output", 0) == 0) {
      const auto a = line.find('"'), b = line.rfind('"');
      pngs.push_back(line.substr(a + 1, b - a - 1));
      script += "set table '" + pngs.back() + ".table'\n";
    } else if (line == "unset output") {
      script += "unset table\n";
    } else {
      script += line + "\n";
    }
  }
  write_file(dir / "tabulate.gp", script);
  const std::string cmd = "cd " + shell_quote(dir) + " && gnuplot tabulate.gp 2>/dev/null";
  EXPECT_EQ(std::system(cmd.c_str()), 0) << cmd;
  std::vector<std::pair<std::string, TabulatedCurves>> out;
  for (const std::string& png : pngs) {
    TabulatedCurves curves;
    for (const std::string& line : lines_of(read_file(dir / (png + ".table")))) {
      const std::string tag = "# Curve title: \"";
      if (line.rfind(tag, 0) == 0) {
        curves.push_back({line.substr(tag.size(), line.size() - tag.size() - 1), {}});
        continue;
      }
      if (line.empty() || line[0] == '#' || curves.empty()) continue;
      std::stringstream ss(line);
      std::vector<double> row;
      for (std::string word; ss >> word;) {
        if (word == "nan" || word == "NaN") row.push_back(std::nan(""));
        else if (std::isdigit(static_cast<unsigned char>(word.back())) || word.back() == '.') row.push_back(std::stod(word));
      }
      curves.back().second.push_back(row);
    }
    out.push_back({png, curves});
  }
  return out;
}

// What one run of the polrig executable gave.
struct RunResult {
  int status = -1;  // exit status, or -1 if the program did not exit normally
  std::string out, err;
};

// Runs `polrig ARGS` through sh (ARGS already shell-quoted where needed), with `prefix` put
// before the program (e.g. "cd X && " or "PATH=… "); stdout and stderr go to the two files.
// The sphere cache is off (the user's ~/.cache untouched, each run solving) unless the test's
// environment or `prefix` ("POLRIG_CACHE_DIR=DIR ") names one.
inline RunResult run_polrig(const std::string& args, const std::string& prefix,
                            const fs::path& stdout_file, const fs::path& stderr_file) {
  const std::string cmd = "export POLRIG_CACHE_DIR=\"${POLRIG_CACHE_DIR:-off}\"; " + prefix +
                          shell_quote(kPolrigExe) + " " + args + " >" +
                          shell_quote(stdout_file) + " 2>" + shell_quote(stderr_file);
  const int rc = std::system(cmd.c_str());
  RunResult r;
  r.status = (rc != -1 && WIFEXITED(rc)) ? WEXITSTATUS(rc) : -1;
  r.out = read_file(stdout_file);
  r.err = read_file(stderr_file);
  return r;
}

// Base of the fixtures that run the polrig executable: a fresh temporary folder `tmp` per
// test, and polrig() / ok() to run the program.
class PolrigTest : public ::testing::Test {
 protected:
  using Result = RunResult;

  // `tmp_prefix` starts the name of the temporary folder; the n-th run's stdout and stderr are
  // kept in tmp/`log_folder` (tmp itself when it is empty) as stdout-n.txt and stderr-n.txt.
  PolrigTest(const std::string& tmp_prefix, const std::string& log_folder)
      : temp_dir_(tmp_prefix), logs_(log_folder.empty() ? tmp : tmp / log_folder) {}

  // Runs `polrig ARGS` (see run_polrig) and returns what it gave.
  Result polrig(const std::string& args, const std::string& prefix = "") {
    const int n = runs_++;
    fs::create_directories(logs_);
    return run_polrig(args, prefix, logs_ / ("stdout-" + std::to_string(n) + ".txt"),
                      logs_ / ("stderr-" + std::to_string(n) + ".txt"));
  }

  // Runs and expects success; returns the result.
  Result ok(const std::string& args, const std::string& prefix = "") {
    Result r = polrig(args, prefix);
    EXPECT_EQ(r.status, 0) << "polrig " << args << "\nstderr: " << r.err << "\nstdout: " << r.out;
    return r;
  }

 private:
  TempDir temp_dir_;  // before `tmp`, which is initialized from it

 protected:
  const fs::path tmp = temp_dir_.path();

 private:
  fs::path logs_;
  int runs_ = 0;
};

}  // namespace polrig::test
