#pragma once
// A mesh moved along its normals by smooth random noise: the start of a refinement from a
// good but imperfect 3D mesh (issue 20), with the truth known.
#include <cstdint>
#include <string>

#include "core/mesh/mesh.h"

namespace satmesh::synth {

struct PerturbOptions {
  double amplitude_m = 1.0;    // of the noise, as a sinusoid's (RMS = amplitude / sqrt 2), >= 0
  double wavelength_m = 15.0;  // of its plane waves, > 0 (buildings are 10-30 m)
  int waves = 8;               // random plane waves summed, [1, 64]
  uint32_t seed = 1;           // directions and phases derive from it
  std::string Check() const;
};

// Each vertex moves along its area-weighted normal (VertexNormals) by
// amplitude * sum_k sin(2 pi d_k . p / wavelength + phi_k) / sqrt(waves), with d_k random
// unit 3D directions and phi_k random phases. Vertices at one position get one normal
// (the mean of theirs), so a mesh with split vertices does not crack open. Deterministic
// in seed. Throws Error{kInvalidArgument} for bad options.
TriangleMesh PerturbAlongNormals(const TriangleMesh& mesh, const PerturbOptions& options);

}  // namespace satmesh::synth
