#include "client/args.h"

#include <algorithm>

#include "core/common/error.h"

namespace satmesh::cli {

Args::Args(const std::vector<std::string>& args, const std::vector<std::string>& flags) {
  for (size_t i = 0; i < args.size(); ++i) {
    const std::string& a = args[i];
    if (a.rfind("--", 0) != 0 || a.size() == 2) {
      positionals_.push_back(a);
      continue;
    }
    std::string key = a.substr(2);
    if (auto eq = key.find('='); eq != std::string::npos) {
      values_.emplace(key.substr(0, eq), key.substr(eq + 1));
    } else if (std::find(flags.begin(), flags.end(), key) != flags.end()) {
      values_.emplace(key, "true");
    } else {
      SATMESH_CHECK(i + 1 < args.size(), ErrorCode::kInvalidArgument,
                    "option --" + key + " needs a value");
      values_.emplace(key, args[++i]);
    }
  }
}

std::optional<std::string> Args::Get(const std::string& key) const {
  auto it = values_.find(key);
  if (it == values_.end()) return std::nullopt;
  return it->second;
}

std::string Args::Require(const std::string& key) const {
  auto v = Get(key);
  SATMESH_CHECK(v.has_value(), ErrorCode::kInvalidArgument, "missing required option --" + key);
  return *v;
}

std::string Args::GetOr(const std::string& key, const std::string& fallback) const {
  return Get(key).value_or(fallback);
}

double Args::GetDouble(const std::string& key, double fallback) const {
  auto v = Get(key);
  if (!v) return fallback;
  try {
    size_t used = 0;
    double d = std::stod(*v, &used);
    if (used == v->size()) return d;
  } catch (...) {
  }
  ThrowError(ErrorCode::kInvalidArgument, "option --" + key + ": not a number: '" + *v + "'");
}

int Args::GetInt(const std::string& key, int fallback) const {
  auto v = Get(key);
  if (!v) return fallback;
  try {
    size_t used = 0;
    int d = std::stoi(*v, &used);
    if (used == v->size()) return d;
  } catch (...) {
  }
  ThrowError(ErrorCode::kInvalidArgument, "option --" + key + ": not an integer: '" + *v + "'");
}

std::vector<std::string> Args::GetAll(const std::string& key) const {
  std::vector<std::string> out;
  auto [lo, hi] = values_.equal_range(key);
  for (auto it = lo; it != hi; ++it) out.push_back(it->second);
  return out;
}

}  // namespace satmesh::cli
