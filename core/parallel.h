#pragma once
// The one thread fan-out: task(0) ... task(count - 1) on up to `threads` threads (the
// caller's among them), each index exactly once, returning when all have ended.
//
// threads <= 1 (or count <= 1) runs every index on the caller's thread, in order. Threads
// take the next index as they finish one, so tasks of unequal length balance. If the system
// refuses a thread, the threads already started and the caller's own share the indices. A
// task's exception is caught; after all tasks have ended the first one caught (by the time
// it was caught) is rethrown on the caller's thread.
//
// Thread safety: `task` is called from several threads at once; it must be safe for that.
// Allocates (threads): not for real-time paths.
#include <functional>

namespace doorbench {

void parallel_for(int count, int threads, const std::function<void(int)>& task);

}  // namespace doorbench
