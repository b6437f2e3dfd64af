#pragma once
// Minimal option parsing shared by the subcommands: --key value, --flag, positionals.
#include <map>
#include <optional>
#include <string>
#include <vector>

namespace satmesh::cli {

class Args {
 public:
  // `flags` lists options that take no value. Throws Error{kInvalidArgument} on a
  // missing value.
  Args(const std::vector<std::string>& args, const std::vector<std::string>& flags = {});

  bool Has(const std::string& key) const { return values_.count(key) > 0; }
  std::optional<std::string> Get(const std::string& key) const;
  std::string Require(const std::string& key) const;  // throws naming the option
  std::string GetOr(const std::string& key, const std::string& fallback) const;
  double GetDouble(const std::string& key, double fallback) const;
  int GetInt(const std::string& key, int fallback) const;
  // All values of a repeatable option (e.g. --set a=1 --set b=2).
  std::vector<std::string> GetAll(const std::string& key) const;
  const std::vector<std::string>& positionals() const { return positionals_; }

 private:
  std::multimap<std::string, std::string> values_;
  std::vector<std::string> positionals_;
};

}  // namespace satmesh::cli
