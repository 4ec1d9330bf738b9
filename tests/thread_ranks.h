#pragma once
// Ranks in one process, for tests without MPI: `size` threads, each one rank, meeting at a
// barrier for every collective as MPI ranks do. with_thread_ranks(n, f) runs f(ranks) on n
// threads and returns what each threw ("" when it returned).
#include <barrier>
#include <cstddef>
#include <exception>
#include <functional>
#include <mutex>
#include <optional>
#include <span>
#include <string>
#include <thread>
#include <vector>

#include "polrig/ranks.h"

namespace polrig::test {

class ThreadWorld {
 public:
  explicit ThreadWorld(int size) : size_(size), barrier_(size), slots_(static_cast<std::size_t>(size)) {}
  int size() const { return size_; }

  std::vector<std::byte> gather(int rank, std::span<const std::byte> mine) {
    slot(rank).assign(mine.begin(), mine.end());
    barrier_.arrive_and_wait();
    std::vector<std::byte> all;
    if (rank == 0)
      for (const auto& s : slots_) all.insert(all.end(), s.begin(), s.end());
    barrier_.arrive_and_wait();  // the slots are free again
    return all;
  }
  void broadcast(int rank, std::vector<std::byte>& bytes) {
    if (rank == 0) slot(0) = bytes;
    barrier_.arrive_and_wait();
    if (rank != 0) bytes = slot(0);
    barrier_.arrive_and_wait();
  }
  std::optional<std::string> first_failure(int rank, const std::optional<std::string>& mine) {
    failed_[static_cast<std::size_t>(rank)] = mine.has_value();
    if (mine) slot(rank).assign(reinterpret_cast<const std::byte*>(mine->data()),
                                reinterpret_cast<const std::byte*>(mine->data()) + mine->size());
    barrier_.arrive_and_wait();
    std::optional<std::string> first;
    for (int r = 0; r < size_ && !first; ++r)
      if (failed_[static_cast<std::size_t>(r)]) first = std::string(reinterpret_cast<const char*>(slot(r).data()), slot(r).size());
    barrier_.arrive_and_wait();
    return first;
  }

 private:
  std::vector<std::byte>& slot(int rank) { return slots_[static_cast<std::size_t>(rank)]; }
  int size_;
  std::barrier<> barrier_;
  std::vector<std::vector<std::byte>> slots_;
  std::vector<char> failed_ = std::vector<char>(static_cast<std::size_t>(size_));
};

class ThreadRank final : public Ranks {
 public:
  ThreadRank(ThreadWorld& world, int rank) : world_(world), rank_(rank) {}
  int rank() const override { return rank_; }
  int size() const override { return world_.size(); }
  std::vector<std::byte> gather(std::span<const std::byte> mine) const override { return world_.gather(rank_, mine); }
  void broadcast(std::vector<std::byte>& bytes) const override { world_.broadcast(rank_, bytes); }
  std::optional<std::string> first_failure(const std::optional<std::string>& mine) const override {
    return world_.first_failure(rank_, mine);
  }

 private:
  ThreadWorld& world_;
  int rank_;
};

// Runs f on `size` ranks, each on its own thread; what each rank threw, in rank order ("" for
// none).
inline std::vector<std::string> with_thread_ranks(int size, const std::function<void(const Ranks&)>& f) {
  ThreadWorld world(size);
  std::vector<std::string> errors(static_cast<std::size_t>(size));
  std::vector<std::thread> threads;
  for (int r = 0; r < size; ++r)
    threads.emplace_back([&, r] {
      const ThreadRank rank(world, r);
      try {
        f(rank);
      } catch (const std::exception& e) {
        errors[static_cast<std::size_t>(r)] = e.what();
      }
    });
  for (std::thread& t : threads) t.join();
  return errors;
}

}  // namespace polrig::test
