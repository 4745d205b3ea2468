#pragma once
// How a long computation (a fit, the residual loop, an inverse design, a bootstrap) is asked to
// stop before its end: the caller gives it a StopHook, which it asks at its stopping points
// (between solver iterations, between stages, between samples); when the hook returns true the
// computation throws StopRequested from there, having written nothing half. The caller keeps
// what finished before and marks its own result interrupted (the verbs do so on SIGINT and
// SIGTERM and exit 130 or 143).
//
// Thread safety: the hook may be asked from several threads at once (folds, refits and samples
// run in parallel); it must be safe for that (a lock-free atomic read, as the verbs' is).
#include <functional>
#include <string>
#include <utility>

namespace doorbench {

// Returns true when the computation should stop; empty: never.
using StopHook = std::function<bool()>;

// Not a std::exception, on purpose (as Boost.Thread's thread_interrupted): the handlers that
// turn a failed fit or sample into a rejected candidate (`catch (const std::exception&)`) must
// not swallow a stop. A `catch (...)` that does not rethrow must catch this first.
class StopRequested {
 public:
  // `where`: what was under way ("the window fit", "the tolerance Monte Carlo").
  explicit StopRequested(std::string where) : where_(std::move(where)) {}
  const std::string& where() const { return where_; }
  std::string what() const { return "stopped on request during " + where_; }

 private:
  std::string where_;
};

inline bool stop_requested(const StopHook& hook) {
  return hook && hook();
}

// Throws StopRequested(where) when the hook asks to stop.
inline void throw_if_stop_requested(const StopHook& hook, const std::string& where) {
  if (stop_requested(hook)) throw StopRequested(where);
}

}  // namespace doorbench
