#pragma once
// The MOOG FCS HapticMaster over its TCP text protocol (haptic/hapticmaster_protocol.h;
// docs/hapticmaster.md). The render loop's tick never touches the socket: an I/O thread
// owns it, sends the newest commanded force (a bias force object on the device) with
// "get measpos;get modelvel;get measforce" in one round trip per period, and publishes each
// reply as a DeviceSample through a lock-free triple buffer that read() takes.
#include <atomic>
#include <cstdint>
#include <memory>
#include <mutex>
#include <string>
#include <thread>

#include "haptic/device.h"

namespace doorbench::haptic {

struct HapticMasterOptions {
  double connect_timeout_s = 2.0;  // TCP connect
  double reply_timeout_s = 0.5;    // one round trip; longer = link lost
  double io_rate_hz = 1000.0;      // round trips per second (at most; the link may be slower)
  // The name of the bias force object the driver creates on the device.
  std::string bias_object = "doorbench_bias";
  // One round trip's commands as one ';'-joined message (true), or as one message each,
  // sent together (false): the fallback if a device answers a joined message with a single
  // reply instead of one per command (docs/hapticmaster.md, assumptions).
  bool join_commands = true;
  std::string validate() const;  // "" or one line naming the option
};

// A single-producer single-consumer triple buffer: the writer fills back() and publishes
// it, the reader takes the newest published value; neither ever waits, locks or allocates.
template <class T>
class TripleBuffer {
 public:
  T& back() { return slots_[back_]; }
  void publish() {
    back_ = static_cast<std::uint8_t>(middle_.exchange(back_ | kFresh, std::memory_order_acq_rel) &
                                      kIndex);
  }
  // Takes the newest published value if there is one; returns whether it did.
  bool update() {
    if ((middle_.load(std::memory_order_relaxed) & kFresh) == 0) return false;
    front_ =
        static_cast<std::uint8_t>(middle_.exchange(front_, std::memory_order_acq_rel) & kIndex);
    return true;
  }
  const T& front() const { return slots_[front_]; }

 private:
  static constexpr std::uint8_t kIndex = 3;
  static constexpr std::uint8_t kFresh = 4;
  T slots_[3]{};
  std::atomic<std::uint8_t> middle_{1};
  std::uint8_t back_ = 0;   // the writer's
  std::uint8_t front_ = 2;  // the reader's
};

class HapticMasterDevice : public HapticDevice {
 public:
  // `address` is "host[:port]" (port 7654 by default). Throws DeviceError for a bad
  // address or options; does not connect (start() does).
  explicit HapticMasterDevice(const std::string& address, HapticMasterOptions options = {});
  ~HapticMasterDevice() override;
  HapticMasterDevice(const HapticMasterDevice&) = delete;
  HapticMasterDevice& operator=(const HapticMasterDevice&) = delete;

  std::string name() const override;  // "hapticmaster://host:port"
  DeviceLimits limits() const override;
  void start(double inertia) override;
  void stop() noexcept override;

  DeviceSample read() noexcept override;
  void command_force(const Vec3& force) noexcept override;
  void command_inertia(double inertia) noexcept override;

  // Why the link was lost (first reason, prefixed with name()), or "" while it is fine.
  // Set-up thread only; not for the tick.
  std::string last_error() const;
  // Round trips done by the I/O thread since start().
  std::uint64_t round_trips() const { return round_trips_.load(std::memory_order_relaxed); }

 private:
  struct Command {
    Vec3 force = Vec3::Zero();
    double inertia = 0.0;
  };
  class Connection;

  // Runs on the I/O thread; its arguments are what start() sent and published.
  void io_loop(double sent_inertia, DeviceSample sample);
  void fail(const std::string& reason);
  // Zero force, "set state stop", remove the bias object: best effort, errors to fail().
  void send_shutdown() noexcept;
  // A round trip in the set-up phase: throws DeviceError with the reply's text on error.
  std::string expect_ok(const std::string& command);

  std::string host_;
  int port_ = 0;
  HapticMasterOptions options_;
  std::unique_ptr<Connection> connection_;
  std::thread io_thread_;
  std::atomic<bool> stop_requested_{false};
  std::atomic<bool> link_ok_{false};
  std::atomic<std::uint64_t> round_trips_{0};

  TripleBuffer<DeviceSample> samples_;  // I/O thread -> tick
  TripleBuffer<Command> commands_;      // tick -> I/O thread
  Command staged_;                      // the tick's copy of what it last commanded
  DeviceSample last_read_;              // the tick's newest sample

  mutable std::mutex error_mutex_;  // only the I/O thread and last_error(), never the tick
  std::string last_error_;
};

}  // namespace doorbench::haptic
