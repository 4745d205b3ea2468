// The HapticMaster emulator itself (tests/hapticmaster_emulator/hapticmaster_emulator.py),
// spoken to raw through the protocol functions: joined commands answered in order, error
// replies for unknown commands and bad arguments, the effect objects and their
// properties, and the admittance model (spring settles at its position, damper gives the
// terminal velocity F/c, nothing moves outside state "force").
#include <arpa/inet.h>
#include <netinet/in.h>
#include <netinet/tcp.h>
#include <poll.h>
#include <sys/socket.h>
#include <unistd.h>

#include <catch2/catch.hpp>
#include <chrono>
#include <string>
#include <thread>
#include <utility>
#include <vector>

#include "haptic/hapticmaster_protocol.h"
#include "tests/support/hapticmaster_emulator_process.h"

using namespace doorbench::haptic;

namespace {

class RawClient {
 public:
  explicit RawClient(int port) {
    fd_ = ::socket(AF_INET, SOCK_STREAM, 0);
    sockaddr_in a{};
    a.sin_family = AF_INET;
    a.sin_port = htons(static_cast<std::uint16_t>(port));
    a.sin_addr.s_addr = htonl(INADDR_LOOPBACK);
    if (::connect(fd_, reinterpret_cast<sockaddr*>(&a), sizeof a) != 0) {
      throw std::runtime_error("cannot connect to the emulator");
    }
  }
  ~RawClient() { ::close(fd_); }
  RawClient(const RawClient&) = delete;
  RawClient& operator=(const RawClient&) = delete;

  std::vector<std::string> send(const std::vector<std::string>& commands, bool joined = true) {
    const std::string bytes = hm::request(commands, joined);
    REQUIRE(::write(fd_, bytes.data(), bytes.size()) == static_cast<ssize_t>(bytes.size()));
    // One reply message per request message, holding one reply per command.
    const std::size_t expected = joined ? 1 : commands.size();
    std::size_t messages = 0;
    std::vector<std::string> replies;
    char buffer[4096];
    while (messages < expected) {
      while (messages < expected) {
        auto message = splitter_.next();
        if (!message) break;
        ++messages;
        for (auto& reply : hm::split_replies(*message)) replies.push_back(reply);
      }
      if (messages >= expected) break;
      pollfd p{fd_, POLLIN, 0};
      if (::poll(&p, 1, 5000) <= 0) throw std::runtime_error("emulator: no reply");
      const ssize_t n = ::read(fd_, buffer, sizeof buffer);
      if (n <= 0) throw std::runtime_error("emulator closed the connection");
      splitter_.feed(std::string_view(buffer, static_cast<std::size_t>(n)));
    }
    REQUIRE(replies.size() == commands.size());
    return replies;
  }
  int fd() const { return fd_; }
  std::string one(const std::string& command) { return send({command}).front(); }
  Vec3 vector(const std::string& command) {
    const hm::Reply r = hm::parse_reply(one(command));
    REQUIRE(r.kind == hm::Reply::Kind::kVector);
    return r.vector;
  }

 private:
  int fd_ = -1;
  hm::ReplySplitter splitter_;
};

using Emulator = doorbench::testing::HapticMasterEmulator;

void emulator_sleep_s(double s) {
  std::this_thread::sleep_for(std::chrono::duration<double>(s));
}

}  // namespace

TEST_CASE("hapticmaster emulator: joined and separate commands, each answered in order",
          "[hapticmaster]") {
  Emulator emulator;
  RawClient client(emulator.port);
  const auto joined = client.send({"get state", "set inertia 4", "get inertia", "get measpos"});
  CHECK(joined == std::vector<std::string>{"\"off\"", "\"Inertia set\"", "4.0", "[0.0,0.0,0.0]"});
  const auto separate = client.send({"set state force", "get state"}, false);
  CHECK(separate == std::vector<std::string>{"\"state set to 'force'\"", "\"force\""});
  // The exact bytes on the wire for `commands` joined in one request.
  const auto wire_reply = [&](const std::vector<std::string>& commands, const std::string& text) {
    const std::string request = hm::request(commands, true);
    REQUIRE(::write(client.fd(), request.data(), request.size()) ==
            static_cast<ssize_t>(request.size()));
    const std::string expected = hm::frame(text);
    std::string got(expected.size(), '\0');
    std::size_t have = 0;
    while (have < got.size()) {
      const ssize_t n = ::read(client.fd(), got.data() + have, got.size() - have);
      REQUIRE(n > 0);
      have += static_cast<std::size_t>(n);
    }
    CHECK(got == expected);
  };
  // A single command's reply has no ';' (texts quoted, numbers bare)...
  wire_reply({"get state"}, "\"force\"");
  wire_reply({"get inertia"}, "4.0");
  wire_reply({"get position_calibrated"}, "\"true\"");
  wire_reply({"get workspace_r"}, "[-0.17,0.45,0.19]");
  // ... and a joined request's replies each end with ';'.
  wire_reply({"get state", "get inertia"}, "\"force\";4.0;");
}

