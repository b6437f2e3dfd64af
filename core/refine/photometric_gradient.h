#pragma once
// The photometric gradient through the RFM (paper 3.2.3, eq. satgrad), for one ordered
// pair (i -> j): view i's pixels hit the surface at X, are warped into j by the RFM, and
// the derivative of M_ij = -Σ ZNCC is pulled back to the vertices:
//   ∂M/∂V_k = Σ_pixels φ · ∂M/∂b · ∇I_j(x_j) · DΠ_j(X) · n_d,i / (n_d,i · n) · w_k · n
// (n_d,i the unit ray of i, n the face normal, w_k the barycentric weight of vertex k,
// φ visibility in both views). This is the exact derivative of the discrete energy for
// fixed visibility; multiplying by the level GSD (in the update) makes it scale-free.
#include <Eigen/Core>
#include <vector>

#include "core/geo/local_frame.h"
#include "core/mesh/mesh.h"
#include "core/refine/view_level.h"
#include "core/refine/zncc.h"

namespace satmesh {

struct PhotometricOptions {
  ZnccOptions zncc;
  double visibility_tolerance_m = 0.6;  // depth test: |X - X_j| below this, metres, > 0
  double min_ray_cos = 0.1;             // ignore pixels whose |cos(ray, normal)| is below, [0,1)
};

struct PairEnergy {
  double sum_zncc = 0;   // Σ ZNCC over view i's windows (M_ij = -sum_zncc)
  long num_windows = 0;
  long num_valid_pixels = 0;
};

// Scratch buffers of one pair-direction, reused across calls.
struct PairWorkspace {
  std::vector<float> a, b, db_dn;
  std::vector<uint8_t> valid;
  ZnccWorkspace zncc;
};

// Adds ∂M_ij/∂V into *vertex_gradient (if not null) and marks the vertices this
// pair-direction touched in *touched (if not null). Hit maps of both views must be current.
PairEnergy AccumulatePhotometricGradient(const ViewLevel& view_i, const ViewLevel& view_j,
                                         const TriangleMesh& mesh,
                                         const std::vector<Eigen::Vector3f>& face_normals,
                                         const PhotometricOptions& options,
                                         std::vector<Eigen::Vector3d>* vertex_gradient,
                                         std::vector<uint8_t>* touched,
                                         PairWorkspace* workspace = nullptr);

}  // namespace satmesh
