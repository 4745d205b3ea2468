#pragma once
// The HapticMaster's TCP text protocol, all its framing in one place (docs/hapticmaster.md
// says which parts are verified from public sources and which are assumed):
//  - a command is ASCII text ("set inertia 3.5", "get measpos", "set b force [1,0,-2]");
//    several can be joined with ';' into one request;
//  - on the wire every message (request or reply) is an 8-byte header followed by its text:
//    bytes 0-3 the text's length as a big-endian unsigned 32-bit number, bytes 4-7 zero;
//  - each request message is answered by one reply message whose text holds one reply per
//    command, each ended by ';' ("[0.1,0,0.2];[0,0,0];" for two commands);
//  - a reply is a vector "[x,y,z]", a number, a quoted string "\"force\"", a plain message
//    ("Inertia set") or an error that starts with "--- ERROR:".
// Everything here is a pure function of its arguments (no I/O), so it is unit-tested alone.
#include <cstddef>
#include <cstdint>
#include <optional>
#include <string>
#include <string_view>
#include <vector>

#include "haptic/device.h"

namespace doorbench::haptic::hm {

constexpr int kDefaultPort = 7654;
constexpr std::size_t kHeaderSize = 8;
// Longer messages than this are taken as a corrupt stream (a real reply is < 200 bytes).
constexpr std::uint32_t kMaxMessageSize = 65536;

// Numbers as the device reads them: '.' decimal point whatever the locale, fixed notation
// (no exponent), at most 6 decimals, trailing zeros dropped ("3.5", "-0.000001", "0").
std::string format_device_number(double value);
// The step of the last digit a number's text carries, from its digits and exponent:
// "10.9195" -> 1e-4, "10.919540" -> 1e-6, "3" -> 1, "1.09195e+06" -> 10, "2.5E-3" -> 1e-4.
// nullopt unless parse_number takes the text.
std::optional<double> last_digit_step(std::string_view text);
// Whether a number the device reports (`reply`, its text) agrees with `sent` (a value the
// driver sent as format_device_number(sent)) to the digits both carry: they differ by at most half
// the reply's last digit plus half of format_device_number's (5e-7, for a device that keeps fewer
// bits than were sent), plus a few units of the binary values' rounding. "10.9195" (%g's
// six significant digits) agrees with 10.91954; "10.9194" and "3.0" do not. False when
// the reply is not a number.
bool agrees_at_reply_precision(double sent, std::string_view reply);
// "[x,y,z]" with format_device_number's numbers and no spaces.
std::string format_vector(const Vec3& v);
// Joins commands with ';' (no trailing ';'). Throws std::invalid_argument if a command is
// empty or contains ';' or a control character (it would change the framing).
std::string join_commands(const std::vector<std::string>& commands);

// The bytes to send for `text`: header + text. Throws std::invalid_argument if too long.
std::string frame(std::string_view text);

// The bytes for one round trip of `commands`, each answered by one reply: one frame of the
// ';'-joined commands (`joined`), or one frame per command sent back to back. Throws
// std::invalid_argument as join_commands and frame do.
std::string request(const std::vector<std::string>& commands, bool joined);

// Splits a byte stream into message texts. Feed it whatever recv() returned; it keeps a
// partial message until the rest arrives.
class ReplySplitter {
 public:
  // Appends bytes; returns false (and keeps failing) once the stream is corrupt.
  bool feed(std::string_view bytes);
  // The next complete message's text, if there is one.
  std::optional<std::string> next();
  bool corrupt() const { return !error_.empty(); }
  const std::string& error() const { return error_; }  // why the stream is corrupt
  std::size_t buffered() const { return buffer_.size() - consumed_; }
  void clear();

 private:
  std::string buffer_;
  std::size_t consumed_ = 0;
  std::string error_;
};

// The replies in one reply message's text: split at each ';' outside double quotes, each
// trimmed; the empty piece after the last ';' is dropped ("a;b;" and "a;b" -> {"a","b"},
// "" -> {}).
std::vector<std::string> split_replies(std::string_view message);

// One reply, classified.
struct Reply {
  enum class Kind { kVector, kNumber, kString, kMessage, kError };
  Kind kind = Kind::kMessage;
  std::string text;  // the reply as received, trimmed; for kError the text after "ERROR:"
  Vec3 vector = Vec3::Zero();
  double number = 0.0;
  std::string string;  // kString: without the quotes
};
// Classifies a reply text. Malformed vectors ("[1,2", "[1,x,3]", 2 or 4 elements) are
// kError replies whose text says what is wrong, so a caller never reads garbage as data.
Reply parse_reply(std::string_view text);

// "" if `replies` answer `commands` without error, else what went wrong: the first error
// reply (named by its command) or a wrong count.
std::string check_replies(const std::vector<std::string>& commands,
                          const std::vector<std::string>& replies);

// Parses a vector reply; nullopt unless `text` is exactly "[x,y,z]" (spaces allowed).
std::optional<Vec3> parse_vector(std::string_view text);
// Parses a list of 1 to 16 numbers "[a,b,...]" (the workspace replies); nullopt otherwise.
std::optional<std::vector<double>> parse_numbers(std::string_view text);
// Parses a number; nullopt unless the whole `text` (trimmed) is one finite number.
std::optional<double> parse_number(std::string_view text);

// "host[:port]" -> host and port (default 7654). Throws std::invalid_argument naming the
// address if the host is empty or the port is not 1..65535.
struct Address {
  std::string host;
  int port = kDefaultPort;
};
Address parse_address(const std::string& address);

}  // namespace doorbench::haptic::hm
