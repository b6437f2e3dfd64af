#include "core/common/memory.h"

#include <gtest/gtest.h>
#include <unistd.h>

#include <cstring>
#include <fstream>
#include <memory>
#include <vector>

namespace satmesh {
namespace {

double ResidentMb() {  // now, not the peak: /proc/self/statm's second field, in pages
  std::ifstream statm("/proc/self/statm");
  double size = 0, resident = 0;
  statm >> size >> resident;
  return resident * double(sysconf(_SC_PAGESIZE)) / double(1 << 20);
}

// Blocks freed below one still in use stay on glibc's heap, resident, until they are
// handed back: as a level's views and buffers were when a tile's write began.
TEST(ReturnFreedMemory, HandsTheHeapsFreedPagesBack) {
#if !defined(__GLIBC__)
  GTEST_SKIP() << "malloc_trim is glibc's";
#endif
  constexpr size_t kBlocks = 100000, kBytes = 1024;  // ~100 MB, each block under mmap's threshold
  std::vector<std::unique_ptr<char[]>> blocks;
  blocks.reserve(kBlocks);
  for (size_t i = 0; i < kBlocks; ++i) {
    blocks.emplace_back(new char[kBytes]);
    std::memset(blocks.back().get(), int(i), kBytes);  // touched: resident
  }
  auto top = std::make_unique<char[]>(kBytes);  // above them: the heap cannot shrink from its top
  std::memset(top.get(), 1, kBytes);
  blocks.clear();
  blocks.shrink_to_fit();
  const double before = ResidentMb();
  ReturnFreedMemory();
  const double after = ResidentMb();
  EXPECT_GT(before - after, 50.0) << before << " -> " << after << " MB";
  EXPECT_GE(PeakRssMb(), before);  // the peak is never below what was resident
}

}  // namespace
}  // namespace satmesh
