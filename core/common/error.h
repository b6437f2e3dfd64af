#pragma once
// satmesh's one error policy (see README "Errors"):
// - Invalid input (bad option, malformed file, missing key) throws satmesh::Error with a
//   code and a message naming the file/field/value. The server maps codes to HTTP status.
// - An expected algorithmic outcome (localisation not converging, a ray missing) is a
//   std::optional / bool, never an exception.
// - Cancellation throws Error{kCancelled} from Progress::ThrowIfCancelled().
#include <stdexcept>
#include <string>

namespace satmesh {

enum class ErrorCode {
  kInvalidArgument,  // an option or parameter out of range
  kInvalidInput,     // a malformed input file or model (named in the message)
  kNotFound,         // a file or resource that does not exist
  kIo,               // reading/writing failed
  kNoSpace,          // writing failed for lack of disk space (ENOSPC, EDQUOT): retry later
  kNotConverged,     // an iterative method failed where the caller required success
  kCancelled,        // the caller asked to stop
  kInternal,         // a bug
};

const char* ErrorCodeName(ErrorCode code);

class Error : public std::runtime_error {
 public:
  Error(ErrorCode code, const std::string& message)
      : std::runtime_error(message), code_(code) {}
  ErrorCode code() const { return code_; }

 private:
  ErrorCode code_;
};

[[noreturn]] void ThrowError(ErrorCode code, const std::string& message);
// For a failed system call with `errno_value`: Error{kNoSpace} for ENOSPC/EDQUOT, else
// Error{kIo}; the message is `what` + ": " + strerror ("No space left on device").
[[noreturn]] void ThrowIoError(const std::string& what, int errno_value);
// For a library's write error text (GDAL/libtiff put strerror in it): kNoSpace when it
// says "No space left on device" or "Disk quota exceeded", else kIo.
ErrorCode WriteErrorCode(const std::string& message);

}  // namespace satmesh

// Throws satmesh::Error(code, message) when cond is false.
#define SATMESH_CHECK(cond, code, message)                 \
  do {                                                     \
    if (!(cond)) ::satmesh::ThrowError((code), (message)); \
  } while (false)
