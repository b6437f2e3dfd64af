#pragma once
// File writers of the scene directory (GDAL GeoTIFFs with RPC tags, PLY points, JSON,
// preview PNG). Internal to core/synth; GDAL/OpenCV stay in the .cc.
#include <Eigen/Core>
#include <cstdint>
#include <string>
#include <vector>

#include "core/dsm/dsm.h"
#include "core/image/acquisition_info.h"
#include "core/image/image.h"
#include "core/rpc/rpc_model.h"
#include "core/synth/scene_writer.h"

namespace satmesh::synth {

// UInt16 GeoTIFF (values rounded and clamped to [0, 65535]) with the RPC in the "RPC"
// metadata domain and the acquisition in the "IMD" domain as GDAL exposes a WorldView IMD
// (ImdMetadata; GTiff keeps it in its GDAL_METADATA tag).
void WriteImageWithRpc(const std::string& path, const ImageF& dn, const RpcModel& rpc,
                       const AcquisitionInfo& acquisition = {});
// Byte GeoTIFF on the grid of `grid` (its z is ignored).
void WriteMaskTif(const std::string& path, const Dsm& grid, const std::vector<uint8_t>& mask);
// Binary PLY: x, y, z double, nx, ny, nz float.
void WritePointsPly(const std::string& path, const std::vector<Eigen::Vector3d>& points,
                    const std::vector<Eigen::Vector3f>& normals);
void WriteSceneJson(const std::string& path, const SynthOptions& options, const SynthResult& r);
void WriteJobJson(const std::string& path, const SynthOptions& options, const SynthResult& r);
// Contact sheet: the views, truth DSM, initial DSM and |initial - truth|.
void WritePreview(const std::string& path, const std::vector<ImageF>& views,
                  const std::vector<std::string>& view_labels, const Dsm& truth,
                  const Dsm& initial);

}  // namespace satmesh::synth
