// Writes the fuzz targets' seed corpora with our own writers (the files a user of
// satmesh would feed back in), one folder per target under argv[1]:
//   fuzz_seeds tests/fuzz/corpus
// The job JSON and HTTP seeds are the documented forms (README, proto/openapi.json).
#include <gdal_priv.h>

#include <cstdio>
#include <filesystem>
#include <fstream>
#include <sstream>

#include "core/common/gdal_init.h"
#include "core/dsm/dsm.h"
#include "core/mesh/mesh_io.h"
#include "core/rpc/rpc_model.h"
#include "core/synth/scene_files.h"
#include "tests/core/mesh/mesh_fixtures.h"

namespace {

using namespace satmesh;
namespace fs = std::filesystem;

void Put(const fs::path& path, const std::string& bytes) {
  fs::create_directories(path.parent_path());
  std::ofstream(path, std::ios::binary) << bytes;
}

std::string Slurp(const fs::path& path) {
  std::ifstream in(path, std::ios::binary);
  std::ostringstream s;
  s << in.rdbuf();
  return s.str();
}

// A near-nadir camera over Jacksonville (the synthetic scenes' place), 0.5 m pixels.
RpcModel SeedRpc() {
  RpcCoefficients c;
  c.line_off = 500, c.samp_off = 500, c.lat_off = 30.33, c.long_off = -81.66, c.height_off = 20;
  c.line_scale = 500, c.samp_scale = 500, c.lat_scale = 0.0025, c.long_scale = 0.003, c.height_scale = 100;
  c.samp_num[1] = 1.0, c.samp_num[3] = 0.02, c.line_num[2] = -1.0, c.line_num[3] = 0.03, c.line_num[4] = 1e-4;
  c.samp_den[0] = c.line_den[0] = 1.0, c.samp_den[1] = 1e-4;
  return RpcModel::FromCoefficients(c);
}

void Meshes(const fs::path& root) {
  TriangleMesh mesh = testing::CreateGridMesh(3, 2.f, /*wavy=*/true);
  mesh.origin = {435000, 3356000, 20};
  mesh.crs = "EPSG:32617";
  const fs::path tmp = fs::temp_directory_path() / "satmesh_fuzz_seed";
  MeshWriteOptions ascii;
  ascii.ply_binary = false;
  MeshWriteOptions floats;
  floats.ply_double = false;
  WriteMesh(tmp.string() + ".ply", mesh);
  Put(root / "ply/binary_double.ply", Slurp(tmp.string() + ".ply"));
  WriteMesh(tmp.string() + ".ply", mesh, ascii);
  Put(root / "ply/ascii.ply", Slurp(tmp.string() + ".ply"));
  WriteMesh(tmp.string() + ".ply", mesh, floats);
  Put(root / "ply/binary_float.ply", Slurp(tmp.string() + ".ply"));
  WriteMesh(tmp.string() + ".obj", mesh);
  Put(root / "obj/grid.obj", Slurp(tmp.string() + ".obj"));
  Put(root / "obj/forms.obj", "v 0 0 0\nv 1 0 0\nv 1 1 0\nv 0 1 0\nvt 0 0\nvn 0 0 1\nf 1/1/1 2/1/1 3/1/1 4/1/1\nf -1 -2 -3\n");
  WriteMesh(tmp.string() + ".drc", mesh);
  Put(root / "drc/grid.drc", Slurp(tmp.string() + ".drc"));
  WriteMesh(tmp.string() + ".glb", mesh);
  Put(root / "glb/grid.glb", Slurp(tmp.string() + ".glb"));
  std::vector<float> heights;
  for (const auto& v : mesh.vertices) heights.push_back(v.z());
  WriteGlb(tmp.string() + ".glb", mesh, {{"_HEIGHT", heights}});
  Put(root / "glb/grid_height.glb", Slurp(tmp.string() + ".glb"));
  for (const char* ext : {".ply", ".obj", ".drc", ".glb"}) fs::remove(tmp.string() + ext);
}

void RpcTexts(const fs::path& root) {
  const auto md = SeedRpc().ToKeyValues();
  std::string lines = std::string(1, '\0');
  for (const auto& [k, v] : md) lines += k + ": " + v + "\n";
  Put(root / "rpc_text/key_values.txt", lines);
  // GDAL's own sidecar writers: a GeoTIFF created with RPCTXT=YES / RPB=YES.
  const fs::path tmp = fs::temp_directory_path() / "satmesh_fuzz_seed";
  for (const char* option : {"RPCTXT", "RPB"}) {
    char** options = CSLSetNameValue(nullptr, option, "YES");
    GDALDataset* ds = GetGDALDriverManager()->GetDriverByName("GTiff")->Create(
        (tmp.string() + ".tif").c_str(), 4, 4, 1, GDT_Byte, options);
    CSLDestroy(options);
    char** list = nullptr;
    for (const auto& [k, v] : md) list = CSLSetNameValue(list, k.c_str(), v.c_str());
    ds->SetMetadata(list, "RPC");
    CSLDestroy(list);
    GDALClose(GDALDataset::ToHandle(ds));
    // (read now: the next Create on the same name deletes the earlier sidecar)
    if (std::string(option) == "RPCTXT") Put(root / "rpc_text/rpc_txt.txt", std::string(1, '\1') + Slurp(tmp.string() + "_RPC.TXT"));
    else Put(root / "rpc_text/rpb.txt", std::string(1, '\2') + Slurp(tmp.string() + ".RPB"));
  }
  for (const char* ext : {".tif", "_RPC.TXT", ".RPB"}) fs::remove(tmp.string() + ext);
}

void Rasters(const fs::path& root) {
  const fs::path tmp = fs::temp_directory_path() / "satmesh_fuzz_seed.tif";
  ImageF image(16, 16);
  for (int r = 0; r < 16; ++r)
    for (int c = 0; c < 16; ++c) image.at(c, r) = float(100 + 7 * c + 13 * r);
  AcquisitionInfo acquisition;
  acquisition.sun_elevation_deg = 55, acquisition.sun_azimuth_deg = 140, acquisition.off_nadir_deg = 12;
  synth::WriteImageWithRpc(tmp.string(), image, SeedRpc(), acquisition);
  Put(root / "geotiff/image_rpc.tif", Slurp(tmp));
  Dsm dsm;
  dsm.width = dsm.height = 8;
  dsm.geo_transform = {435000, 0.5, 0, 3356040, 0, -0.5};
  dsm.crs_wkt = "EPSG:32617";
  for (int k = 0; k < 64; ++k) dsm.z.push_back(k % 9 == 0 ? NAN : float(20 + k % 8));
  OGRSpatialReference srs;
  srs.SetFromUserInput("EPSG:32617");
  char* wkt = nullptr;
  srs.exportToWkt(&wkt);
  dsm.crs_wkt = wkt;
  CPLFree(wkt);
  WriteDsm(tmp.string(), dsm);
  Put(root / "geotiff/dsm.tif", Slurp(tmp));
  fs::remove(tmp);
}

void Jobs(const fs::path& root) {
  const std::string job =
      R"({"images": [{"href": "a.tif"}, {"href": "b.tif", "bias": [0.5, -0.25]}],
 "initial": {"dsm": "dsm.tif", "fill_holes_m": 20},
 "outputs": {"crs": "EPSG:32617"},
 "options": {"iterations_per_level": 20, "max_pair_angle_deg": 45, "levels": 2, "estimate_bias": false},
 "aoi": {"bbox": [436900, 3355700, 437100, 3355900], "crs": "EPSG:32617"},
 "tiling": {"size_m": 100, "overlap_m": 24, "workers": 2, "memory_budget_mb": 2000}})";
  Put(root / "job_json/readme_job.json", job);
  Put(root / "job_json/ogc_inputs.json", R"({"inputs": {"job": )" + job + "}}");
  Put(root / "job_json/polygon.json",
      R"({"images": [{"href": "sub/c.tif"}, {"href": "/vsicurl/https://data.example.com/x.tif"}],
 "initial": {"dsm": "dsm.tif"}, "aoi": {"polygon": [[0, 0], [10, 0], [10, 10]], "crs": "EPSG:4326"}})");
  // HTTP: first byte = method (0-2 GET, 3 DELETE, 4 POST, 5 OPTIONS; +128 with the token),
  // then the request target; {job} is a finished job's id.
  const std::vector<std::pair<std::string, std::string>> http = {
      {"landing", "\x80/"}, {"jobs", "\x80/jobs?status=successful&limit=5"},
      {"job", "\x80/jobs/{job}"}, {"tiles", "\x80/jobs/{job}/tiles"},
      {"tile", "\x80/jobs/{job}/tiles/0_0.glb"}, {"results", "\x80/jobs/{job}/results"},
      {"tileset", "\x80/jobs/{job}/results/tileset.json"}, {"live", "\x80/jobs/{job}/tileset.json"},
      {"viewer", "\x80/jobs/{job}/viewer"}, {"cesium", "\x80/viewer/Cesium/Cesium.js"},
      {"process", "\x80/processes/refine-mesh"}, {"health", "/health"}, {"metrics", "\x80/metrics"},
      {"dismiss", "\x83/jobs/{job}"}, {"preflight", "\x05/jobs"},
      {"submit", "\x84/processes/refine-mesh/execution\n" + job},
      {"traversal", "\x80/viewer/Cesium/..%2f..%2f..%2fetc%2fpasswd"}};
  for (const auto& [name, bytes] : http) Put(root / ("http/" + name), bytes);
}

}  // namespace

int main(int argc, char** argv) {
  if (argc != 2) {
    std::fprintf(stderr, "usage: fuzz_seeds CORPUS_ROOT\n");
    return 2;
  }
  EnsureGdalInitialized();
  const fs::path root = argv[1];
  Meshes(root);
  RpcTexts(root);
  Rasters(root);
  Jobs(root);
  std::printf("seeds written under %s\n", root.c_str());
  return 0;
}
