#pragma once
// RFC 7807 problem details: the one place that maps errors to HTTP status codes.
#include <nlohmann/json.hpp>
#include <exception>
#include <stdexcept>
#include <string>

namespace satmesh::server {

// An error that is only meaningful over HTTP (no such job, result not ready, auth).
class HttpError : public std::runtime_error {
 public:
  HttpError(int status, std::string type, const std::string& detail)
      : std::runtime_error(detail), status_(status), type_(std::move(type)) {}
  int status() const { return status_; }
  const std::string& type() const { return type_; }  // short name, e.g. "no-such-job"

 private:
  int status_;
  std::string type_;
};

struct Problem {
  int status = 500;
  nlohmann::json body;  // type, title, status, detail
};

// Maps satmesh::Error codes, HttpError and anything else (500) to a problem.
Problem ProblemFromException(std::exception_ptr error);
// A problem for a status that httplib produced itself (413, 404 route, 400 parse).
Problem ProblemForStatus(int status, const std::string& detail);
// The problem "type" URI for a short name (OGC exception URIs where OGC defines them).
std::string ProblemTypeUri(const std::string& name);

}  // namespace satmesh::server
