#pragma once
// Helpers shared by the libFuzzer targets (tests/fuzz/README.md).
#include <unistd.h>

#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <exception>
#include <filesystem>
#include <fstream>
#include <string>

namespace satmesh::fuzz {

// A scratch file of this fuzzing process (in /dev/shm when it exists: the readers under
// test take paths), removed at exit.
inline std::string ScratchFile(const std::string& extension) {
  const std::string dir = std::filesystem::is_directory("/dev/shm") ? "/dev/shm" : "/tmp";
  const std::string path = dir + "/satmesh_fuzz_" + std::to_string(::getpid()) + extension;
  struct Remover {
    std::string path;
    ~Remover() { std::remove(path.c_str()); }
  };
  static thread_local Remover remover{path};
  remover.path = path;
  return path;
}

inline void WriteBytes(const std::string& path, const uint8_t* data, size_t size) {
  std::ofstream out(path, std::ios::binary | std::ios::trunc);
  out.write(reinterpret_cast<const char*>(data), std::streamsize(size));
}

// A broken promise of the code under test: print it and abort, so libFuzzer keeps the input.
[[noreturn]] inline void Fail(const std::string& what) {
  std::fprintf(stderr, "fuzz invariant violated: %s\n", what.c_str());
  std::fflush(stderr);
  std::abort();
}

}  // namespace satmesh::fuzz
