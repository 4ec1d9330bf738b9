#pragma once
// 64-bit FNV-1a (Fowler–Noll–Vo, http://www.isthe.com/chongo/tech/comp/fnv/): a short, stable
// fingerprint of a long input. Not cryptographic: for files polrig wrote itself (a resumable
// sweep's progress, the sphere cache's keys and checksums), never against an adversary.
#include <cstdint>
#include <cstring>
#include <string_view>

namespace polrig {

inline constexpr std::uint64_t kFnvBasis = 14695981039346656037ull;
inline constexpr std::uint64_t kFnvPrime = 1099511628211ull;

// Adds `bytes` to the running hash `h` (start it at kFnvBasis).
inline void fnv_add(std::uint64_t& h, std::string_view bytes) {
  std::uint64_t x = h;  // in a register: the bytes read may not alias h
  for (unsigned char b : bytes) x = (x ^ b) * kFnvPrime;
  h = x;
}
// FNV-1a over 64-bit words for long inputs (a sweep's files: hundreds of MB), h = (h ⊕ w)·prime per
// 8 bytes taken little-endian, so 8× fewer dependent multiplications than fnv_add; a last partial
// word is its bytes zero-padded, then their count is folded in. Not byte-wise FNV-1a's value.
// Streaming: the same value however the input is split between add() calls.
class FnvWords {
 public:
  void add(std::string_view bytes) {
    std::size_t i = 0;
    for (; have_ > 0 && i < bytes.size(); ++i) push(static_cast<unsigned char>(bytes[i]));
    std::uint64_t h = h_;  // in a register: the bytes read may not alias it
    for (; i + 8 <= bytes.size(); i += 8) {
      std::uint64_t w;
      std::memcpy(&w, bytes.data() + i, 8);
      h = (h ^ w) * kFnvPrime;
    }
    h_ = h;
    for (; i < bytes.size(); ++i) push(static_cast<unsigned char>(bytes[i]));
  }
  void add_word(std::uint64_t w) {  // 8 bytes at a word boundary (a double's bits)
    if (have_ == 0) {
      h_ = (h_ ^ w) * kFnvPrime;
      return;
    }
    for (int b = 0; b < 8; ++b) push(static_cast<unsigned char>(w >> (8 * b)));
  }
  std::uint64_t value() const { return have_ == 0 ? h_ : (((h_ ^ word_) * kFnvPrime) ^ static_cast<std::uint64_t>(have_)) * kFnvPrime; }

 private:
  void push(unsigned char b) {
    word_ |= static_cast<std::uint64_t>(b) << (8 * have_);
    if (++have_ == 8) {
      h_ = (h_ ^ word_) * kFnvPrime;
      word_ = 0;
      have_ = 0;
    }
  }
  std::uint64_t h_ = kFnvBasis, word_ = 0;
  int have_ = 0;
};

// The hash of `bytes` alone.
inline std::uint64_t fnv1a(std::string_view bytes) {
  std::uint64_t h = kFnvBasis;
  fnv_add(h, bytes);
  return h;
}

}  // namespace polrig
