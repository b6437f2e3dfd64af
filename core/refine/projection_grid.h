#pragma once
// Fast RFM projection for the refinement's inner loop: the 3D box of the surface is cut
// into cells of the local frame, and in each cell the RFM of a view (at one level) is
// replaced by its first-order expansion at the cell centre (exact pixel and Jacobian).
// The RFM is smooth at the cell scale (second derivatives ~1e-5 px/m²), so over a
// 16 x 16 x 8 m cell the error stays below 1e-3 px (checked in a test against the exact
// RPC). One cell is one cache line: a projection is a lookup and six multiply-adds.
// Points outside the box fall back to the exact RPC.
#include <Eigen/Core>
#include <cmath>
#include <vector>

#include "core/geo/local_frame.h"
#include "core/rpc/rpc_model.h"

namespace satmesh {

class ProjectionGrid {
 public:
  ProjectionGrid() = default;
  // Cells over [box_min, box_max] (frame metres) with the given sizes.
  ProjectionGrid(const RpcModel& rpc_level, const LocalFrame& frame, const Eigen::Vector3d& box_min,
                 const Eigen::Vector3d& box_max, double spacing_xy_m, double spacing_z_m);

  // Pixel (col, row) of frame point X and d(col,row)/d(x,y,z).
  Eigen::Vector2d PixelFromLocal(const Eigen::Vector3d& X,
                                 Eigen::Matrix<double, 2, 3>* pixel_from_local) const {
    const Eigen::Vector3d g = (X - origin_).cwiseProduct(inv_spacing_);
    const int i = int(std::floor(g.x())), j = int(std::floor(g.y())), k = int(std::floor(g.z()));
    if (i < 0 || j < 0 || k < 0 || i >= nx_ || j >= ny_ || k >= nz_)
      return ExactPixelFromLocal(X, pixel_from_local);
    const Cell& cell = cells_[(size_t(k) * ny_ + j) * nx_ + i];
    const Eigen::Vector3d d = (g - Eigen::Vector3d(i + 0.5, j + 0.5, k + 0.5)).cwiseProduct(spacing_);
    *pixel_from_local = cell.pixel_from_local;
    return cell.pixel + cell.pixel_from_local * d;
  }

  // The same lattice in float, for vectorised projection (8 points at a time): cell
  // (i, j, k) is cells[(k ny + j) nx + i], and pixel = cell.pixel + J (g - ijk - 0.5)
  // spacing with g = (X - origin) inv_spacing. Rounding the cell centres' pixels to
  // float adds < 2.5e-4 px (images below 4096 px) to the lattice's < 1e-3 px. Points
  // outside the lattice (g out of [0, n)) need PixelFromLocal.
  struct FloatCell {
    float pixel[2];
    float jacobian[6];  // d(col, row)/d(x, y, z), row-major
  };
  struct FloatLattice {
    const FloatCell* cells;
    float origin[3], inv_spacing[3], spacing[3];
    int n[3];
  };
  FloatLattice float_lattice() const;

 private:
  Eigen::Vector2d ExactPixelFromLocal(const Eigen::Vector3d& X,
                                      Eigen::Matrix<double, 2, 3>* pixel_from_local) const;

  RpcModel rpc_;
  LocalFrame frame_;
  struct Cell {
    Eigen::Vector2d pixel;                      // at the cell centre
    Eigen::Matrix<double, 2, 3> pixel_from_local;  // at the cell centre
  };
  Eigen::Vector3d origin_{0, 0, 0}, spacing_{1, 1, 1}, inv_spacing_{1, 1, 1};
  int nx_ = 0, ny_ = 0, nz_ = 0;  // cells per axis
  std::vector<Cell> cells_;       // x fastest
  std::vector<FloatCell> float_cells_;
};

}  // namespace satmesh
