#pragma once
namespace satmesh {
// Registers GDAL drivers once and routes GDAL's error handler into spdlog. Thread-safe.
void EnsureGdalInitialized();
}  // namespace satmesh
