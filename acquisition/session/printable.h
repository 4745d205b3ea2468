#pragma once
// Text from files (CSV cells, session attributes, channel names) shown on a terminal: every
// control character (bytes 0x00-0x1f and 0x7f) is shown escaped, \n \r \t \e by name and
// the others as \xHH, so that a file cannot clear the screen, set the title or forge a line
// of output. Other bytes (UTF-8 text, backslashes) pass unchanged, so escaping twice (a
// message escaped where it is made and again where it is printed) changes nothing more.
#include <algorithm>
#include <cctype>
#include <string>
#include <string_view>

namespace doorbench {

inline std::string printable(std::string_view text) {
  static constexpr char kHex[] = "0123456789abcdef";
  std::string out;
  out.reserve(text.size());
  for (const char c : text) {
    const auto byte = static_cast<unsigned char>(c);
    if (byte >= 0x20 && byte != 0x7f) {
      out += c;
      continue;
    }
    out += '\\';
    switch (c) {
      case '\n':
        out += 'n';
        break;
      case '\r':
        out += 'r';
        break;
      case '\t':
        out += 't';
        break;
      case '\x1b':
        out += 'e';
        break;
      default:
        out += 'x';
        out += kHex[byte >> 4];
        out += kHex[byte & 0xf];
    }
  }
  return out;
}

// A message with its long values cut, so that a 10 MB value is not echoed on one line: a quoted
// value ('...' or "...") longer than 80 characters keeps its first 60 and its size ("'xxx...
// (10000000 characters)'"); a run without spaces longer than 1000 characters (a value not
// quoted; paths are shorter) the same. Everything else is left as it is.
inline std::string shortened(std::string_view text) {
  const auto cut = [](std::string_view value) {
    return std::string(value.substr(0, 60)) + "... (" + std::to_string(value.size()) +
           " characters)";
  };
  std::string out;
  std::size_t i = 0;
  while (i < text.size()) {
    const char c = text[i];
    // A quote opens after a space or punctuation, never inside a word ("the file's"), and
    // closes where no letter or digit follows it.
    const auto word_char = [&text](std::size_t at) {
      return at < text.size() && std::isalnum(static_cast<unsigned char>(text[at])) != 0;
    };
    if ((c == '\'' || c == '"') && !(i > 0 && word_char(i - 1))) {
      std::size_t close = text.find(c, i + 1);
      while (close != std::string_view::npos && word_char(close + 1))
        close = text.find(c, close + 1);
      if (close != std::string_view::npos && close - i - 1 > 80) {
        out += c + cut(text.substr(i + 1, close - i - 1)) + c;
        i = close + 1;
        continue;
      }
    }
    if (c != ' ' && (i == 0 || text[i - 1] == ' ')) {
      const std::size_t end = std::min(text.find(' ', i), text.size());
      if (end - i > 1000) {
        out += cut(text.substr(i, end - i));
        i = end;
        continue;
      }
    }
    out += c;
    ++i;
  }
  return out;
}

}  // namespace doorbench
