#pragma once
// Reading YAML for every YAML reader of io/ (rigs, scenes, params.yaml, truth.yaml,
// calibration.yaml, board.yaml, resume-state.yaml), private to io/. Each problem is an `Error`
// (RigError or DataError: exit 2) naming the file and, within it, the line:
// - read_yaml_file: a named regular file of at most `max_bytes` (checked before it is read);
// - load_yaml: the text's size, then a pass of yaml-cpp's event parser before any document is
//   built, which counts the nodes with every alias expanded (a "billion laughs" of nested
//   anchors is refused after a few aliases, not walked for minutes) and the nesting (yaml-cpp's
//   depth guard, and the depth an alias adds); then YAML::Load. Syntax errors are
//   "FILE:LINE:COLUMN: YAML syntax error: …";
// - refuse_duplicate_keys: a key given twice in one mapping (yaml-cpp keeps both and returns the
//   first), "FILE:LINE: key 'K': duplicate key (first at line N)".
#include <algorithm>
#include <cmath>
#include <cstdint>
#include <filesystem>
#include <fstream>
#include <map>
#include <set>
#include <sstream>
#include <string>
#include <string_view>
#include <vector>

#include <fmt/format.h>
#include <yaml-cpp/depthguard.h>
#include <yaml-cpp/eventhandler.h>
#include <yaml-cpp/yaml.h>

#include "polrig/io/measured.h"
#include "polrig/io/rig_yaml.h"
#include "polrig/quoted.h"

namespace polrig {

// A polrig YAML file is a few kilobytes; a rig may list up to kMaxStops table angles.
inline constexpr std::uintmax_t kMaxYamlBytes = 1u << 20;       // 1 MiB
inline constexpr std::size_t kMaxYamlNodes = 2'000'000;         // with every alias expanded
inline constexpr int kMaxYamlDepth = 500;                       // yaml-cpp's own depth guard

namespace yaml_detail {

struct Exceeded {
  YAML::Mark mark;
  std::string what;
};

// Counts the document's nodes and nesting as YAML::Load would build them, an alias counting
// the whole of its anchor's node.
class Budget : public YAML::EventHandler {
 public:
  void OnDocumentStart(const YAML::Mark&) override {}
  void OnDocumentEnd() override {}
  void OnNull(const YAML::Mark& m, YAML::anchor_t a) override { leaf(m, a); }
  void OnScalar(const YAML::Mark& m, const std::string&, YAML::anchor_t a, const std::string&) override { leaf(m, a); }
  void OnAlias(const YAML::Mark& m, YAML::anchor_t a) override {
    // yaml-cpp knows an anchor before its node ends, so `&x [*x]` would build a cycle.
    for (const Open& o : open_)
      if (o.anchor == a && a != YAML::NullAnchor)
        throw Exceeded{m, "an alias inside its own anchor's node (a cycle)"};
    add(m, anchors_[a]);
  }
  void OnSequenceStart(const YAML::Mark& m, const std::string&, YAML::anchor_t a, YAML::EmitterStyle::value) override {
    open(m, a);
  }
  void OnMapStart(const YAML::Mark& m, const std::string&, YAML::anchor_t a, YAML::EmitterStyle::value) override {
    open(m, a);
  }
  void OnSequenceEnd() override { close(); }
  void OnMapEnd() override { close(); }

 private:
  struct Size {
    std::size_t nodes = 1;
    int depth = 1;
  };
  struct Open {
    YAML::anchor_t anchor;
    Size size;
  };
  std::vector<Open> open_;
  std::map<YAML::anchor_t, Size> anchors_;
  std::size_t total_ = 0;

