#pragma once
// Progress reporting and cancellation, passed explicitly to long-running stages.
#include <functional>
#include <string>

#include "core/common/error.h"

namespace satmesh {

struct Progress {
  // Called with the overall fraction done in [0, 1] and a short stage label.
  std::function<void(double fraction, const std::string& stage)> on_progress;
  // Returns true when the caller wants the stage to stop as soon as possible.
  std::function<bool()> is_cancelled;

  void Report(double fraction, const std::string& stage) const {
    if (on_progress) on_progress(fraction, stage);
  }
  bool Cancelled() const { return is_cancelled && is_cancelled(); }
  void ThrowIfCancelled() const {
    if (Cancelled()) ThrowError(ErrorCode::kCancelled, "cancelled by the caller");
  }
};

}  // namespace satmesh
