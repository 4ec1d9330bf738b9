#include "polrig/ranks.h"

namespace polrig {

namespace {
class ThisProcessOnly final : public Ranks {
 public:
  int rank() const override { return 0; }
  int size() const override { return 1; }
  std::vector<std::byte> gather(std::span<const std::byte> mine) const override {
    return {mine.begin(), mine.end()};
  }
  void broadcast(std::vector<std::byte>&) const override {}
  std::optional<std::string> first_failure(const std::optional<std::string>& mine) const override {
    return mine;
  }
};
}  // namespace

const Ranks& this_process_only() {
  static const ThisProcessOnly ranks;
  return ranks;
}

}  // namespace polrig
