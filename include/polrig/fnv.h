#pragma once
// 64-bit FNV-1a (Fowler–Noll–Vo, http://www.isthe.com/chongo/tech/comp/fnv/): a short, stable
// fingerprint of a long input. Not cryptographic: for files polrig wrote itself (a resumable
// sweep's progress, the sphere cache's keys and checksums), never against an adversary.
#include <cstdint>
#include <string_view>

namespace polrig {

inline constexpr std::uint64_t kFnvBasis = 14695981039346656037ull;
inline constexpr std::uint64_t kFnvPrime = 1099511628211ull;

// Adds `bytes` to the running hash `h` (start it at kFnvBasis).
inline void fnv_add(std::uint64_t& h, std::string_view bytes) {
  for (unsigned char b : bytes) h = (h ^ b) * kFnvPrime;
}
// The hash of `bytes` alone.
inline std::uint64_t fnv1a(std::string_view bytes) {
  std::uint64_t h = kFnvBasis;
  fnv_add(h, bytes);
  return h;
}

}  // namespace polrig
