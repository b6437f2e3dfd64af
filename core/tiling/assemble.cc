#include "core/tiling/assemble.h"

#include <spdlog/spdlog.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <filesystem>
#include <limits>
#include <optional>

#include "core/common/error.h"
#include "core/common/stats.h"
#include "core/dsm/dsm.h"
#include "core/mesh/mesh_clean.h"
#include "core/mesh/mesh_io.h"

namespace satmesh {
namespace {

namespace fs = std::filesystem;
constexpr float kNaN = std::numeric_limits<float>::quiet_NaN();

// A tile's refined (padded) DSM, addressed by the initial DSM's global cell indices.
struct TileDsm {
  Dsm dsm;
  PixelWindow cells;
  float At(int col, int row) const {
    const int i = col - cells.col0, j = row - cells.row0;
    if (i < 0 || j < 0 || i >= cells.width || j >= cells.height) return kNaN;
    return dsm.at(i, j);
  }
};

TileDsm LoadTileDsm(const std::string& out_dir, const PlannedTile& tile) {
  return TileDsm{ReadDsm((fs::path(out_dir) / TileDsmPath(tile)).string()), tile.padded_cells};
}

SeamStats Stats(const std::string& a, const std::string& b, const std::vector<double>& diffs) {
  SeamStats s{a, b, int(diffs.size())};
  if (diffs.empty()) return s;
  std::vector<double> abs_diffs;
  double sum = 0;
  for (double d : diffs) abs_diffs.push_back(std::abs(d)), sum += d;
  s.median_abs_m = Quantile(abs_diffs, 0.5);
  s.p95_abs_m = Quantile(abs_diffs, 0.95);
  s.max_abs_m = *std::max_element(abs_diffs.begin(), abs_diffs.end());
  s.mean_m = sum / double(diffs.size());
  return s;
}

// z_a - z_b on the cells either side of the shared core edge of a and its east (dx = 1)
// or north (dy = 1) neighbour b.
std::vector<double> SeamDiffs(const TileDsm& a, const TileDsm& b, const PlannedTile& ta, bool east) {
  std::vector<double> diffs;
  const PixelWindow& c = ta.core_cells;
  for (int k = 0; k < (east ? c.height : c.width); ++k) {
    for (int side = -1; side <= 0; ++side) {  // the cell before and after the edge
      const int col = east ? c.col0 + c.width + side : c.col0 + k;
      const int row = east ? c.row0 + k : c.row0 + side;
      const float za = a.At(col, row), zb = b.At(col, row);
      if (std::isfinite(za) && std::isfinite(zb)) diffs.push_back(double(za) - zb);
    }
  }
  return diffs;
}

void AppendPiece(const TriangleMesh& piece, TriangleMesh* mesh) {
  if (mesh->vertices.empty()) mesh->origin = piece.origin, mesh->crs = piece.crs;
  const Eigen::Vector3f shift = (piece.origin - mesh->origin).cast<float>();
  const int base = int(mesh->vertices.size());
  // height_sigma: kept only while every piece has it (dropped as soon as one lacks it).
  const bool had_sigma = mesh->height_sigma.size() == size_t(base) && base > 0;
  const bool has_sigma = piece.height_sigma.size() == piece.vertices.size();
  if (base == 0 && has_sigma) mesh->height_sigma = piece.height_sigma;
  else if (had_sigma && has_sigma)
    mesh->height_sigma.insert(mesh->height_sigma.end(), piece.height_sigma.begin(), piece.height_sigma.end());
  else mesh->height_sigma.clear();
  for (const auto& v : piece.vertices) mesh->vertices.push_back(v + shift);
  for (const auto& f : piece.faces) mesh->faces.push_back(f + Eigen::Vector3i::Constant(base));
}

bool SameWindow(const PixelWindow& a, const PixelWindow& b) {
  return a.col0 == b.col0 && a.row0 == b.row0 && a.width == b.width && a.height == b.height;
}

// A job of one tile whose padded cells are the AOI's: its piece is the mesh, its DSM and
// confidence rasters are the job's, so they are copied, not read and written again
// (stereo 0.5 m: 0.2 s of a 3.7 s job; the read and rewrite only rounded the piece's
// coordinates through floats, by up to 8e-6 m).
bool CopiedTheOnlyTile(const JobPlan& plan, const std::vector<TileResult>& results,
                       const std::string& out_dir, Assembly* out) {
  if (plan.tiles.size() != 1 || results.size() != 1 || !results[0].ok) return false;
  const PlannedTile& tile = plan.tiles[0];
  if (!SameWindow(tile.padded_cells, plan.aoi_cells) || !SameWindow(tile.core_cells, plan.aoi_cells))
    return false;
  const auto copy = [&](const std::string& from, const std::string& to) {
    std::error_code ec;
    fs::copy_file(fs::path(out_dir) / from, to, fs::copy_options::overwrite_existing, ec);
    SATMESH_CHECK(!ec, ErrorCode::kIo, "cannot write " + to + " (a copy of " + from + "): " + ec.message());
  };
  copy(TilePiecePath(tile), out->mesh_path);
  copy(TileDsmPath(tile), out->dsm_path);
  if (fs::exists(fs::path(out_dir) / TileConfidencePath(tile))) {
    out->confidence_path = (fs::path(out_dir) / "confidence.tif").string();
    copy(TileConfidencePath(tile), out->confidence_path);
  }
  out->vertices = results[0].core_vertices;
  out->faces = results[0].core_faces;
  return true;
}

// Mesh and DSM: each successful tile's core, the pieces merged where they meet, written to
// out->mesh_path, out->dsm_path and (where every successful tile has one) confidence.tif.
void MergeTiles(const JobPlan& plan, const std::vector<TileResult>& results,
                const std::string& out_dir, Assembly* out) {
  TriangleMesh mesh;
  Dsm dsm;
  const PixelWindow& a = plan.aoi_cells;
  dsm.width = a.width, dsm.height = a.height, dsm.crs_wkt = plan.dsm.crs_wkt;
  dsm.geo_transform = plan.dsm.geo_transform;
  dsm.geo_transform[0] += a.col0 * dsm.geo_transform[1];
  dsm.geo_transform[3] += a.row0 * dsm.geo_transform[5];
  dsm.z.assign(size_t(a.width) * a.height, kNaN);
  Dsm confidence = dsm;  // written if every successful tile has one
  bool all_confidence = true;
  for (const auto& r : results) {
    if (!r.ok) continue;
    const PlannedTile& tile = plan.tiles[r.index];
    AppendPiece(ReadMesh((fs::path(out_dir) / TilePiecePath(tile)).string()), &mesh);
    const TileDsm t = LoadTileDsm(out_dir, tile);
    const fs::path confidence_path = fs::path(out_dir) / TileConfidencePath(tile);
    std::optional<TileDsm> tc;
    if (all_confidence && fs::exists(confidence_path))
      tc = TileDsm{ReadDsm(confidence_path.string()), tile.padded_cells};
    all_confidence = all_confidence && tc.has_value();
    const PixelWindow& c = tile.core_cells;
    for (int row = c.row0; row < c.row0 + c.height; ++row)
      for (int col = c.col0; col < c.col0 + c.width; ++col) {
        dsm.at(col - a.col0, row - a.row0) = t.At(col, row);
        if (tc) confidence.at(col - a.col0, row - a.row0) = tc->At(col, row);
      }
  }
  // Pieces meet along the cores' edges: a cut vertex two tiles share is one vertex.
  const MeshDebris merged = CleanMesh(&mesh);
  if (merged.Total() > 0) spdlog::info("assemble: {}", merged.ToString());
  out->vertices = mesh.num_vertices();
  out->faces = mesh.num_faces();
  WriteMesh(out->mesh_path, mesh);
  mesh = TriangleMesh{};
  WriteDsm(out->dsm_path, dsm);
  if (all_confidence) {
    out->confidence_path = (fs::path(out_dir) / "confidence.tif").string();
    WriteDsm(out->confidence_path, confidence);
  }
}

}  // namespace

Tileset BuildTileset(const JobPlan& plan, const std::vector<TileResult>& results) {
  Tileset ts;
  ts.geometric_error = plan.tile_cells * plan.dsm.geo_transform[1];
  ts.region = {1e300, 1e300, -1e300, -1e300, 1e300, -1e300};
  for (const auto& r : results) {
    if (!r.ok) continue;
    TilesetTile t{r.name, TileGlbPath(plan.tiles[r.index]), r.region, r.transform, 0.0};
    for (int k : {0, 1, 4}) ts.region[k] = std::min(ts.region[k], r.region[k]);
    for (int k : {2, 3, 5}) ts.region[k] = std::max(ts.region[k], r.region[k]);
    ts.tiles.push_back(t);
  }
  return ts;
}

Assembly AssembleOutputs(const JobPlan& plan, const std::vector<TileResult>& results,
                         const std::string& out_dir) {
  const auto t0 = std::chrono::steady_clock::now();
  Assembly out;
  std::string first_error;
  for (const auto& r : results) {
    (r.ok ? out.tiles_ok : out.tiles_failed)++;
    if (!r.ok && first_error.empty()) first_error = r.name + ": " + r.error;
  }
  SATMESH_CHECK(out.tiles_ok > 0, ErrorCode::kInvalidInput, "every tile failed; first: " + first_error);
  out.mesh_path = (fs::path(out_dir) / "mesh.ply").string();
  out.dsm_path = (fs::path(out_dir) / "dsm.tif").string();
  if (!CopiedTheOnlyTile(plan, results, out_dir, &out)) MergeTiles(plan, results, out_dir, &out);

  // Seams between successful neighbours.
  std::vector<double> all;
  for (const auto& r : results) {
    if (!r.ok) continue;
    const PlannedTile& ta = plan.tiles[r.index];
    std::optional<TileDsm> da;
    for (const bool east : {true, false}) {
      const int j = plan.IndexOf(ta.x + (east ? 1 : 0), ta.y + (east ? 0 : 1));
      if (j < 0 || !results[j].ok) continue;
      if (!da) da = LoadTileDsm(out_dir, ta);
      const auto diffs = SeamDiffs(*da, LoadTileDsm(out_dir, plan.tiles[j]), ta, east);
      out.seams.push_back(Stats(r.name, results[j].name, diffs));
      all.insert(all.end(), diffs.begin(), diffs.end());
    }
  }
  out.seams_total = Stats("all", "all", all);
  out.tileset = BuildTileset(plan, results);
  out.assemble_s = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  return out;
}

}  // namespace satmesh
