#include "server/problem.h"

#include "core/common/error.h"

namespace satmesh::server {
namespace {

const char* Title(int status) {
  switch (status) {
    case 400: return "Bad Request";
    case 401: return "Unauthorized";
    case 403: return "Forbidden";
    case 404: return "Not Found";
    case 405: return "Method Not Allowed";
    case 409: return "Conflict";
    case 413: return "Payload Too Large";
    case 415: return "Unsupported Media Type";
    case 422: return "Unprocessable Content";
    case 503: return "Service Unavailable";
    case 507: return "Insufficient Storage";
    default: return status < 500 ? "Client Error" : "Internal Server Error";
  }
}

// satmesh::ErrorCode -> HTTP status. The request body or its inputs are the caller's
// responsibility (4xx); I/O and bugs are ours (5xx).
int StatusFor(ErrorCode code) {
  switch (code) {
    case ErrorCode::kInvalidArgument: return 400;
    case ErrorCode::kInvalidInput: return 422;
    case ErrorCode::kNotFound: return 404;
    case ErrorCode::kCancelled: return 409;
    case ErrorCode::kNotConverged: return 422;
    case ErrorCode::kIo: return 500;
    case ErrorCode::kNoSpace: return 507;
    case ErrorCode::kInternal: return 500;
  }
  return 500;
}

Problem Make(int status, const std::string& type, const std::string& detail) {
  return {status, {{"type", ProblemTypeUri(type)}, {"title", Title(status)},
                   {"status", status}, {"detail", detail}}};
}

}  // namespace

std::string ProblemTypeUri(const std::string& name) {
  if (name == "no-such-job" || name == "result-not-ready" || name == "no-such-process")
    return "http://www.opengis.net/def/exceptions/ogcapi-processes-1/1.0/" + name;
  return "https://satmesh.org/problems/" + name;
}

Problem ProblemFromException(std::exception_ptr error) {
  try {
    std::rethrow_exception(error);
  } catch (const HttpError& e) {
    return Make(e.status(), e.type(), e.what());
  } catch (const Error& e) {
    return Make(StatusFor(e.code()), ErrorCodeName(e.code()), e.what());
  } catch (const nlohmann::json::exception& e) {
    return Make(400, "invalid-json", e.what());
  } catch (const std::exception& e) {
    return Make(500, "internal", e.what());
  } catch (...) {
    return Make(500, "internal", "unknown error");
  }
}

Problem ProblemForStatus(int status, const std::string& detail) {
  const char* type = status == 413 ? "payload-too-large" : status == 404 ? "not-found"
                   : status == 401 ? "unauthorized" : status < 500 ? "bad-request" : "internal";
  return Make(status, type, detail);
}

}  // namespace satmesh::server
