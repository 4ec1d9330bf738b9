// The ranks of an MPI job (-DPOLRIG_MPI=ON): MPI's C API, called from the main thread only.
#include <mpi.h>

#include <algorithm>
#include <chrono>
#include <cstdint>
#include <stdexcept>
#include <string>
#include <thread>

#include "polrig/ranks.h"

namespace polrig {

namespace {

// MPI counts are ints: messages go in pieces of at most 1 GiB, so a rank may hold any size.
constexpr std::size_t kPiece = std::size_t{1} << 30;

// Waits for a request, sleeping between tests (50 µs, doubling up to 2 ms) instead of MPI's
// busy polling: a rank that waits for the others (rank 1 while rank 0 writes a block, rank 0
// while a slower rank computes) then leaves its core to the ranks and threads that work, which
// matters whenever ranks × --threads fill the cores. The added latency is at most 2 ms per
// collective, against blocks that take far longer.
void wait_politely(MPI_Request& request) {
  auto pause = std::chrono::microseconds(50);
  for (int done = 0;;) {
    MPI_Test(&request, &done, MPI_STATUS_IGNORE);
    if (done) return;
    std::this_thread::sleep_for(pause);
    pause = std::min(2 * pause, std::chrono::microseconds(2000));
  }
}

void send_bytes(const std::byte* data, std::size_t n, int to) {
  for (std::size_t at = 0; at < n; at += kPiece) {
    MPI_Request r;
    MPI_Isend(data + at, static_cast<int>(std::min(kPiece, n - at)), MPI_BYTE, to, 0, MPI_COMM_WORLD, &r);
    wait_politely(r);
  }
}

void receive_bytes(std::byte* data, std::size_t n, int from) {
  for (std::size_t at = 0; at < n; at += kPiece) {
    MPI_Request r;
    MPI_Irecv(data + at, static_cast<int>(std::min(kPiece, n - at)), MPI_BYTE, from, 0, MPI_COMM_WORLD, &r);
    wait_politely(r);
  }
}

void broadcast_from(std::vector<std::byte>& bytes, int root) {
  std::uint64_t n = bytes.size();
  MPI_Request r;
  MPI_Ibcast(&n, 1, MPI_UINT64_T, root, MPI_COMM_WORLD, &r);
  wait_politely(r);
  bytes.resize(n);
  for (std::size_t at = 0; at < n; at += kPiece) {
    MPI_Ibcast(bytes.data() + at, static_cast<int>(std::min<std::size_t>(kPiece, n - at)), MPI_BYTE, root,
               MPI_COMM_WORLD, &r);
    wait_politely(r);
  }
}

class MpiJob final : public Ranks {
 public:
  MpiJob() {
    MPI_Comm_rank(MPI_COMM_WORLD, &rank_);
    MPI_Comm_size(MPI_COMM_WORLD, &size_);
  }
  ~MpiJob() override { MPI_Finalize(); }
  MpiJob(const MpiJob&) = delete;
  MpiJob& operator=(const MpiJob&) = delete;

  int rank() const override { return rank_; }
  int size() const override { return size_; }

  std::vector<std::byte> gather(std::span<const std::byte> mine) const override {
    std::uint64_t n = mine.size();
    std::vector<std::uint64_t> sizes(rank_ == 0 ? static_cast<std::size_t>(size_) : 0);
    MPI_Request r;
    MPI_Igather(&n, 1, MPI_UINT64_T, sizes.data(), 1, MPI_UINT64_T, 0, MPI_COMM_WORLD, &r);
    wait_politely(r);
    if (rank_ != 0) {
      send_bytes(mine.data(), mine.size(), 0);
      return {};
    }
    std::uint64_t total = 0;
    for (std::uint64_t s : sizes) total += s;
    std::vector<std::byte> all(total);
    std::copy(mine.begin(), mine.end(), all.begin());
    std::size_t at = mine.size();
    for (int r = 1; r < size_; ++r) {
      receive_bytes(all.data() + at, sizes[static_cast<std::size_t>(r)], r);
      at += sizes[static_cast<std::size_t>(r)];
    }
    return all;
  }

  void broadcast(std::vector<std::byte>& bytes) const override { broadcast_from(bytes, 0); }

  std::optional<std::string> first_failure(const std::optional<std::string>& mine) const override {
    const int candidate = mine ? rank_ : size_;
    int first = size_;
    MPI_Request r;
    MPI_Iallreduce(&candidate, &first, 1, MPI_INT, MPI_MIN, MPI_COMM_WORLD, &r);
    wait_politely(r);
    if (first == size_) return std::nullopt;
    std::vector<std::byte> message;
    if (rank_ == first) {
      const auto* b = reinterpret_cast<const std::byte*>(mine->data());
      message.assign(b, b + mine->size());
    }
    broadcast_from(message, first);
    return std::string(reinterpret_cast<const char*>(message.data()), message.size());
  }

 private:
  int rank_ = 0, size_ = 1;
};

}  // namespace

bool built_with_mpi() { return true; }

std::unique_ptr<Ranks> join_mpi_job(int& argc, char**& argv) {
  if (!launch_from_environment().by_mpi_launcher) return nullptr;
  int provided = 0;
  if (MPI_Init_thread(&argc, &argv, MPI_THREAD_FUNNELED, &provided) != MPI_SUCCESS)
    throw std::runtime_error("MPI_Init_thread failed");
  if (provided < MPI_THREAD_FUNNELED) {
    MPI_Finalize();
    throw std::runtime_error("the MPI library does not provide MPI_THREAD_FUNNELED");
  }
  return std::make_unique<MpiJob>();
}

}  // namespace polrig
