// Fuzzes the HapticMaster's reply parsing (haptic/hapticmaster_protocol.h): a byte stream from
// the device, fed to the splitter in pieces, each message split into replies and each reply
// classified. Nothing may crash, throw or be undefined; a vector reply is three finite numbers
// and a number reply is finite, whatever the bytes.
#include <cmath>
#include <cstddef>
#include <cstdint>
#include <cstdlib>
#include <string_view>

#include "haptic/hapticmaster_protocol.h"

namespace hm = doorbench::haptic::hm;

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  const std::string_view bytes(reinterpret_cast<const char*>(data), size);
  // The first byte chooses the piece size the stream arrives in (1..256 bytes).
  const std::size_t piece = size == 0 ? 1 : static_cast<std::size_t>(data[0]) + 1;
  hm::ReplySplitter splitter;
  for (std::size_t at = 0; at < bytes.size(); at += piece) {
    if (!splitter.feed(bytes.substr(at, piece))) break;
    while (auto message = splitter.next()) {
      for (const std::string& text : hm::split_replies(*message)) {
        const hm::Reply reply = hm::parse_reply(text);
        if (reply.kind == hm::Reply::Kind::kVector && !reply.vector.allFinite()) std::abort();
        if (reply.kind == hm::Reply::Kind::kNumber && !std::isfinite(reply.number)) std::abort();
        if (const auto numbers = hm::parse_numbers(text)) {
          if (numbers->empty() || numbers->size() > 16) std::abort();
          for (const double x : *numbers) {
            if (!std::isfinite(x)) std::abort();
          }
        }
      }
    }
  }
  // The same bytes as one reply text, without framing.
  (void)hm::parse_reply(bytes);
  (void)hm::split_replies(bytes);
  return 0;
}
