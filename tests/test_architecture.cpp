// The include graph keeps the part order of docs/architecture.md: every include of a project
// header in include/polrig and src (`#include "polrig/…"` or `<polrig/…>`, or a path relative to
// the including file that reaches into include/polrig or src) runs down the Parts table (or
// within a part), never up, and keeps the "includes only …" promises the table's rows make. The
// order and the promises are read from the table itself, so the document is the rule. A relative
// path that climbs out of its folder (`../`) is flagged too: project headers are included as
// "polrig/…".
#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>
#include <map>
#include <regex>
#include <set>
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

// The "includes only …" promises of the Parts table: part → the parts it may include besides
// itself, read from its row's "owns" cell ("includes only top-level headers and `optics/`").
std::map<std::string, std::set<std::string>> part_promises(const std::string& architecture_md) {
  std::map<std::string, std::set<std::string>> promises;
  const auto begin = architecture_md.find("\n## Parts");
  if (begin == std::string::npos) return promises;
  std::istringstream in(architecture_md.substr(begin + 1));
  std::string line;
  std::getline(in, line);
  const std::regex row(R"(^\| *`([a-z_]+)/` *\|([^|]*)\|)");
  const std::regex only(R"(includes only ([^)|]*))");
  const std::regex part(R"(`([a-z_]+)/`)");
  while (std::getline(in, line)) {
    if (line.starts_with("## ")) break;
    std::smatch m, o;
    if (!std::regex_search(line, m, row)) continue;
    const std::string owns = m[2].str();
    if (!std::regex_search(owns, o, only)) continue;
    std::set<std::string>& allowed = promises[m[1].str()];
    const std::string list = o[1].str();
    if (list.find("top-level") != std::string::npos) allowed.insert(kTopLevel);
    for (auto it = std::sregex_iterator(list.begin(), list.end(), part); it != std::sregex_iterator(); ++it)
      allowed.insert((*it)[1].str());
  }
  return promises;
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
  std::string file;   // relative to the source root
  int line;
  std::string part;   // the included part
  std::string text;   // the path as written
  bool climbs;        // a relative path with `..`
};

// Every include of a project header in the given text: `polrig/…` in quotes or angle brackets,
// or a quoted path that, resolved against the including file's folder, lies in include/polrig
// or src (a file's own folder's headers, such as "cli.h", stay in its part).
std::vector<Include> includes_of(const std::string& file, const std::string& text) {
  std::vector<Include> out;
  const std::regex inc(R"(^\s*#\s*include\s*([<"])([^>"]+)[>"])");
  std::istringstream in(text);
  std::string line;
  for (int n = 1; std::getline(in, line); ++n) {
    std::smatch m;
    if (!std::regex_search(line, m, inc)) continue;
    const std::string path = m[2].str();
    if (path.starts_with("polrig/")) {
      out.push_back({file, n, part_of(fs::path("include") / path), path, false});
      continue;
    }
    if (m[1].str() == "<") continue;  // a library's header
    const fs::path resolved = (fs::path(file).parent_path() / path).lexically_normal();
    const std::string r = resolved.generic_string();
    if (r.starts_with("include/polrig/") || r.starts_with("src/"))
      out.push_back({file, n, part_of(resolved), path, path.find("..") != std::string::npos});
  }
  return out;
}

