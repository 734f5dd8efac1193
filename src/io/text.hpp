#pragma once
// Small text helpers shared by the readers of text formats (PCD and PLY headers and ascii data,
// CSV). Internal to the library.
#include <charconv>
#include <cstddef>
#include <cstdint>
#include <span>
#include <string>
#include <string_view>
#include <system_error>
#include <vector>

namespace viewpose::text {

/// Splits `line` at runs of spaces and tabs.
std::vector<std::string_view> split_whitespace(std::string_view line);
/// Splits `line` at every `sep` (empty fields kept).
std::vector<std::string_view> split(std::string_view line, char sep);
std::string_view trim(std::string_view s);

/// Parses the whole of `s` as a number (a leading '+' is allowed; nan and inf are accepted for
/// floating point). Returns false when `s` is not exactly one number of type T.
template <typename T>
bool parse_number(std::string_view s, T& out) {
  if (!s.empty() && s.front() == '+') s.remove_prefix(1);
  if (s.empty()) return false;
  const auto [end, ec] = std::from_chars(s.data(), s.data() + s.size(), out);
  return ec == std::errc() && end == s.data() + s.size();
}

/// Reads lines from a byte buffer, dropping "\n" and a trailing "\r".
class LineReader {
 public:
  explicit LineReader(std::span<const std::uint8_t> bytes) : bytes_(bytes) {}
  /// Next line, or false at the end of the buffer.
  bool next(std::string_view& line);
  /// Offset of the first byte not yet read.
  std::size_t offset() const { return pos_; }

 private:
  std::span<const std::uint8_t> bytes_;
  std::size_t pos_ = 0;
};

/// A printable excerpt of possibly binary bytes, for error messages.
std::string excerpt(std::string_view s, std::size_t max_chars = 24);

}  // namespace viewpose::text
