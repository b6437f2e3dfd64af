// Micro-benchmarks of the refinement's hot paths (Google Benchmark). Not a ctest test:
// run build/tests/bench/satmesh_micro_bench by hand (numbers in BENCHMARKS.md). Parallel
// (OpenMP) benchmarks report wall time and the CPU time of all threads.
// Fixture: a 1024² px view at 0.5 m GSD, 20° off nadir, with a cubic RPC, over a 512 m
// square of blocky "city" heights meshed at 1 m (0.53 M faces). The "Refinement"
// variants use what a level-0 iteration sees: a mesh of 1.4 faces per pixel (0.6 m grid,
// 1.46 M faces; the large preset's tiles have 1.4 per hit pixel) in Z-order (SortSpatially), and a partner view from the opposite orbit
// direction (its image rotated by 160°, like ascending vs descending passes).
#include <benchmark/benchmark.h>

#include <cmath>
#include <random>

#include "core/mesh/topology.h"
#include "core/refine/coarse_mesh.h"
#include "core/raycast/ray_scene.h"
#include "core/refine/hit_map_raster.h"
#include "core/refine/lattice_avx2.h"
#include "core/refine/photometric_gradient.h"
#include "core/refine/projection_grid.h"
#include "core/refine/thin_plate.h"
#include "core/refine/view_level.h"
#include "core/refine/zncc.h"
#include "core/rpc/rpc_model.h"

