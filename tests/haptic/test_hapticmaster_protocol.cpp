// The HapticMaster protocol's pure functions: number and vector formatting, joining,
// framing, splitting a reply stream (partial, several at once, corrupt) and parsing replies;
// numbers read back compared at the precision their replies carry.
#include <algorithm>
#include <catch2/catch.hpp>
#include <clocale>
#include <cstdio>
#include <locale>
#include <stdexcept>
#include <string>

#include "haptic/hapticmaster_protocol.h"

using namespace doorbench::haptic;
using namespace doorbench::haptic::hm;

TEST_CASE("hapticmaster: numbers are fixed-point with '.', trimmed", "[hapticmaster]") {
  CHECK(format_device_number(3.5) == "3.5");
  CHECK(format_device_number(0.0) == "0");
  CHECK(format_device_number(-0.0) == "0");
  CHECK(format_device_number(-2.0) == "-2");
  CHECK(format_device_number(1e-7) == "0");
  CHECK(format_device_number(-1e-6) == "-0.000001");
  CHECK(format_device_number(123456.25) == "123456.25");
  CHECK(format_device_number(1e9) == "1000000000");  // no exponent
  CHECK_THROWS_AS(format_device_number(std::nan("")), std::invalid_argument);
  CHECK(format_vector(Vec3(1, -0.5, 0)) == "[1,-0.5,0]");
}

TEST_CASE("hapticmaster: a number read back agrees at the precision its reply carries",
          "[hapticmaster]") {
  CHECK(last_digit_step("10.9195") == Approx(1e-4));
  CHECK(last_digit_step("10.919540") == Approx(1e-6));
  CHECK(last_digit_step(" 3 ") == Approx(1.0));
  CHECK(last_digit_step("1.09195e+06") == Approx(10.0));
  CHECK(last_digit_step("2.5E-3") == Approx(1e-4));
  CHECK_FALSE(last_digit_step("ten").has_value());
  auto printed = [](const char* format, double value) {
    char text[64];
    std::snprintf(text, sizeof text, format, value);
    return std::string(text);
  };
  // Values as the driver sends them (6 decimals at most), replied as C's %g (six
  // significant digits), %.6f and at full precision: each agrees with what was sent; the
  // reply moved by one unit of its last digit, or by 2.5e-6 when that is less (the
  // tolerance keeps half of format_device_number's last digit for a device keeping fewer bits than
  // were sent; %.6f moved by two units), does not.
  for (const double sent : {10.91954, 5.0, 2.000001, 99.999999, 12.345678, 0.000123, 3.5}) {
    for (const char* format : {"%g", "%.6f", "%.17g"}) {
      const std::string reply = printed(format, sent);
      INFO(sent << " replied as " << format << ": " << reply);
      CHECK(agrees_at_reply_precision(sent, reply));
      const double step = *last_digit_step(reply);
      const double off = std::string(format) == "%.6f" ? 2.0 * step : std::max(step, 2.5e-6);
      const double moved = std::stod(reply) + off;
      CHECK_FALSE(agrees_at_reply_precision(sent, printed(format, moved)));
    }
  }
  CHECK(agrees_at_reply_precision(10.91954, "10.9195"));
  CHECK_FALSE(agrees_at_reply_precision(10.91954, "10.9194"));
  CHECK_FALSE(agrees_at_reply_precision(5.0, "3.0"));
  CHECK_FALSE(agrees_at_reply_precision(5.0, "\"5\""));
  CHECK_FALSE(agrees_at_reply_precision(5.0, "Inertia set"));
}

namespace {
struct CommaDecimal : std::numpunct<char> {
  char do_decimal_point() const override { return ','; }
};
}  // namespace

TEST_CASE("hapticmaster: formatting ignores the C and C++ locales", "[hapticmaster]") {
  // A C++ global locale with ',' as the decimal point (always available, unlike de_DE).
  const std::locale saved_cpp =
      std::locale::global(std::locale(std::locale::classic(), new CommaDecimal));
  CHECK(format_device_number(3.5) == "3.5");
  CHECK(format_vector(Vec3(0.25, 0, -1)) == "[0.25,0,-1]");
  CHECK(parse_number("3.5") == Approx(3.5));
  std::locale::global(saved_cpp);
  // de_DE would print "3,5" with printf; if that locale is not installed this checks "C".
  const char* old = std::setlocale(LC_NUMERIC, nullptr);
  const std::string saved = old ? old : "C";
  std::setlocale(LC_NUMERIC, "de_DE.UTF-8");
  CHECK(format_device_number(3.5) == "3.5");
  CHECK(parse_number("3.5") == Approx(3.5));
  std::setlocale(LC_NUMERIC, saved.c_str());
}

