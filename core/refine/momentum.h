#pragma once
// The heavy-ball step of the refinement's iterations (RefineOptions::momentum).
#include <Eigen/Core>

#include <cmath>

namespace satmesh {

// The heavy ball's carried move (MomentumStep): per coordinate, the smaller of a vertex's
// last two moves where they have the same sign, else 0 (minmod): what both directions of a
// pair, taken in turn, moved it by; their swing is not carried.
inline Eigen::Vector3f AgreedMove(const Eigen::Vector3f& last, const Eigen::Vector3f& before) {
  Eigen::Vector3f agreed;
  for (int c = 0; c < 3; ++c)
    agreed[c] = last[c] * before[c] <= 0 ? 0.f
                : std::abs(last[c]) < std::abs(before[c]) ? last[c] : before[c];
  return agreed;
}

// The heavy-ball step: the gradient step plus momentum x the move the vertex's last two
// (clamped) moves agree on (AgreedMove). A move the iterations agree on grows to
// 1 / (1 - momentum) gradient steps; the swing between a pair's two directions, taken in
// turn, and between the pair groups is not carried at all. Carrying the last move itself
// (the classic heavy ball) damps that swing only to 1 / (1 + momentum), and where the level
// ends in it depended on the parity of the iteration count: the multi-date 0.3 m set's
// roofs 10% worse with 20 iterations than with 21 or 25, even after 6 plain steps
// (docs/benchmarks-history.md, sessions 31 and 32).
inline Eigen::Vector3d MomentumStep(const Eigen::Vector3d& gradient_step,
                                    const Eigen::Vector3f& agreed_move, double momentum) {
  return gradient_step + momentum * agreed_move.cast<double>();
}

}  // namespace satmesh