namespace satmesh {
namespace {

constexpr int kSizePx = 1024;
constexpr double kGsdM = 0.5;
const LocalFrame& Frame() {
  static const LocalFrame frame(Eigen::Vector3d(5.44, 43.26, 100.0));
  return frame;
}

// RPC looking at the frame centre from (off_nadir, azimuth), with small cubic and
// denominator terms so every monomial of the RFM matters.
RpcModel ViewRpc(double off_nadir_deg, double azimuth_deg, double image_rotation_deg = 0) {
  const LocalFrame& frame = Frame();
  RpcCoefficients c;
  const Eigen::Vector3d center = frame.center_lon_lat_h();
  c.long_off = center.x(), c.lat_off = center.y(), c.height_off = center.z();
  c.long_scale = c.lat_scale = 0.005;
  c.height_scale = 100;
  c.samp_off = c.line_off = 0.5 * kSizePx - 0.5;
  c.samp_scale = c.line_scale = 0.5 * kSizePx;
  const double sx = c.long_scale * frame.meters_per_degree_lon();
  const double sy = c.lat_scale * frame.meters_per_degree_lat();
  const double t = std::tan(off_nadir_deg * M_PI / 180), phi = azimuth_deg * M_PI / 180;
  // Ground (east, north) to image axes, rotated by image_rotation_deg.
  const double rot = image_rotation_deg * M_PI / 180, cr = std::cos(rot), sr = std::sin(rot);
  c.samp_num[1] = cr * sx / kGsdM / c.samp_scale;
  c.samp_num[2] = -sr * sy / kGsdM / c.samp_scale;
  c.samp_num[3] = -c.height_scale * t * std::sin(phi) / kGsdM / c.samp_scale;
  c.line_num[1] = -sr * sx / kGsdM / c.line_scale;
  c.line_num[2] = -cr * sy / kGsdM / c.line_scale;
  c.line_num[3] = c.height_scale * t * std::cos(phi) / kGsdM / c.line_scale;
  for (int k = 4; k < 20; ++k) {
    c.samp_num[k] = 1e-4 * std::sin(k), c.line_num[k] = 1e-4 * std::cos(k);
    c.samp_den[k] = 1e-5 * std::cos(3 * k), c.line_den[k] = 1e-5 * std::sin(3 * k);
  }
  c.samp_den[0] = c.line_den[0] = 1;
  c.samp_den[1] = 1e-3, c.line_den[2] = -1e-3;
  return RpcModel::FromCoefficients(c);
}

double CityZ(double x, double y) {
  const double block = (std::sin(x / 23.0) > 0.2 && std::cos(y / 19.0) > 0.1) ? 12.0 : 0.0;
  return block + 0.5 * std::sin(x / 7.0) * std::cos(y / 5.0);
}

// The city heights as a grid mesh over [-256, 256]² m with the given spacing.
TriangleMesh CityGridMesh(double spacing_m) {
  TriangleMesh m;
  const int n = int(std::lround(512 / spacing_m)) + 1;
  for (int j = 0; j < n; ++j)
    for (int i = 0; i < n; ++i) {
      const double x = i * spacing_m - 256, y = j * spacing_m - 256;
      m.vertices.emplace_back(float(x), float(y), float(CityZ(x, y)));
    }
  for (int j = 0; j + 1 < n; ++j) {
    for (int i = 0; i + 1 < n; ++i) {
      const int v00 = j * n + i, v10 = v00 + 1, v01 = v00 + n, v11 = v01 + 1;
      m.faces.emplace_back(v00, v10, v11);
      m.faces.emplace_back(v00, v11, v01);
    }
  }
  return m;
}

const TriangleMesh& RefinementMesh() {
  static const TriangleMesh mesh = [] {
    TriangleMesh m = CityGridMesh(512.0 / 853);
    SortSpatially(&m);
    return m;
  }();
  return mesh;
}

const TriangleMesh& CityMesh() {
  static const TriangleMesh mesh = CityGridMesh(1.0);
  return mesh;
}

ImageF NoiseImage(uint32_t seed) {
  ImageF image(kSizePx, kSizePx);
  std::mt19937 rng(seed);
  std::uniform_real_distribution<float> u(0.f, 1.f);
  for (float& p : image.pixels) p = u(rng);
  return image;
}

const Eigen::Vector3d kBoxMin(-266, -266, -10), kBoxMax(266, 266, 30);

ViewLevel MakeView(int index, double off_nadir_deg, double azimuth_deg,
                   double image_rotation_deg = 0) {
  return MakeViewLevel(index, 0, NoiseImage(index + 1),
                       ViewRpc(off_nadir_deg, azimuth_deg, image_rotation_deg), Frame(), kBoxMin,
                       kBoxMax, /*grid_px=*/16);
}

std::vector<Eigen::Vector3d> RandomLocalPoints(size_t n) {
  std::mt19937 rng(7);
  std::uniform_real_distribution<double> xy(-250, 250), z(-5, 25);
  std::vector<Eigen::Vector3d> points(n);
  for (auto& p : points) p = Eigen::Vector3d(xy(rng), xy(rng), z(rng));
  return points;
}

void BM_RpcPixelFromGeo(benchmark::State& state) {
  const RpcModel rpc = ViewRpc(20, 30);
  auto points = RandomLocalPoints(4096);
  for (auto& p : points) p = Frame().GeoFromLocal(p);
  Eigen::Matrix<double, 2, 3> jacobian;
  const bool with_jacobian = state.range(0) != 0;
  size_t i = 0;
  for (auto _ : state) {
    const auto& p = points[i++ & 4095];
    benchmark::DoNotOptimize(with_jacobian ? rpc.PixelFromGeo(p, &jacobian) : rpc.PixelFromGeo(p));
    benchmark::DoNotOptimize(jacobian);
  }
  state.SetItemsProcessed(state.iterations());
}
BENCHMARK(BM_RpcPixelFromGeo)->ArgName("jacobian")->Arg(0)->Arg(1);

void BM_RpcLocalizeLonLat(benchmark::State& state) {
  const RpcModel rpc = ViewRpc(20, 30);
  std::mt19937 rng(3);
  std::uniform_real_distribution<double> px(0, kSizePx);
  std::vector<Eigen::Vector2d> pixels(4096);
  for (auto& p : pixels) p = Eigen::Vector2d(px(rng), px(rng));
  size_t i = 0;
  for (auto _ : state) benchmark::DoNotOptimize(rpc.LocalizeLonLat(pixels[i++ & 4095], 110.0));
  state.SetItemsProcessed(state.iterations());
}
BENCHMARK(BM_RpcLocalizeLonLat);

void BM_ProjectionGridPixelFromLocal(benchmark::State& state) {
  const ProjectionGrid grid(ViewRpc(20, 30), Frame(), kBoxMin, kBoxMax, 16.0, 8.0);
  const auto points = RandomLocalPoints(4096);
  Eigen::Matrix<double, 2, 3> jacobian;
  size_t i = 0;
  for (auto _ : state) {
    benchmark::DoNotOptimize(grid.PixelFromLocal(points[i++ & 4095], &jacobian));
    benchmark::DoNotOptimize(jacobian);
  }
  state.SetItemsProcessed(state.iterations());
}
BENCHMARK(BM_ProjectionGridPixelFromLocal);

void BM_ComputeZnccField(benchmark::State& state) {  // 1 Mpx, window (2r+1)²
  const ImageF a = NoiseImage(1), b = NoiseImage(2);
  std::vector<uint8_t> valid(a.pixels.size(), 1);
  for (size_t i = 0; i < valid.size(); i += 7) valid[i] = 0;
  if (state.range(1)) {  // only a square rotated by 30° is seen (64% of the crop, as on a tile)
    const double c = std::cos(M_PI / 6), s = std::sin(M_PI / 6), half = 0.4 * kSizePx;
    for (int y = 0; y < kSizePx; ++y)
      for (int x = 0; x < kSizePx; ++x) {
        const double u = x - 0.5 * kSizePx, v = y - 0.5 * kSizePx;
        if (std::abs(c * u + s * v) > half || std::abs(-s * u + c * v) > half)
          valid[size_t(y) * kSizePx + x] = 0;
      }
  }
  ZnccOptions options;
  options.window_radius = int(state.range(0));
  ZnccWorkspace workspace;
  for (auto _ : state)
    benchmark::DoNotOptimize(ComputeZnccField(a.pixels, b.pixels, valid, kSizePx, kSizePx, options, &workspace));
  state.SetItemsProcessed(state.iterations() * a.pixels.size());
}
BENCHMARK(BM_ComputeZnccField)->ArgNames({"radius", "footprint"})->Args({2, 0})->Args({3, 0})->Args({2, 1})->Unit(benchmark::kMillisecond)
    ->UseRealTime()->MeasureProcessCPUTime();

void BM_RaySceneIntersect1M(benchmark::State& state) {
  const RayScene scene(CityMesh());
  const std::vector<Ray> rays = PixelRays(MakeView(0, 20, 30));  // 1024² rays
  std::vector<RayHit> hits(rays.size());
  for (auto _ : state) scene.Intersect(rays.data(), hits.data(), hits.size());
  state.SetItemsProcessed(state.iterations() * hits.size());
}
BENCHMARK(BM_RaySceneIntersect1M)->Unit(benchmark::kMillisecond)->UseRealTime()->MeasureProcessCPUTime();

void BM_RaySceneBuild(benchmark::State& state) {
  for (auto _ : state) RayScene scene(CityMesh());
  state.SetItemsProcessed(state.iterations() * CityMesh().num_faces());
}
BENCHMARK(BM_RaySceneBuild)->Unit(benchmark::kMillisecond)->UseRealTime()->MeasureProcessCPUTime();

void BM_RaySceneUpdateVertices(benchmark::State& state) {
  RayScene scene(CityMesh());
  auto vertices = CityMesh().vertices;
  for (auto _ : state) {
    for (auto& v : vertices) v.z() += 1e-3f;
    scene.UpdateVertices(vertices);
  }
}
BENCHMARK(BM_RaySceneUpdateVertices)->Unit(benchmark::kMillisecond)->UseRealTime()->MeasureProcessCPUTime();

void BM_CastHitMap(benchmark::State& state) {
  const RayScene scene(CityMesh());
  ViewLevel view = MakeView(0, 20, 30);
  for (auto _ : state) CastHitMap(scene, &view);
  state.SetItemsProcessed(state.iterations() * view.ray_directions.size());
}
BENCHMARK(BM_CastHitMap)->Unit(benchmark::kMillisecond)->UseRealTime()->MeasureProcessCPUTime();

void BM_RasterizeHitMap(benchmark::State& state) {  // the same hit map without Embree
  ViewLevel view = MakeView(0, 20, 30);
  RasterWorkspace workspace;
  for (auto _ : state) RasterizeHitMap(CityMesh(), &view, &workspace);
  state.SetItemsProcessed(state.iterations() * view.ray_directions.size());
}
BENCHMARK(BM_RasterizeHitMap)->Unit(benchmark::kMillisecond)->UseRealTime()->MeasureProcessCPUTime();

void BM_RasterizeHitMaps4Views(benchmark::State& state) {  // one view per thread
  std::vector<ViewLevel> views;
  for (int v = 0; v < 4; ++v) views.push_back(MakeView(v, 15 + 5 * v, 30 + 60 * v));
  HitMapScratch scratch;
  for (auto _ : state) RasterizeHitMaps(CityMesh(), &views, &scratch);
  state.SetItemsProcessed(state.iterations() * 4 * views[0].ray_directions.size());
}
BENCHMARK(BM_RasterizeHitMaps4Views)->Unit(benchmark::kMillisecond)->UseRealTime()->MeasureProcessCPUTime();

void BM_MakeViewLevel(benchmark::State& state) {  // virtual camera + lattice + 1M rays
  for (auto _ : state) benchmark::DoNotOptimize(MakeView(0, 20, 30));
}
BENCHMARK(BM_MakeViewLevel)->Unit(benchmark::kMillisecond)->UseRealTime()->MeasureProcessCPUTime();

void BM_AccumulatePhotometricGradient(benchmark::State& state) {  // one pair-direction
  const TriangleMesh& mesh = CityMesh();
  const RayScene scene(mesh);
  ViewLevel view_i = MakeView(0, 20, 30), view_j = MakeView(1, 15, 60);
  CastHitMap(scene, &view_i);
  CastHitMap(scene, &view_j);
  const auto normals = FaceNormals(mesh);
  PhotometricOptions options;
  options.visibility_tolerance_m = 2 * kGsdM;
  std::vector<Eigen::Vector3d> gradient(mesh.num_vertices(), Eigen::Vector3d::Zero());
  std::vector<uint8_t> touched(mesh.num_vertices());
  PairWorkspace workspace;
  for (auto _ : state)
    benchmark::DoNotOptimize(AccumulatePhotometricGradient(view_i, view_j, mesh, normals, options,
                                                           &gradient, &touched, &workspace));
  state.SetItemsProcessed(state.iterations() * view_i.ray_directions.size());
}
BENCHMARK(BM_AccumulatePhotometricGradient)->Unit(benchmark::kMillisecond)->UseRealTime()->MeasureProcessCPUTime();

void BM_RasterizeHitMapRefinement(benchmark::State& state) {  // 1.4 faces per pixel, Z-order
  const TriangleMesh& mesh = RefinementMesh();  // built before the timing
  const auto normals = FaceNormals(mesh);        // ray cosines too, as the refinement asks
  ViewLevel view = MakeView(0, 20, 30);
  RasterWorkspace workspace;
  for (auto _ : state) RasterizeHitMap(mesh, &view, &workspace, &normals);
  state.SetItemsProcessed(state.iterations() * view.width() * view.height());
}
BENCHMARK(BM_RasterizeHitMapRefinement)->Unit(benchmark::kMillisecond)->UseRealTime()->MeasureProcessCPUTime();

// One pair-direction as a level-0 iteration runs it: 1.4 faces per pixel in Z-order, the
// partner image rotated by 160°, one thread's accumulator.
void BM_PairDirectionRefinement(benchmark::State& state) {
  const TriangleMesh& mesh = RefinementMesh();
  ViewLevel view_i = MakeView(0, 20, 30), view_j = MakeView(1, 15, 200, /*rotation=*/160);
  const auto normals = FaceNormals(mesh);
  RasterWorkspace raster;
  RasterizeHitMap(mesh, &view_i, &raster, &normals);
  RasterizeHitMap(mesh, &view_j, &raster, &normals);
  PhotometricOptions options;
  options.visibility_tolerance_m = 2 * kGsdM;
  const VertexAdjacency adjacency = BuildVertexAdjacency(mesh);
  GradientAccumulator accumulator;
  accumulator.Reset(mesh, adjacency);
  PairWorkspace workspace;
  for (auto _ : state)
    benchmark::DoNotOptimize(
        AccumulatePairGradient(view_i, view_j, normals, options, &accumulator, &workspace));
  state.SetItemsProcessed(state.iterations() * view_i.width() * view_i.height());
}
BENCHMARK(BM_PairDirectionRefinement)->Unit(benchmark::kMillisecond)->UseRealTime()->MeasureProcessCPUTime();

#ifdef SATMESH_HAVE_AVX2_LATTICE
// 8-lane loads from a 4 KiB table (L1), 4 independent chains: the hardware gather
// against lattice_avx2.h's scalar loads and inserts. Items are 8-lane loads; on the
// benchmark machine (gather-data-sampling microcode) the gather is the slower one.
SATMESH_AVX2 __m256 HardwareGather(const float* table, __m256i index, __m256 mask) {
  return _mm256_mask_i32gather_ps(_mm256_setzero_ps(), table, index, mask, 4);
}
template <bool kHardware>
SATMESH_AVX2 void GatherLoop(benchmark::State& state) {
  std::vector<float> table(1024, 1.f);
  std::vector<int> indices(8192);
  for (size_t i = 0; i < indices.size(); ++i) indices[i] = int(i * 37) & 1023;
  const __m256 all = _mm256_castsi256_ps(_mm256_set1_epi32(-1));
  for (auto _ : state) {
    __m256 acc[4] = {_mm256_setzero_ps(), _mm256_setzero_ps(), _mm256_setzero_ps(), _mm256_setzero_ps()};
    for (size_t i = 0; i < indices.size(); i += 32)
      for (int k = 0; k < 4; ++k) {
        const __m256i index = _mm256_loadu_si256(reinterpret_cast<const __m256i*>(&indices[i + 8 * k]));
        acc[k] = _mm256_add_ps(acc[k], kHardware ? HardwareGather(table.data(), index, all)
                                                 : Gather(table.data(), index, all));
      }
    benchmark::DoNotOptimize(acc);
  }
  state.SetItemsProcessed(state.iterations() * indices.size() / 8);
}
void BM_Gather8Lanes(benchmark::State& state) {
  if (!HasAvx2Lattice()) return state.SkipWithError("no AVX2");
  state.range(0) ? GatherLoop<true>(state) : GatherLoop<false>(state);
}
BENCHMARK(BM_Gather8Lanes)->ArgName("vgatherdps")->Arg(0)->Arg(1);
#endif

void BM_UmbrellaSquared(benchmark::State& state) {
  const VertexAdjacency adjacency = BuildVertexAdjacency(CityMesh());
  for (auto _ : state) benchmark::DoNotOptimize(UmbrellaSquared(CityMesh().vertices, adjacency));
  state.SetItemsProcessed(state.iterations() * CityMesh().num_vertices());
}
BENCHMARK(BM_UmbrellaSquared)->Unit(benchmark::kMillisecond)->UseRealTime()->MeasureProcessCPUTime();

}  // namespace
}  // namespace satmesh

BENCHMARK_MAIN();