// The edges that run up the table (or touch a part it does not list), one message each:
// "src/source/x.cpp:3: source → study (polrig/study/cs.h): study is above source".
std::vector<std::string> violations(const std::vector<std::string>& order,
                                    const std::vector<std::pair<std::string, std::string>>& files,
                                    const std::map<std::string, std::set<std::string>>& promises = {}) {
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
                               " (" + i.text + ")";
      const auto promise = promises.find(from);
      if (i.climbs)
        bad.push_back(edge + ": a relative path out of its folder; include project headers as \"polrig/…\"");
      if (!rank.count(i.part))
        bad.push_back(edge + ": part '" + i.part + "' is not in the Parts table");
      else if (rank[i.part] > rank[from])
        bad.push_back(edge + ": " + i.part + " is above " + from + " in the Parts table");
      else if (i.part != from && promise != promises.end() && !promise->second.count(i.part))
        bad.push_back(edge + ": the Parts table says " + from + "/ includes only " +
                      [&] {
                        std::string list;
                        for (const std::string& p : promise->second)
                          list += (list.empty() ? "" : ", ") + (p == kTopLevel ? p : p + "/");
                        return list;
                      }());
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

TEST(Architecture, ThePartsTableMakesItsIncludesOnlyPromises) {
  const auto promises = part_promises(read(kRoot / "docs/architecture.md"));
  ASSERT_EQ(promises.size(), 4u);
  EXPECT_EQ(promises.at("sky"), (std::set<std::string>{kTopLevel, "optics"}));
  EXPECT_EQ(promises.at("spectral"), (std::set<std::string>{kTopLevel}));
  EXPECT_EQ(promises.at("ins"), (std::set<std::string>{kTopLevel}));
  EXPECT_EQ(promises.at("compass"), (std::set<std::string>{kTopLevel, "sky"}));
}

TEST(Architecture, NoIncludeRunsBackUpThePartsTable) {
  const std::string md = read(kRoot / "docs/architecture.md");
  const std::vector<std::string> order = part_order(md);
  const auto files = project_files();
  ASSERT_GT(files.size(), 50u);
  std::size_t edges = 0;
  for (const auto& [file, text] : files) edges += includes_of(file, text).size();
  EXPECT_GT(edges, 100u);
  for (const std::string& v : violations(order, files, part_promises(md))) ADD_FAILURE() << v;
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

// Angle brackets, spaces after the #, and relative paths are includes too; a relative path out
// of its folder is flagged even when the edge is allowed; a part's own headers ("cli.h") are not.
TEST(Architecture, AnyIncludeSpellingIsChecked) {
  const std::vector<std::string> order{kTopLevel, "optics", "sky", "source", "study", "cli"};
  const auto bad = violations(order, {{"src/sky/m.cpp", "#include <polrig/study/cs.h>\n"
                                                        "# include \"../../include/polrig/study/cs.h\"\n"
                                                        "#include \"../optics/ray_math.h\"\n"
                                                        "#include <tbb/parallel_for.h>\n"
                                                        "#include \"local.h\"\n"},
                                      {"src/cli/c.cpp", "#include \"cli.h\"\n#include <fmt/format.h>\n"}});
  ASSERT_EQ(bad.size(), 4u) << ::testing::PrintToString(bad);
  EXPECT_EQ(bad[0], "src/sky/m.cpp:1: sky → study (polrig/study/cs.h): study is above sky in the Parts table");
  EXPECT_EQ(bad[1], "src/sky/m.cpp:2: sky → study (../../include/polrig/study/cs.h): a relative path out of its folder; include project headers as \"polrig/…\"");
  EXPECT_EQ(bad[2], "src/sky/m.cpp:2: sky → study (../../include/polrig/study/cs.h): study is above sky in the Parts table");
  EXPECT_EQ(bad[3], "src/sky/m.cpp:3: sky → optics (../optics/ray_math.h): a relative path out of its folder; include project headers as \"polrig/…\"");
}

// The promises: sky/ may include optics/ and top-level headers, not geometry/, which the
// table's order alone would allow (it sits below sky/ here).
TEST(Architecture, AnIncludeBreakingAPromiseIsNamed) {
  const std::vector<std::string> order{kTopLevel, "optics", "geometry", "sky", "compass", "cli"};
  const std::map<std::string, std::set<std::string>> promises{{"sky", {kTopLevel, "optics"}},
                                                              {"compass", {kTopLevel, "sky"}}};
  const auto bad = violations(order, {{"src/sky/a.cpp", "#include \"polrig/optics/lens.h\"\n"
                                                        "#include \"polrig/units.h\"\n"
                                                        "#include \"polrig/geometry/turn.h\"\n"},
                                      {"src/compass/b.cpp", "#include \"polrig/sky/sun.h\"\n"
                                                            "#include \"polrig/optics/lens.h\"\n"}},
                              promises);
  ASSERT_EQ(bad.size(), 2u) << ::testing::PrintToString(bad);
  EXPECT_EQ(bad[0], "src/sky/a.cpp:3: sky → geometry (polrig/geometry/turn.h): the Parts table says sky/ includes only optics/, top level");
  EXPECT_EQ(bad[1], "src/compass/b.cpp:2: compass → optics (polrig/optics/lens.h): the Parts table says compass/ includes only sky/, top level");
}

}  // namespace
