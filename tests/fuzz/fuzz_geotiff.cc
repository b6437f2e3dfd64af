// libFuzzer target: a GeoTIFF (or any raster GDAL recognises) through our readers as the
// job's files are read: raster info, RPC tags, acquisition metadata (IMD), a pixel window,
// the DSM grid and a DSM window. GDAL itself is Debian's (not instrumented): a crash inside
// it still shows, an overflow it does not catch itself does not.
#include <cpl_vsi.h>
#include <gdal_priv.h>

#include <algorithm>

#include "core/common/error.h"
#include "core/common/gdal_init.h"
#include "core/image/image_io.h"
#include "core/rpc/rpc_io.h"
#include "core/tiling/tile_plan.h"
#include "tests/fuzz/fuzz_util.h"

extern "C" int LLVMFuzzerInitialize(int*, char***) {
  satmesh::EnsureGdalInitialized();
  CPLPushErrorHandler(CPLQuietErrorHandler);
  CPLSetConfigOption("GDAL_PAM_ENABLED", "NO");  // no .aux.xml written beside the input
  return 0;
}

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  using namespace satmesh;
  const char* path = "/vsimem/fuzz_geotiff.tif";
  VSIFCloseL(VSIFileFromMemBuffer(path, const_cast<GByte*>(data), vsi_l_offset(size), /*bTakeOwnership=*/FALSE));
  auto guarded = [&](auto&& read) {
    try {
      read();
    } catch (const Error& e) {
      if (e.code() == ErrorCode::kInternal) fuzz::Fail(std::string("internal error: ") + e.what());
    }
  };
  RasterInfo info;
  guarded([&] { info = ReadRasterInfo(path); });
  guarded([&] { ReadRpc(path); });
  guarded([&] { ReadAcquisitionInfo(path); });
  if (info.width > 0 && info.height > 0 && info.bands > 0) {
    const PixelWindow w{std::max(0, info.width - 40), std::max(0, info.height - 40), 64, 64};
    guarded([&] { ReadImageWindow(path, 1, w); });
  }
  guarded([&] {
    const DsmGrid grid = ReadDsmGrid(path);
    ReadDsmWindow(path, PixelWindow{0, 0, std::min(grid.width, 64), std::min(grid.height, 64)});
  });
  VSIUnlink(path);
  return 0;
}
