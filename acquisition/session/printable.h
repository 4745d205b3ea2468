#pragma once
// Text from files (CSV cells, session attributes, channel names) shown on a terminal: every
// control character (bytes 0x00-0x1f and 0x7f) is shown escaped, \n \r \t \e by name and
// the others as \xHH, so that a file cannot clear the screen, set the title or forge a line
// of output. Other bytes (UTF-8 text, backslashes) pass unchanged, so escaping twice (a
// message escaped where it is made and again where it is printed) changes nothing more.
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
      case '\n': out += 'n'; break;
      case '\r': out += 'r'; break;
      case '\t': out += 't'; break;
      case '\x1b': out += 'e'; break;
      default:
        out += 'x';
        out += kHex[byte >> 4];
        out += kHex[byte & 0xf];
    }
  }
  return out;
}

}  // namespace doorbench
