#pragma once
// A value from an input file or the command line as an error message quotes it: whole when it is
// short, else its first kQuotedChars bytes (never splitting a UTF-8 character) and
// "…(N bytes)", so that a 1 MB CSV cell gives a short line on stderr (issue 23 §5.4).
#include <cstddef>
#include <string>
#include <string_view>

#include <fmt/format.h>

namespace polrig {

inline constexpr std::size_t kQuotedChars = 60;

// Control bytes (a NUL, a stray carriage return) are written as \xNN: a NUL would end the message
// where a C string carries it (Python's exception text, what()).
inline std::string escaped_controls(std::string_view text) {
  std::string out;
  out.reserve(text.size());
  for (const char c : text) {
    const unsigned char u = static_cast<unsigned char>(c);
    if (u < 0x20 || u == 0x7F) out += fmt::format("\\x{:02x}", u);
    else out += c;
  }
  return out;
}

inline std::string quoted_value(std::string_view raw) {
  const std::string escaped = escaped_controls(raw);
  const std::string_view text = escaped;
  if (text.size() <= kQuotedChars + 16) return std::string(text);  // no shorter once cut
  std::size_t cut = kQuotedChars;
  while (cut > 0 && (static_cast<unsigned char>(text[cut]) & 0xC0) == 0x80) --cut;  // a continuation byte
  return fmt::format("{}…({} bytes)", text.substr(0, cut), text.size());
}

}  // namespace polrig
