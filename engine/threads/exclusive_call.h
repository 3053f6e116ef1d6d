// One call at a time on one object: a method that writes the object's scratch (SolverFeatherstone::step,
// CollisionPipeline::collide) holds its busy flag for the call's duration; a second call from another thread
// meanwhile throws Error instead of racing on the scratch. The flag is released when the call returns or throws.
#pragma once

#include <atomic>

#include "engine/model/error.h"

namespace novaphy {

class ExclusiveCall {
 public:
  // takes `busy`, or throws naming `what` (e.g. "SolverFeatherstone.step") where another call holds it
  ExclusiveCall(std::atomic<bool>& busy, const char* what) : busy_(busy) {
    if (busy_.exchange(true, std::memory_order_acquire))
      fail(what, " called while another call of the same object runs on another thread (use one object per thread)");
  }
  ~ExclusiveCall() { busy_.store(false, std::memory_order_release); }
  ExclusiveCall(const ExclusiveCall&) = delete;
  ExclusiveCall& operator=(const ExclusiveCall&) = delete;

 private:
  std::atomic<bool>& busy_;
};

}  // namespace novaphy
