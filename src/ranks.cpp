#include "polrig/ranks.h"

#include <charconv>
#include <cstdlib>
#include <string_view>

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

namespace {
// The variable's value as a whole number ≥ 0, or -1 when it is unset or not a number.
int environment_number(const char* name) {
  const char* text = std::getenv(name);
  if (!text) return -1;
  const std::string_view s(text);
  int v = -1;
  const auto [end, err] = std::from_chars(s.data(), s.data() + s.size(), v);
  return err == std::errc() && end == s.data() + s.size() && v >= 0 ? v : -1;
}
}  // namespace

Launch launch_from_environment() {
  struct Names {
    const char* rank;
    const char* size;
  };
  // OpenMPI's mpirun, MPICH's hydra and srun --mpi=pmi2, PMIx (srun --mpi=pmix, prterun).
  for (const Names& n : {Names{"OMPI_COMM_WORLD_RANK", "OMPI_COMM_WORLD_SIZE"}, Names{"PMI_RANK", "PMI_SIZE"},
                         Names{"PMIX_RANK", "SLURM_NTASKS"}}) {
    const int rank = environment_number(n.rank);
    if (rank < 0) continue;
    const int size = environment_number(n.size);
    return {true, rank, size > 0 ? size : 0};
  }
  return {};
}

}  // namespace polrig
