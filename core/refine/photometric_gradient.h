#pragma once
// The photometric gradient through the RFM (paper 3.2.3, eq. satgrad), for one ordered
// pair (i -> j): view i's pixels hit the surface at X, are warped into j by the RFM, and
// the derivative of M_ij = -Σ ZNCC is pulled back to the vertices:
//   ∂M/∂V_k = Σ_pixels φ · ∂M/∂b · ∇I_j(x_j) · DΠ_j(X) · n_d,i / (n_d,i · n) · w_k · n
// (n_d,i the unit ray of i, n the face normal, w_k the barycentric weight of vertex k,
// φ visibility in both views). This is the exact derivative of the discrete energy for
// fixed visibility; multiplying by the level GSD (in the update) makes it scale-free.
#include <Eigen/Core>
#include <cstdint>
#include <vector>

#include "core/geo/local_frame.h"
#include "core/mesh/mesh.h"
#include "core/mesh/topology.h"
#include "core/refine/view_level.h"
#include "core/refine/zncc.h"

namespace satmesh {

struct PhotometricOptions {
  ZnccOptions zncc;
  double visibility_tolerance_m = 0.6;  // depth test: |X - X_j| below this, metres, > 0
  double min_ray_cos = 0.1;             // ignore pixels whose |cos(ray, normal)| is below, [0,1)
  bool vectorized = true;               // AVX2 warp where the CPU has it (warp.h); false:
                                        // the scalar reference
  // Where view i's hit map says which suns light its pixels (HitMap::sunlit, both views'
  // suns marked), a pixel lit under one view's sun and shadowed under the other's is left
  // out of the pair-direction (RefineOptions::sunlit_pairs).
  bool sunlit_only = false;
};

struct PairEnergy {
  double sum_zncc = 0;   // Σ ZNCC over view i's windows (M_ij = -sum_zncc)
  long num_windows = 0;
  long num_valid_pixels = 0;
};

// Scratch buffers of one pair-direction, reused across calls (a is view i's image).
struct PairWorkspace {
  std::vector<float> b, db_dn;
  std::vector<uint8_t> valid;
  ZnccField field;
  ZnccWorkspace zncc;
};

// The photometric gradient of many pair-directions, gathered per face (one thread's
// share): pixels add g·(w0, w1, w2) to their face (g = ∂M/∂b · ∂b/∂n, w the barycentric
// weights) and mark the face seen by the current direction; only AddTo() multiplies by
// the face normals and scatters to vertices. A pixel's work is three float adds and an OR
// into one 16-byte slot: which vertices a direction saw is worked out from the faces'
// direction bits, 32 directions at a time.
class GradientAccumulator {
 public:
  // Zeroes everything for `mesh` (kept by reference until AddTo, as is its `adjacency`,
  // BuildVertexAdjacency's: AddTo gathers each vertex's faces, in parallel).
  // with_information: also gather each vertex's height information (AddInformation).
  void Reset(const TriangleMesh& mesh, const VertexAdjacency& adjacency,
             bool with_information = false);
  bool with_information() const { return !information_.empty(); }
  // Starts a new pair-direction (for counting the directions that see each vertex).
  void BeginDirection();
  // Starts loading a face's slot into cache (a pixel some columns ahead).
  void Prefetch(int face) const { __builtin_prefetch(&faces_[face], 1); }
  void AddPixel(int face, float u, float v, float g) {
    FaceSlot& slot = faces_[face];
    slot.weights += Eigen::Vector3f(g * (1.f - u - v), g * u, g * v);
    slot.directions |= direction_bit_;
  }
  // The pixel's contribution to the Fisher information of its face's vertices' positions
  // along the normal: w_k² (∂b/∂n)², ∂b/∂n the warped intensity's derivative (per metre).
  void AddInformation(int face, float u, float v, float db_dn) {
    const float w0 = 1.f - u - v, g2 = db_dn * db_dn;
    information_[face] += Eigen::Vector3f(g2 * w0 * w0, g2 * u * u, g2 * v * v);
  }
  // vertex_gradient[v] += Σ_faces weight · normal; seen[v] += directions that saw v;
  // information[v] += Σ_faces information (if gathered and not null). Each vertex gathers
  // from its faces, the vertices in parallel; it ends the accumulation (Reset before more).
  void AddTo(const std::vector<Eigen::Vector3f>& face_normals,
             std::vector<Eigen::Vector3d>* vertex_gradient, std::vector<int>* seen,
             std::vector<double>* information = nullptr);

 private:
  // Adds the directions marked on the faces to their vertices' counts; clears the marks.
  void CountDirections();

  struct FaceSlot {  // one 16-byte slot per face: a pixel touches one cache line
    Eigen::Vector3f weights = Eigen::Vector3f::Zero();
    uint32_t directions = 0;  // bit d % 32: direction d saw the face (since the last count)
  };
  const TriangleMesh* mesh_ = nullptr;
  const VertexAdjacency* adjacency_ = nullptr;
  std::vector<FaceSlot> faces_;
  std::vector<Eigen::Vector3f> information_;  // per face, if gathered
  std::vector<int> seen_;
  int direction_ = -1;
  uint32_t direction_bit_ = 0;
};

// One ordered pair (i -> j): returns the energy terms and, if accumulator is not null,
// adds the pair-direction's gradient to it (Reset for the mesh whose faces the hit maps
// index). Hit maps of both views must be current.
PairEnergy AccumulatePairGradient(const ViewLevel& view_i, const ViewLevel& view_j,
                                  const std::vector<Eigen::Vector3f>& face_normals,
                                  const PhotometricOptions& options,
                                  GradientAccumulator* accumulator, PairWorkspace* workspace);

// The same for one pair-direction alone: adds ∂M_ij/∂V into *vertex_gradient (if not
// null) and marks the vertices it touched in *touched (if not null).
PairEnergy AccumulatePhotometricGradient(const ViewLevel& view_i, const ViewLevel& view_j,
                                         const TriangleMesh& mesh,
                                         const std::vector<Eigen::Vector3f>& face_normals,
                                         const PhotometricOptions& options,
                                         std::vector<Eigen::Vector3d>* vertex_gradient,
                                         std::vector<uint8_t>* touched,
                                         PairWorkspace* workspace = nullptr);

}  // namespace satmesh