TEST_CASE("hapticmaster emulator: unknown commands and bad arguments are error replies",
          "[hapticmaster]") {
  Emulator emulator;
  RawClient client(emulator.port);
  CHECK(client.one("fly away") == "--- ERROR: Unknown command 'fly away'");
  CHECK(client.one("set inertia heavy") == "--- ERROR: 'heavy' is not a number");
  CHECK(client.one("set inertia -1") == "--- ERROR: Inertia -1 out of range");
  CHECK(client.one("set state flying") == "--- ERROR: Unknown state 'flying'");
  CHECK(client.one("get nothing") == "--- ERROR: Unknown parameter 'nothing'");
  CHECK(client.one("create blob b") == "--- ERROR: Unknown effect type 'blob'");
  CHECK(client.one("set b force [0,0,0]") == "--- ERROR: No effect with name 'b'");
  CHECK(client.one("create biasforce b") == "\"Effect biasforce with name b created\"");
  CHECK(client.one("create spring b") == "--- ERROR: An effect with name 'b' already exists");
  CHECK(client.one("set b force [1,2]") == "--- ERROR: '[1,2]' is not a vector of 3 numbers");
  CHECK(client.one("set b force [1,x,2]") == "--- ERROR: 'x' is not a number");
  CHECK(client.one("set b stiffness 3") ==
        "--- ERROR: Effect biasforce has no property 'stiffness'");
  CHECK(client.one("set b force") == "--- ERROR: 'set b force' needs a value");
  CHECK(client.one("remove nothing") == "--- ERROR: No effect with name 'nothing'");
  // An error in the middle of a joined message does not stop the rest.
  CHECK(
      client.send({"get b force", "bogus", "get b enabled"}) ==
      std::vector<std::string>{"[0.0,0.0,0.0]", "--- ERROR: Unknown command 'bogus'", "\"false\""});
}

TEST_CASE("hapticmaster emulator: effect objects keep their properties", "[hapticmaster]") {
  Emulator emulator;
  RawClient client(emulator.port);
  for (const char* kind : {"spring", "damper", "cylinder", "torus", "biasforce"}) {
    CHECK(client.one(std::string("create ").append(kind).append(" o_").append(kind)) ==
          std::string("\"Effect ")
              .append(kind)
              .append(" with name o_")
              .append(kind)
              .append(" created\""));
  }
  CHECK(client.one("set o_spring stiffness 250.5") == "\"Spring's stiffness set\"");
  CHECK(client.one("get o_spring stiffness") == "250.5");
  CHECK(client.vector("get o_spring direction").isZero(0.0));  // no direction: all three axes
  CHECK(client.one("set o_damper dampcoef [1,2,3]") == "\"Damper's damp coefficient set\"");
  CHECK(client.vector("get o_damper dampcoef").isApprox(Vec3(1, 2, 3)));
  CHECK(client.one("set o_cylinder radius 0.1") == "\"Cylinder's radius set\"");
  CHECK(client.one("set o_torus ringradius 0.2") == "\"Torus's ringradius set\"");
  CHECK(client.one("get o_torus ringradius") == "0.2");
  CHECK(client.one("set o_cylinder enable") == "\"Effect enabled\"");
  CHECK(client.one("get o_cylinder enabled") == "\"true\"");
  CHECK(client.one("remove all") == "\"All effects Removed\"");
  CHECK(client.one("get o_spring stiffness") == "--- ERROR: No effect with name 'o_spring'");
}

TEST_CASE("hapticmaster emulator: the admittance model moves plausibly", "[hapticmaster]") {
  Emulator emulator({"--ext-force", "[0,0,0]"});
  RawClient client(emulator.port);
  client.send({"set inertia 2", "emulator extforce [10,0,0]"});
  emulator_sleep_s(0.2);
  // Not in state "force": nothing moves.
  CHECK(client.vector("get measpos").norm() == 0.0);

  // A damper only: terminal velocity F/c = 10/50 = 0.2 m/s after a few m/c = 0.04 s.
  client.send({"create damper d", "set d dampcoef [50,50,50]", "set d enable", "set state force"});
  emulator_sleep_s(0.5);
  const Vec3 v = client.vector("get modelvel");
  CHECK(v.x() == Approx(0.2).margin(0.005));
  CHECK(v.y() == 0.0);
  CHECK(client.vector("get measforce").isApprox(Vec3(10, 0, 0)));

  // A critically damped spring at x = 0.05 (k = 200; dampfactor 1 is critical damping,
  // c = 2 sqrt(k m) = 40) and no user force: the end-effector settles there.
  client.send({"emulator extforce [0,0,0]", "remove d", "create spring s", "set s pos [0.05,0,0]",
               "set s stiffness 200", "set s dampfactor 1", "set s enable"});
  emulator_sleep_s(1.5);
  const Vec3 p = client.vector("get measpos");
  CHECK(p.x() == Approx(0.05).margin(0.003));
  CHECK(std::abs(client.vector("get modelvel").x()) < 0.01);

  // A bias force of 10 N against the spring: the equilibrium moves by F/k = 0.05 m.
  client.send({"create biasforce b", "set b force [10,0,0]", "set b enable"});
  emulator_sleep_s(1.5);
  CHECK(client.vector("get measpos").x() == Approx(0.10).margin(0.003));
}