  void count(const YAML::Mark& m, const Size& s) {
    total_ += s.nodes;
    if (total_ > kMaxYamlNodes)
      throw Exceeded{m, fmt::format("the YAML expands to more than {} nodes (its aliases repeat what their anchors "
                                    "name): refused before it is built", kMaxYamlNodes)};
    if (static_cast<long long>(open_.size()) + s.depth > kMaxYamlDepth)
      throw Exceeded{m, fmt::format("the YAML nests deeper than the reader's limit of {} levels once its aliases "
                                    "are expanded", kMaxYamlDepth)};
  }
  void add(const YAML::Mark& m, const Size& s) {
    count(m, s);
    if (open_.empty()) return;
    Size& parent = open_.back().size;
    parent.nodes += s.nodes;
    parent.depth = std::max(parent.depth, s.depth + 1);
  }
  void leaf(const YAML::Mark& m, YAML::anchor_t a) {
    add(m, Size{});
    if (a) anchors_[a] = Size{};
  }
  void open(const YAML::Mark& m, YAML::anchor_t a) {
    count(m, Size{});
    open_.push_back({a, Size{}});
  }
  void close() {
    const Open o = open_.back();
    open_.pop_back();
    if (o.anchor) anchors_[o.anchor] = o.size;
    if (open_.empty()) return;
    Size& parent = open_.back().size;
    parent.nodes += o.size.nodes;
    parent.depth = std::max(parent.depth, o.size.depth + 1);
  }
};

}  // namespace yaml_detail

// The bytes of `path`, a regular file of at most `max_bytes`, for the reader of a `what` ("rig
// file", "parameter file").
template <class Error = RigError>
std::string read_yaml_file(const std::filesystem::path& path, std::string_view what,
                           std::uintmax_t max_bytes = kMaxYamlBytes) {
  std::error_code ec;
  const auto fail = [&](std::string_view why) {
    throw Error(fmt::format("{}: cannot read the {}: {}", path.empty() ? "''" : path.string(), what, why));
  };
  if (path.empty()) fail("an empty path (expected a file name)");
  if (std::filesystem::is_directory(path, ec)) fail("it is a directory (expected a file)");
  if (!std::filesystem::is_regular_file(path, ec))
    fail(std::filesystem::exists(path, ec) ? "not a regular file" : "no such file");
  const std::uintmax_t size = std::filesystem::file_size(path, ec);
  if (!ec && size > max_bytes)
    fail(fmt::format("{} bytes, more than the {} bytes a {} may have", size, max_bytes, what));
  std::ifstream in(path, std::ios::binary);
  std::stringstream buf;
  buf << in.rdbuf();
  if (!in && !in.eof()) fail("the file cannot be read");
  return buf.str();
}

// `needs` says how deep a valid file nests, for the message: "a rig file nests 3 levels".
template <class Error = RigError>
YAML::Node load_yaml(const std::string& text, std::string_view file, std::string_view needs,
                     std::uintmax_t max_bytes = kMaxRigYamlBytes) {
  if (text.size() > max_bytes)
    throw Error(fmt::format("{}: {} bytes of YAML, more than the reader's limit of {}", file, text.size(), max_bytes));
  try {
    std::istringstream in(text);
    YAML::Parser parser(in);
    yaml_detail::Budget budget;
    parser.HandleNextDocument(budget);
    return YAML::Load(text);
  } catch (const yaml_detail::Exceeded& e) {
    throw Error(fmt::format("{}:{}: {}", file, e.mark.line + 1, e.what));
  } catch (const YAML::DeepRecursion& e) {
    // The mark is where the scanner had got to, which may be past the too-deep place: the line
    // only.
    throw Error(fmt::format("{}:{}: the YAML nests deeper than the reader's limit of {} levels "
                            "({})", file, e.mark.line + 1, e.depth(), needs));
  } catch (const YAML::Exception& e) {
    throw Error(fmt::format("{}:{}:{}: YAML syntax error: {}", file, e.mark.line + 1,
                            e.mark.column + 1, e.msg));
  }
}

// Refuses a key that appears twice in one mapping, at any depth (the walk is bounded by
// load_yaml's node count).
template <class Error = DataError>
void refuse_duplicate_keys(const YAML::Node& node, std::string_view file) {
  if (node.IsSequence())
    for (const YAML::Node& item : node) refuse_duplicate_keys<Error>(item, file);
  if (!node.IsMap()) return;
  std::map<std::string, int> first_line;
  for (auto it = node.begin(); it != node.end(); ++it) {
    const std::string key = it->first.IsScalar() ? it->first.Scalar() : "?";
    const int line = it->first.Mark().line + 1;
    const auto [at, inserted] = first_line.emplace(key, line);
    if (!inserted)
      throw Error(fmt::format("{}:{}: key '{}': duplicate key (first at line {})", file, line, key, at->second));
    refuse_duplicate_keys<Error>(it->second, file);
  }
}

// A YAML data file's problems (calibration.yaml, start.yaml), "FILE:LINE: key 'K': problem":
// `node` gives the line (the file alone where it has none).
[[noreturn]] inline void refuse_key(const std::filesystem::path& file, const YAML::Node& node, const std::string& key,
                                    const std::string& problem) {
  const std::string where = node.Mark().is_null() ? file.string() : fmt::format("{}:{}", file.string(), node.Mark().line + 1);
  throw DataError(fmt::format("{}: key '{}': {}", where, key, problem));
}

inline void refuse_unknown_keys(const std::filesystem::path& file, const YAML::Node& map, const std::set<std::string>& known,
                                const std::string& prefix, const std::string& expected) {
  for (const auto& kv : map) {
    const std::string key = kv.first.IsScalar() ? kv.first.Scalar() : "?";
    if (!known.contains(key)) refuse_key(file, kv.first, prefix + key, "unknown key (expected " + expected + ")");
  }
}

inline double number_at(const std::filesystem::path& file, const YAML::Node& n, const std::string& key) {
  double v = 0;
  try {
    v = n.as<double>();
  } catch (const YAML::Exception&) {
    refuse_key(file, n, key, fmt::format("expected a number, got '{}'", quoted_value(n.IsScalar() ? n.Scalar() : "")));
  }
  if (!std::isfinite(v)) refuse_key(file, n, key, fmt::format("expected a finite number, got '{}'", quoted_value(n.Scalar())));
  return v;
}

}  // namespace polrig
