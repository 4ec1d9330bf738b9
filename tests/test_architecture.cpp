// The include graph keeps the part order of docs/architecture.md: every
// `#include "polrig/<part>/…"` in include/polrig and src runs down the Parts table (or within a
// part), never up. The order is read from the table itself, so the document is the rule.
#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>
#include <map>
#include <regex>
#include <sstream>
#include <string>
#include <vector>

namespace {

namespace fs = std::filesystem;
const fs::path kRoot = POLRIG_SOURCE_DIR;

std::string read(const fs::path& p) {
  std::ifstream in(p, std::ios::binary);
  std::stringstream s;
  s << in.rdbuf();
  return s.str();
}

constexpr const char* kTopLevel = "top level";

// The parts of the "## Parts" table, bottom first, as the table lists them: each row's first
// cell is `part/` or "top level".
std::vector<std::string> part_order(const std::string& architecture_md) {
  std::vector<std::string> parts;
  const auto begin = architecture_md.find("\n## Parts");
  if (begin == std::string::npos) return parts;
  std::istringstream in(architecture_md.substr(begin + 1));
  std::string line;
  std::getline(in, line);  // the heading
  const std::regex row(R"(^\| *(?:`([a-z_]+)/`|(top level)) *\|)");
  bool in_table = false;
  while (std::getline(in, line)) {
    if (line.starts_with("## ")) break;
    std::smatch m;
    if (std::regex_search(line, m, row)) {
      parts.push_back(m[1].matched ? m[1].str() : kTopLevel);
      in_table = true;
    } else if (in_table && !line.starts_with("|")) {
      break;
    }
  }
  return parts;
}

// The part a file belongs to: include/polrig/<part>/… or src/<part>/…; a file directly in
// include/polrig or src is top level.
std::string part_of(const fs::path& relative) {
  auto it = relative.begin();
  const std::string first = (it++)->string();
  if (first == "include") ++it;  // polrig
  const fs::path rest = [&] {
    fs::path r;
    for (; it != relative.end(); ++it) r /= *it;
    return r;
  }();
  return std::distance(rest.begin(), rest.end()) > 1 ? rest.begin()->string() : kTopLevel;
}

struct Include {
  std::string file;  // relative to the source root
  int line;
  std::string part;  // the included part
  std::string text;  // the included path
};

// Every `#include "polrig/…"` of the given text.
std::vector<Include> includes_of(const std::string& file, const std::string& text) {
  std::vector<Include> out;
  const std::regex inc(R"(^\s*#\s*include\s*"polrig/([^"]+)\")");
  std::istringstream in(text);
  std::string line;
  for (int n = 1; std::getline(in, line); ++n) {
    std::smatch m;
    if (!std::regex_search(line, m, inc)) continue;
    const std::string path = m[1].str();
    const auto slash = path.find('/');
    out.push_back({file, n, slash == std::string::npos ? kTopLevel : path.substr(0, slash), path});
  }
  return out;
}

// The edges that run up the table (or touch a part it does not list), one message each:
// "src/source/x.cpp:3: source → study (polrig/study/cs.h): study is above source".
std::vector<std::string> violations(const std::vector<std::string>& order,
                                    const std::vector<std::pair<std::string, std::string>>& files) {
  std::map<std::string, std::size_t> rank;
  for (std::size_t i = 0; i < order.size(); ++i) rank[order[i]] = i;
  std::vector<std::string> bad;
  for (const auto& [file, text] : files) {
    const std::string from = part_of(file);
    if (!rank.count(from)) {
      bad.push_back(file + ": part '" + from + "' is not in docs/architecture.md's Parts table");
      continue;
    }
    for (const Include& i : includes_of(file, text)) {
      const std::string edge = file + ":" + std::to_string(i.line) + ": " + from + " → " + i.part +
                               " (polrig/" + i.text + ")";
      if (!rank.count(i.part))
        bad.push_back(edge + ": part '" + i.part + "' is not in the Parts table");
      else if (rank[i.part] > rank[from])
        bad.push_back(edge + ": " + i.part + " is above " + from + " in the Parts table");
    }
  }
  return bad;
}

std::vector<std::pair<std::string, std::string>> project_files() {
  std::vector<std::pair<std::string, std::string>> files;
  for (const char* dir : {"include/polrig", "src"})
    for (const auto& e : fs::recursive_directory_iterator(kRoot / dir)) {
      const std::string ext = e.path().extension().string();
      if (e.is_regular_file() && (ext == ".h" || ext == ".cpp"))
        files.emplace_back(fs::relative(e.path(), kRoot).generic_string(), read(e.path()));
    }
  return files;
}

TEST(Architecture, ThePartsTableListsTheLayersBottomFirst) {
  const std::vector<std::string> order = part_order(read(kRoot / "docs/architecture.md"));
  ASSERT_GE(order.size(), 10u) << "docs/architecture.md has no Parts table";
  EXPECT_EQ(order.front(), kTopLevel);
  EXPECT_EQ(order.back(), "cli");
}

TEST(Architecture, NoIncludeRunsBackUpThePartsTable) {
  const std::vector<std::string> order = part_order(read(kRoot / "docs/architecture.md"));
  const auto files = project_files();
  ASSERT_GT(files.size(), 50u);
  std::size_t edges = 0;
  for (const auto& [file, text] : files) edges += includes_of(file, text).size();
  EXPECT_GT(edges, 100u);
  for (const std::string& v : violations(order, files)) ADD_FAILURE() << v;
}

// The check itself: an edge up the table is named with its file, line and parts.
TEST(Architecture, AnEdgeUpTheTableIsNamed) {
  const std::vector<std::string> order{kTopLevel, "optics", "source", "study", "cli"};
  const auto bad = violations(order, {{"src/source/x.cpp", "#include \"polrig/optics/lens.h\"\n"
                                                           "#include \"polrig/units.h\"\n"
                                                           "  #include \"polrig/study/cs.h\"\n"},
                                      {"include/polrig/units.h", "#include \"polrig/cli/cli.h\"\n"},
                                      {"src/nowhere/y.cpp", ""}});
  ASSERT_EQ(bad.size(), 3u);
  EXPECT_EQ(bad[0], "src/source/x.cpp:3: source → study (polrig/study/cs.h): study is above source in the Parts table");
  EXPECT_EQ(bad[1], "include/polrig/units.h:1: top level → cli (polrig/cli/cli.h): cli is above top level in the Parts table");
  EXPECT_EQ(bad[2], "src/nowhere/y.cpp: part 'nowhere' is not in docs/architecture.md's Parts table");
}

}  // namespace