TEST_CASE("hapticmaster: commands are joined with semicolons and checked", "[hapticmaster]") {
  CHECK(join_commands({"get measpos", "get modelvel"}) == "get measpos;get modelvel");
  CHECK(join_commands({"get state"}) == "get state");
  CHECK_THROWS_WITH(join_commands({"get a;get b"}),
                    "join_commands: command 'get a;get b' contains ';' or a control character");
  CHECK_THROWS_WITH(join_commands({"get\nstate"}), Catch::Contains("control character"));
  CHECK_THROWS_WITH(join_commands({" "}), "join_commands: an empty command");
}

TEST_CASE("hapticmaster: a frame is a big-endian length, 4 zero bytes, the text",
          "[hapticmaster]") {
  const std::string bytes = frame("get state");
  REQUIRE(bytes.size() == 8 + 9);
  CHECK(bytes.substr(0, 8) == std::string("\0\0\0\x09\0\0\0\0", 8));
  CHECK(bytes.substr(8) == "get state");
  const std::string long_text(300, 'x');
  CHECK(frame(long_text).substr(0, 4) == std::string("\0\0\x01\x2c", 4));
  CHECK_THROWS_AS(frame(std::string(kMaxMessageSize + 1, 'x')), std::invalid_argument);
}

TEST_CASE("hapticmaster: the splitter waits for partial messages and splits a burst",
          "[hapticmaster]") {
  ReplySplitter splitter;
  const std::string stream = frame("[1,2,3]") + frame("Inertia set") + frame("");
  // Byte by byte: nothing until a message is complete.
  std::size_t complete = 0;
  std::string got;
  for (char c : stream) {
    splitter.feed(std::string_view(&c, 1));
    while (auto reply = splitter.next()) {
      ++complete;
      got += *reply + "|";
    }
  }
  CHECK(complete == 3);
  CHECK(got == "[1,2,3]|Inertia set||");
  CHECK(splitter.buffered() == 0);

  // A whole burst at once.
  splitter.feed(stream);
  CHECK(*splitter.next() == "[1,2,3]");
  CHECK(*splitter.next() == "Inertia set");
  CHECK(*splitter.next() == "");
  CHECK_FALSE(splitter.next());

  // Half a header, then half a body: still nothing.
  const std::string one = frame("\"force\"");
  splitter.feed(one.substr(0, 5));
  CHECK_FALSE(splitter.next());
  splitter.feed(one.substr(5, 4));
  CHECK_FALSE(splitter.next());
  splitter.feed(one.substr(9));
  CHECK(*splitter.next() == "\"force\"");
}

TEST_CASE("hapticmaster: a corrupt header makes the stream corrupt for good", "[hapticmaster]") {
  ReplySplitter splitter;
  splitter.feed(std::string("\xff\xff\xff\xffgarbage"));
  CHECK_FALSE(splitter.next());
  CHECK(splitter.corrupt());
  CHECK_THAT(splitter.error(), Catch::Contains("not the HapticMaster protocol"));
  CHECK_FALSE(splitter.feed(frame("ok")));
  CHECK_FALSE(splitter.next());
  splitter.clear();
  splitter.feed(frame("ok"));
  CHECK(*splitter.next() == "ok");
}

TEST_CASE("hapticmaster: replies are classified", "[hapticmaster]") {
  Reply r = parse_reply("[0.1,-2.5,3e-3]");
  CHECK(r.kind == Reply::Kind::kVector);
  CHECK(r.vector.isApprox(Vec3(0.1, -2.5, 0.003)));
  r = parse_reply(" [ 1 , 2 , 3 ] \n");
  CHECK(r.kind == Reply::Kind::kVector);
  CHECK(r.vector.isApprox(Vec3(1, 2, 3)));

  r = parse_reply("3.25");
  CHECK(r.kind == Reply::Kind::kNumber);
  CHECK(r.number == 3.25);

  r = parse_reply("\"force\"");
  CHECK(r.kind == Reply::Kind::kString);
  CHECK(r.string == "force");

  r = parse_reply("Inertia set");
  CHECK(r.kind == Reply::Kind::kMessage);
  CHECK(r.text == "Inertia set");

  r = parse_reply("--- ERROR: Unknown command 'bogus'");
  CHECK(r.kind == Reply::Kind::kError);
  CHECK(r.text == "Unknown command 'bogus'");
  r = parse_reply("ERROR:x");
  CHECK(r.kind == Reply::Kind::kError);
  CHECK(r.text == "x");
  r = parse_reply("--- ERROR:");
  CHECK(r.kind == Reply::Kind::kError);
  CHECK(r.text == "error reply without a message");
  // "ERROR" inside a message is not an error reply.
  CHECK(parse_reply("No ERROR here").kind == Reply::Kind::kMessage);
}

