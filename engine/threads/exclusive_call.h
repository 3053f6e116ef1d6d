// One call at a time on one object: a method that writes the object's scratch (SolverFeatherstone::step,
// CollisionPipeline::collide) holds its CallFlag for the call's duration; a call from another thread meanwhile throws
// Error instead of racing on the scratch. The flag is released when the outermost call returns or throws.
// The thread holding the flag may take it again (nested): a caller can hold an object's flag around work that belongs
// with its call (the binding widening a float32 State before a step and rounding it after), so a call refused on
// another thread touches nothing.
#pragma once

#include <atomic>
#include <thread>

#include "engine/model/error.h"

namespace novaphy {

// which thread holds an object's calls (none: a default id) and how deeply they nest there
class CallFlag {
 public:
  bool held() const { return owner_.load(std::memory_order_acquire) != std::thread::id(); }

 private:
  friend class ExclusiveCall;
  std::atomic<std::thread::id> owner_{};
  int depth_ = 0;  // read and written by the owner only
};

class ExclusiveCall {
 public:
  // takes `flag`, or throws naming `what` (e.g. "SolverFeatherstone.step") where another thread holds it
  ExclusiveCall(CallFlag& flag, const char* what) : flag_(flag) {
    const std::thread::id me = std::this_thread::get_id();
    // only this thread ever stores its own id, so a relaxed read that sees it is this thread's own earlier store
    if (flag_.owner_.load(std::memory_order_relaxed) != me) {
      std::thread::id none;
      if (!flag_.owner_.compare_exchange_strong(none, me, std::memory_order_acquire))
        fail(what, " called while another call of the same object runs on another thread (use one object per thread)");
    }
    ++flag_.depth_;
  }
  ~ExclusiveCall() {
    if (--flag_.depth_ == 0) flag_.owner_.store(std::thread::id(), std::memory_order_release);
  }
  ExclusiveCall(const ExclusiveCall&) = delete;
  ExclusiveCall& operator=(const ExclusiveCall&) = delete;

 private:
  CallFlag& flag_;
};

}  // namespace novaphy
