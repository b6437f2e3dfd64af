#pragma once
// Scratch paths of a test process under the system temp directory, removed when the
// process exits (so repeated test runs do not fill /tmp).
#include <filesystem>
#include <mutex>
#include <set>
#include <string>
#include <system_error>

namespace satmesh::testing {

inline void RemoveAtExit(const std::filesystem::path& path) {
  struct Registry {
    std::mutex mutex;
    std::set<std::string> paths;
    ~Registry() {
      for (const auto& p : paths) {
        std::error_code ignored;
        std::filesystem::remove_all(p, ignored);
      }
    }
  };
  static Registry registry;
  std::lock_guard<std::mutex> lock(registry.mutex);
  registry.paths.insert(path.string());
}

}  // namespace satmesh::testing