TEST_CASE("hapticmaster: malformed vectors are errors, never data", "[hapticmaster]") {
  for (const char* bad : {"[1,2", "[1,2]", "[1,2,3,4]", "[1,x,3]", "[,,]", "[1,2,3]x", "[]",
                          "[1;2;3]", "[nan,0,0]", "[inf,0,0]", "[1,,3]"}) {
    INFO(bad);
    const Reply r = parse_reply(bad);
    CHECK(r.kind == Reply::Kind::kError);
    CHECK_FALSE(parse_vector(bad));
  }
  CHECK_THAT(parse_reply("[1,2").text, Catch::Equals("malformed vector reply '[1,2'"));
  CHECK_FALSE(parse_number(""));
  CHECK_FALSE(parse_number("1.5x"));
  CHECK_FALSE(parse_number("1,5"));
  CHECK(*parse_number("+2") == 2.0);
}

TEST_CASE("hapticmaster: addresses are host[:port]", "[hapticmaster]") {
  Address a = parse_address("10.0.0.5");
  CHECK(a.host == "10.0.0.5");
  CHECK(a.port == 7654);
  a = parse_address("localhost:1234");
  CHECK(a.host == "localhost");
  CHECK(a.port == 1234);
  CHECK_THROWS_WITH(parse_address(":7654"), "HapticMaster address ':7654': no host");
  CHECK_THROWS_WITH(parse_address("h:0"), "HapticMaster address 'h:0': port '0' is not 1..65535");
  CHECK_THROWS_WITH(parse_address("h:"), Catch::Contains("port '' is not"));
  CHECK_THROWS_WITH(parse_address("h:70000"), Catch::Contains("port '70000'"));
  CHECK_THROWS_WITH(parse_address("h:12a"), Catch::Contains("port '12a'"));
}

TEST_CASE("hapticmaster: a request is one joined frame or one frame per command",
          "[hapticmaster]") {
  CHECK(request({"get measpos", "get modelvel"}, true) == frame("get measpos;get modelvel"));
  CHECK(request({"get measpos", "get modelvel"}, false) ==
        frame("get measpos") + frame("get modelvel"));
  CHECK_THROWS_WITH(request({"a;b"}, false), Catch::Contains("contains ';'"));
}

TEST_CASE(
    "hapticmaster: a reply message holds one reply per command, split at semicolons outside quotes",
    "[hapticmaster]") {
  using V = std::vector<std::string>;
  CHECK(split_replies("[0.1,0,0.2];[0,0,0];") == V{"[0.1,0,0.2]", "[0,0,0]"});
  CHECK(split_replies("Inertia set") == V{"Inertia set"});
  CHECK(split_replies("stop;") == V{"stop"});
  CHECK(split_replies(" a ; b ;\n") == V{"a", "b"});
  CHECK(split_replies("") == V{});
  CHECK(split_replies(";") == V{""});
  CHECK(split_replies("\"a;b\";c;") == V{"\"a;b\"", "c"});  // ';' inside quotes stays
  CHECK(split_replies("--- ERROR: bad;[1,2,3];") == V{"--- ERROR: bad", "[1,2,3]"});
  // A single reply as the raw-TCP client sees it: quoted, no ';'.
  CHECK(split_replies("\"state set to 'force'\"") == V{"\"state set to 'force'\""});
}

TEST_CASE("hapticmaster: quoted replies, quoted errors and number lists", "[hapticmaster]") {
  const Reply quoted_error = parse_reply("\"--- ERROR: Unknown parameter 'x'\"");
  CHECK(quoted_error.kind == Reply::Kind::kError);
  CHECK(quoted_error.text == "Unknown parameter 'x'");
  const Reply state = parse_reply("\"stop\"");
  CHECK(state.kind == Reply::Kind::kString);
  CHECK(state.string == "stop");
  CHECK(parse_reply("2.3").kind == Reply::Kind::kNumber);
  // Quoted text that merely mentions an error is not one.
  CHECK(parse_reply("\"no ERROR here\"").kind == Reply::Kind::kString);
  CHECK(parse_numbers("[-0.17,0.45,0.19]") == std::vector<double>{-0.17, 0.45, 0.19});
  CHECK(parse_numbers("[0.5,-0.5]") == std::vector<double>{0.5, -0.5});
  CHECK_FALSE(parse_numbers("[0.5,,1]"));
  CHECK_FALSE(parse_numbers("0.5,1"));
  CHECK_FALSE(parse_numbers("[]"));
}
