#include "core/common/gdal_init.h"

#include <cpl_error.h>
#include <gdal.h>
#include <spdlog/spdlog.h>

#include <mutex>

namespace satmesh {
namespace {
void CPL_STDCALL GdalErrorToSpdlog(CPLErr level, CPLErrorNum num, const char* msg) {
  if (level == CE_Debug) spdlog::debug("GDAL: {}", msg);
  else if (level == CE_Warning) spdlog::warn("GDAL: {}", msg);
  else if (level >= CE_Failure) spdlog::debug("GDAL error {}: {}", num, msg);
}
}  // namespace

void EnsureGdalInitialized() {
  static std::once_flag once;
  std::call_once(once, [] {
    GDALAllRegister();
    CPLSetErrorHandler(GdalErrorToSpdlog);
  });
}

}  // namespace satmesh
