#include "text.hpp"

#include <algorithm>

namespace viewpose::text {

std::vector<std::string_view> split_whitespace(std::string_view line) {
  std::vector<std::string_view> out;
  std::size_t i = 0;
  while (i < line.size()) {
    while (i < line.size() && (line[i] == ' ' || line[i] == '\t')) ++i;
    const std::size_t start = i;
    while (i < line.size() && line[i] != ' ' && line[i] != '\t') ++i;
    if (i > start) out.push_back(line.substr(start, i - start));
  }
  return out;
}

std::vector<std::string_view> split(std::string_view line, char sep) {
  std::vector<std::string_view> out;
  std::size_t start = 0;
  for (;;) {
    const std::size_t end = line.find(sep, start);
    out.push_back(line.substr(start, end == std::string_view::npos ? std::string_view::npos : end - start));
    if (end == std::string_view::npos) return out;
    start = end + 1;
  }
}

std::string_view trim(std::string_view s) {
  const auto is_space = [](char c) { return c == ' ' || c == '\t' || c == '\r' || c == '\n'; };
  while (!s.empty() && is_space(s.front())) s.remove_prefix(1);
  while (!s.empty() && is_space(s.back())) s.remove_suffix(1);
  return s;
}

bool LineReader::next(std::string_view& line) {
  if (pos_ >= bytes_.size()) return false;
  const char* begin = reinterpret_cast<const char*>(bytes_.data()) + pos_;
  const std::size_t left = bytes_.size() - pos_;
  const char* nl = static_cast<const char*>(std::char_traits<char>::find(begin, left, '\n'));
  const std::size_t len = nl ? static_cast<std::size_t>(nl - begin) : left;
  pos_ += len + (nl ? 1 : 0);
  line = std::string_view(begin, len);
  if (!line.empty() && line.back() == '\r') line.remove_suffix(1);
  return true;
}

std::string excerpt(std::string_view s, std::size_t max_chars) {
  std::string out;
  for (char c : s.substr(0, max_chars)) {
    out += (c >= 32 && c < 127) ? c : '?';
  }
  if (s.size() > max_chars) out += "...";
  return out;
}

}  // namespace viewpose::text
