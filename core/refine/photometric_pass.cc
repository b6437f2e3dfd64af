#include "core/refine/photometric_pass.h"

#include <omp.h>

#include "core/common/threads.h"

namespace satmesh {

std::vector<std::pair<int, int>> PairDirections(const std::vector<std::pair<int, int>>& pairs,
                                                int one_direction) {
  std::vector<std::pair<int, int>> directions;
  for (size_t k = 0; k < pairs.size(); ++k) {
    const auto [i, j] = pairs[k];
    if (one_direction < 0) directions.insert(directions.end(), {{i, j}, {j, i}});
    else directions.push_back((one_direction + k) % 2 == 0 ? std::pair{i, j} : std::pair{j, i});
  }
  return directions;
}

double PhotometricPass(std::vector<ViewLevel>& views, const std::vector<int>& slot,
                       const std::vector<std::pair<int, int>>& pairs, const TriangleMesh& mesh,
                       const std::vector<Eigen::Vector3f>& normals,
                       const VertexAdjacency& adjacency, const PhotometricOptions& options,
                       std::vector<PassScratch>* scratch,
                       std::vector<Eigen::Vector3d>* gradient, std::vector<int>* seen,
                       int one_direction, std::vector<double>* information,
                       std::vector<PairEnergy>* energies,
                       std::vector<std::vector<float>>* windows) {
  const std::vector<std::pair<int, int>> directions = PairDirections(pairs, one_direction);
  const bool accumulate = gradient || seen || information;
  double sum = 0;
  long count = 0;
  if (scratch->size() < size_t(omp_get_max_threads())) scratch->resize(omp_get_max_threads());
  if (energies) energies->assign(directions.size(), PairEnergy{});
  if (windows) windows->assign(directions.size(), {});
  auto direction = [&](size_t d, PassScratch& own) {
    const auto [a, b] = directions[d];
    const PairEnergy e = AccumulatePairGradient(views[slot[a]], views[slot[b]], normals, options,
                                                accumulate ? &own.accumulator : nullptr,
                                                &own.workspace);
    if (energies) (*energies)[d] = e;
    if (windows) (*windows)[d] = std::move(own.workspace.field.windows);
    return e;
  };
  if (!OnePerThread(directions.size())) {
    // One direction after the other, every thread in each one's warp (a stereo pass's
    // single direction).
    PassScratch& own = (*scratch)[0];
    if (accumulate) own.accumulator.Reset(mesh, adjacency, information != nullptr);
    for (size_t d = 0; d < directions.size(); ++d) {
      const PairEnergy e = direction(d, own);
      sum += e.sum_zncc;
      count += e.num_windows;
    }
    if (accumulate) own.accumulator.AddTo(normals, gradient, seen, information);
    return count > 0 ? sum / count : 0.0;
  }
  std::vector<char> took(scratch->size(), 0);  // per thread: a direction
#pragma omp parallel
  {
    PassScratch& own = (*scratch)[omp_get_thread_num()];
    if (accumulate) own.accumulator.Reset(mesh, adjacency, information != nullptr);
#pragma omp for schedule(dynamic, 1) reduction(+ : sum, count)
    for (size_t d = 0; d < directions.size(); ++d) {
      const PairEnergy e = direction(d, own);
      sum += e.sum_zncc;
      count += e.num_windows;
      took[omp_get_thread_num()] = 1;
    }
  }
  // The threads' shares in thread order (each AddTo in parallel over the vertices).
  for (size_t t = 0; t < took.size() && accumulate; ++t)
    if (took[t]) (*scratch)[t].accumulator.AddTo(normals, gradient, seen, information);
  return count > 0 ? sum / count : 0.0;
}

}  // namespace satmesh
