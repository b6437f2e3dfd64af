#include "core/common/error.h"

#include <cerrno>
#include <cstring>

namespace satmesh {

const char* ErrorCodeName(ErrorCode code) {
  switch (code) {
    case ErrorCode::kInvalidArgument: return "invalid-argument";
    case ErrorCode::kInvalidInput: return "invalid-input";
    case ErrorCode::kNotFound: return "not-found";
    case ErrorCode::kIo: return "io";
    case ErrorCode::kNoSpace: return "no-space";
    case ErrorCode::kNotConverged: return "not-converged";
    case ErrorCode::kCancelled: return "cancelled";
    case ErrorCode::kInternal: return "internal";
  }
  return "unknown";
}

void ThrowError(ErrorCode code, const std::string& message) { throw Error(code, message); }

ErrorCode WriteErrorCode(const std::string& message) {
  for (int e : {ENOSPC, EDQUOT})
    if (message.find(std::strerror(e)) != std::string::npos) return ErrorCode::kNoSpace;
  return ErrorCode::kIo;
}

void ThrowIoError(const std::string& what, int errno_value) {
  const bool full = errno_value == ENOSPC || errno_value == EDQUOT;
  throw Error(full ? ErrorCode::kNoSpace : ErrorCode::kIo,
              what + ": " + (errno_value ? std::strerror(errno_value) : "unknown error"));
}

}  // namespace satmesh
