// satmesh convert: DSM <-> mesh and mesh format conversions.
#include <spdlog/spdlog.h>

#include <cmath>
#include <cstdio>
#include <sstream>
#include <string>
#include <vector>

#include "client/args.h"
#include "client/command.h"
#include "core/common/error.h"
#include "core/dsm/dsm.h"
#include "core/mesh/mesh_io.h"
#include "core/synth/perturb.h"

namespace satmesh::cli {
namespace {

constexpr const char* kUsage =
    "usage:\n"
    "  satmesh convert dsm2mesh IN.tif OUT.{ply,obj,drc,glb} [write options]\n"
    "  satmesh convert mesh2dsm IN_MESH --grid REF.tif OUT.tif [--origin X,Y,Z]\n"
    "  satmesh convert mesh IN OUT [write options] [--perturb-m A [--perturb-wavelength-m L]\n"
    "                                               [--seed S]]\n"
    "\n"
    "dsm2mesh: a vertex per valid DSM cell centre, two triangles per 2x2 block of valid\n"
    "  cells (one if exactly 3 are valid); nodata stays open.\n"
    "mesh2dsm: highest hit of a vertical ray through each cell centre of REF.tif's grid\n"
    "  (size, transform, CRS; its heights are ignored); NaN where the mesh is absent.\n"
    "  IN_MESH must be in REF.tif's CRS. --origin is added to the mesh's vertices (for\n"
    "  .drc/.glb files, which store tile-local positions).\n"
    "mesh: format by extension (.ply, .obj, .drc, .glb). --perturb-m moves every vertex\n"
    "  along its normal by smooth random noise of amplitude A m (plane waves of L m, default\n"
    "  15; synth::PerturbAlongNormals): an imperfect start whose truth is known.\n"
    "\n"
    "write options:\n"
    "  --ply-ascii          ASCII PLY (default binary little endian)\n"
    "  --ply-float          float PLY coordinates (default double, origin added)\n"
    "  --draco-bits N       Draco/glb position quantisation bits, in [8, 30] (default 16)\n"
    "  --draco-speed N      Draco encoder speed, in [0, 10] (default 6)\n"
    "\n"
    ".drc/.glb store tile-local positions: the mesh origin is logged, not written.\n";

int Usage(const std::string& problem) {
  if (!problem.empty()) std::fprintf(stderr, "satmesh convert: %s\n", problem.c_str());
  std::fprintf(problem.empty() ? stdout : stderr, "%s", kUsage);
  return problem.empty() ? kExitOk : kExitUsage;
}

MeshWriteOptions WriteOptions(const Args& args) {
  MeshWriteOptions options;
  options.ply_binary = !args.Has("ply-ascii");
  options.ply_double = !args.Has("ply-float");
  options.draco_position_bits = args.GetInt("draco-bits", options.draco_position_bits);
  options.draco_speed = args.GetInt("draco-speed", options.draco_speed);
  const std::string problem = options.Check();
  SATMESH_CHECK(problem.empty(), ErrorCode::kInvalidArgument, problem);
  return options;
}

void WriteAndLog(const std::string& path, const TriangleMesh& mesh, const Args& args) {
  WriteMesh(path, mesh, WriteOptions(args));
  spdlog::info("wrote {}: {} vertices, {} faces, origin ({:.3f}, {:.3f}, {:.3f})", path,
               mesh.num_vertices(), mesh.num_faces(), mesh.origin.x(), mesh.origin.y(),
               mesh.origin.z());
}

Eigen::Vector3d ParseOrigin(const std::string& text) {
  std::istringstream in(text);
  Eigen::Vector3d origin;
  char c1 = 0, c2 = 0;
  in >> origin.x() >> c1 >> origin.y() >> c2 >> origin.z();
  SATMESH_CHECK(in && c1 == ',' && c2 == ',' && (in >> std::ws).eof(),
                ErrorCode::kInvalidArgument, "option --origin: expected X,Y,Z, got '" + text + "'");
  return origin;
}

int RunConvert(const std::vector<std::string>& raw) {
  const Args args(raw, {"help", "ply-ascii", "ply-float"});
  const auto& pos = args.positionals();
  if (args.Has("help")) return Usage("");
  if (pos.empty()) return Usage("missing mode (dsm2mesh, mesh2dsm or mesh)");
  const std::string& mode = pos[0];
  if (pos.size() != 3) return Usage(mode + ": expected 2 paths, got " + std::to_string(pos.size() - 1));

  if (mode == "dsm2mesh") {
    const Dsm dsm = ReadDsm(pos[1]);
    spdlog::info("read {}: {}x{} cells", pos[1], dsm.width, dsm.height);
    WriteAndLog(pos[2], MeshFromDsm(dsm), args);
  } else if (mode == "mesh2dsm") {
    if (!args.Has("grid")) return Usage("mesh2dsm needs --grid REF.tif");
    const Dsm grid = ReadDsm(args.Require("grid"));
    TriangleMesh mesh = ReadMesh(pos[1]);
    if (args.Has("origin")) mesh.origin += ParseOrigin(args.Require("origin"));
    spdlog::info("read {}: {} vertices, {} faces", pos[1], mesh.num_vertices(), mesh.num_faces());
    const Dsm out = DsmFromMesh(mesh, grid);
    size_t valid = 0;
    for (float z : out.z) valid += std::isfinite(z);
    WriteDsm(pos[2], out);
    spdlog::info("wrote {}: {}x{} cells, {} with a height", pos[2], out.width, out.height,
                 valid);
  } else if (mode == "mesh") {
    TriangleMesh mesh = ReadMesh(pos[1]);
    if (args.Has("perturb-m")) {
      synth::PerturbOptions perturb;
      perturb.amplitude_m = args.GetDouble("perturb-m", perturb.amplitude_m);
      perturb.wavelength_m = args.GetDouble("perturb-wavelength-m", perturb.wavelength_m);
      perturb.seed = uint32_t(args.GetInt("seed", int(perturb.seed)));
      mesh = synth::PerturbAlongNormals(mesh, perturb);
    }
    WriteAndLog(pos[2], mesh, args);
  } else {
    return Usage("unknown mode '" + mode + "'");
  }
  return kExitOk;
}

}  // namespace

SATMESH_REGISTER_COMMAND("convert", "DSM <-> mesh, mesh format conversion", RunConvert);

}  // namespace satmesh::cli
