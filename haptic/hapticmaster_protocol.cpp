#include "haptic/hapticmaster_protocol.h"

#include <algorithm>
#include <charconv>
#include <cmath>
#include <limits>
#include <stdexcept>

namespace doorbench::haptic::hm {
namespace {

std::string_view trim(std::string_view s) {
  const auto is_space = [](char c) {
    return c == ' ' || c == '\t' || c == '\r' || c == '\n' || c == '\0';
  };
  while (!s.empty() && is_space(s.front())) s.remove_prefix(1);
  while (!s.empty() && is_space(s.back())) s.remove_suffix(1);
  return s;
}

}  // namespace

std::string format_device_number(double value) {
  if (!std::isfinite(value))
    throw std::invalid_argument("format_device_number: not a finite number");
  char buffer[64];
  // Fixed notation: the device's parser is not known to take exponents.
  const auto result =
      std::to_chars(buffer, buffer + sizeof buffer, value, std::chars_format::fixed, 6);
  if (result.ec != std::errc()) throw std::invalid_argument("format_device_number: out of range");
  std::string text(buffer, result.ptr);
  const std::size_t point = text.find('.');
  if (point != std::string::npos) {
    std::size_t end = text.size();
    while (end > point + 1 && text[end - 1] == '0') --end;
    if (end == point + 1) end = point;
    text.resize(end);
  }
  if (text == "-0") text = "0";
  return text;
}

std::string format_vector(const Vec3& v) {
  std::string text("[");
  text.append(format_device_number(v.x())).append(",");
  text.append(format_device_number(v.y())).append(",");
  text.append(format_device_number(v.z())).append("]");
  return text;
}

std::string join_commands(const std::vector<std::string>& commands) {
  std::string joined;
  for (const std::string& command : commands) {
    if (trim(command).empty()) throw std::invalid_argument("join_commands: an empty command");
    for (char c : command) {
      if (c == ';' || static_cast<unsigned char>(c) < 0x20 || c == 0x7f) {
        throw std::invalid_argument(std::string("join_commands: command '")
                                        .append(command)
                                        .append("' contains ';' or a control character"));
      }
    }
    if (!joined.empty()) joined += ';';
    joined += command;
  }
  return joined;
}

std::string frame(std::string_view text) {
  if (text.size() > kMaxMessageSize) {
    throw std::invalid_argument("frame: message of " + std::to_string(text.size()) +
                                " bytes is longer than " + std::to_string(kMaxMessageSize));
  }
  const auto n = static_cast<std::uint32_t>(text.size());
  std::string bytes(kHeaderSize, '\0');
  bytes[0] = static_cast<char>((n >> 24) & 0xff);
  bytes[1] = static_cast<char>((n >> 16) & 0xff);
  bytes[2] = static_cast<char>((n >> 8) & 0xff);
  bytes[3] = static_cast<char>(n & 0xff);
  bytes.append(text);
  return bytes;
}

std::string request(const std::vector<std::string>& commands, bool joined) {
  if (joined) return frame(join_commands(commands));
  std::string bytes;
  for (const std::string& command : commands) bytes += frame(join_commands({command}));
  return bytes;
}

bool ReplySplitter::feed(std::string_view bytes) {
  if (corrupt()) return false;
  // Drop what next() has consumed before the buffer grows (amortised, no per-byte copies).
  if (consumed_ > 0 && consumed_ == buffer_.size()) {
    buffer_.clear();
    consumed_ = 0;
  } else if (consumed_ > 4096) {
    buffer_.erase(0, consumed_);
    consumed_ = 0;
  }
  buffer_.append(bytes);
  return true;
}

std::optional<std::string> ReplySplitter::next() {
  if (corrupt() || buffer_.size() - consumed_ < kHeaderSize) return std::nullopt;
  const auto* p = reinterpret_cast<const unsigned char*>(buffer_.data() + consumed_);
  const std::uint32_t n = (std::uint32_t{p[0]} << 24) | (std::uint32_t{p[1]} << 16) |
                          (std::uint32_t{p[2]} << 8) | std::uint32_t{p[3]};
  if (n > kMaxMessageSize) {
    error_ = "reply header announces " + std::to_string(n) + " bytes (more than " +
             std::to_string(kMaxMessageSize) + "): the stream is not the HapticMaster protocol";
    return std::nullopt;
  }
  if (buffer_.size() - consumed_ < kHeaderSize + n) return std::nullopt;
  std::string text = buffer_.substr(consumed_ + kHeaderSize, n);
  consumed_ += kHeaderSize + n;
  return text;
}

void ReplySplitter::clear() {
  buffer_.clear();
  consumed_ = 0;
  error_.clear();
}

std::vector<std::string> split_replies(std::string_view message) {
  std::vector<std::string> replies;
  bool quoted = false;
  std::size_t begin = 0;
  for (std::size_t i = 0; i <= message.size(); ++i) {
    if (i < message.size() && message[i] == '"') quoted = !quoted;
    if (i == message.size() || (message[i] == ';' && !quoted)) {
      const std::string_view piece = trim(message.substr(begin, i - begin));
      if (i < message.size() || !piece.empty()) replies.emplace_back(piece);
      begin = i + 1;
    }
  }
  return replies;
}

std::optional<double> parse_number(std::string_view text) {
  text = trim(text);
  if (text.empty()) return std::nullopt;
  if (text.front() == '+') text.remove_prefix(1);
  double value = 0.0;
  const auto result = std::from_chars(text.data(), text.data() + text.size(), value);
  if (result.ec != std::errc() || result.ptr != text.data() + text.size()) return std::nullopt;
  if (!std::isfinite(value)) return std::nullopt;
  return value;
}

std::optional<double> last_digit_step(std::string_view text) {
  if (!parse_number(text)) return std::nullopt;
  text = trim(text);
  const std::size_t exponent_at = text.find_first_of("eE");
  int exponent = 0;
  if (exponent_at != std::string_view::npos) {
    std::string_view digits = text.substr(exponent_at + 1);
    if (!digits.empty() && digits.front() == '+') digits.remove_prefix(1);
    const auto result = std::from_chars(digits.data(), digits.data() + digits.size(), exponent);
    if (result.ec != std::errc()) return std::nullopt;
    text = text.substr(0, exponent_at);
  }
  const std::size_t point = text.find('.');
  const int decimals =
      point == std::string_view::npos ? 0 : static_cast<int>(text.size() - point - 1);
  return std::pow(10.0, exponent - decimals);
}

bool agrees_at_reply_precision(double sent, std::string_view reply) {
  const std::optional<double> value = parse_number(reply);
  const std::optional<double> step = last_digit_step(reply);
  if (!value || !step || !std::isfinite(sent)) return false;
  const double rounding =
      8.0 * std::numeric_limits<double>::epsilon() * std::max(std::abs(sent), std::abs(*value));
  return std::abs(*value - sent) <= 0.5 * *step + 0.5e-6 + rounding;
}

std::optional<Vec3> parse_vector(std::string_view text) {
  text = trim(text);
  if (text.size() < 2 || text.front() != '[' || text.back() != ']') return std::nullopt;
  text = text.substr(1, text.size() - 2);
  Vec3 v;
  for (int i = 0; i < 3; ++i) {
    const std::size_t comma = text.find(',');
    if ((i < 2) != (comma != std::string_view::npos)) return std::nullopt;
    const auto value = parse_number(text.substr(0, comma));
    if (!value) return std::nullopt;
    v[i] = *value;
    if (i < 2) text.remove_prefix(comma + 1);
  }
  return v;
}

std::optional<std::vector<double>> parse_numbers(std::string_view text) {
  text = trim(text);
  if (text.size() < 2 || text.front() != '[' || text.back() != ']') return std::nullopt;
  text = text.substr(1, text.size() - 2);
  std::vector<double> numbers;
  for (;;) {
    const std::size_t comma = text.find(',');
    const auto value = parse_number(text.substr(0, comma));
    if (!value || numbers.size() == 16) return std::nullopt;
    numbers.push_back(*value);
    if (comma == std::string_view::npos) break;
    text.remove_prefix(comma + 1);
  }
  return numbers;
}

Reply parse_reply(std::string_view raw) {
  Reply reply;
  const std::string_view text = trim(raw);
  reply.text = std::string(text);
  // An error may come quoted like any other text: look inside the quotes too.
  std::string_view unquoted = text;
  if (unquoted.size() >= 2 && unquoted.front() == '"' && unquoted.back() == '"') {
    unquoted = trim(unquoted.substr(1, unquoted.size() - 2));
  }
  // "--- ERROR: ..." (public examples), tolerated with fewer dashes or none.
  const std::size_t error_at = unquoted.find("ERROR");
  if (error_at != std::string_view::npos && unquoted.find_first_not_of("- ") == error_at) {
    std::string_view message = unquoted.substr(error_at + 5);
    if (!message.empty() && message.front() == ':') message.remove_prefix(1);
    reply.kind = Reply::Kind::kError;
    reply.text = std::string(trim(message));
    if (reply.text.empty()) reply.text = "error reply without a message";
    return reply;
  }
  if (!text.empty() && text.front() == '[') {
    if (const auto v = parse_vector(text)) {
      reply.kind = Reply::Kind::kVector;
      reply.vector = *v;
    } else {
      reply.kind = Reply::Kind::kError;
      reply.text = std::string("malformed vector reply '").append(text).append("'");
    }
    return reply;
  }
  if (text.size() >= 2 && text.front() == '"' && text.back() == '"') {
    reply.kind = Reply::Kind::kString;
    reply.string = std::string(text.substr(1, text.size() - 2));
    return reply;
  }
  if (const auto number = parse_number(text)) {
    reply.kind = Reply::Kind::kNumber;
    reply.number = *number;
    return reply;
  }
  reply.kind = Reply::Kind::kMessage;
  return reply;
}

Address parse_address(const std::string& address) {
  Address result;
  const std::size_t colon = address.rfind(':');
  result.host = address.substr(0, colon);
  if (result.host.empty()) {
    throw std::invalid_argument(
        std::string("HapticMaster address '").append(address).append("': no host"));
  }
  if (colon != std::string::npos) {
    const std::string port_text = address.substr(colon + 1);
    int port = 0;
    const auto r = std::from_chars(port_text.data(), port_text.data() + port_text.size(), port);
    if (port_text.empty() || r.ec != std::errc() || r.ptr != port_text.data() + port_text.size() ||
        port < 1 || port > 65535) {
      throw std::invalid_argument(std::string("HapticMaster address '")
                                      .append(address)
                                      .append("': port '")
                                      .append(port_text)
                                      .append("' is not 1..65535"));
    }
    result.port = port;
  }
  return result;
}

// "" if `replies` answer `commands` without error, else what went wrong: the first error
// reply (named by its command) or a wrong count.
std::string check_replies(const std::vector<std::string>& commands,
                          const std::vector<std::string>& replies) {
  for (std::size_t i = 0; i < replies.size(); ++i) {
    const Reply reply = parse_reply(replies[i]);
    if (reply.kind == Reply::Kind::kError) {
      const std::string& command = i < commands.size() ? commands[i] : commands.back();
      return "'" + command + "' failed: " + reply.text;
    }
  }
  if (replies.size() != commands.size()) {
    return std::to_string(commands.size()) + " command(s) '" + join_commands(commands) +
           "' answered with " + std::to_string(replies.size()) + " repl" +
           (replies.size() == 1 ? "y" : "ies");
  }
  return "";
}

}  // namespace doorbench::haptic::hm
