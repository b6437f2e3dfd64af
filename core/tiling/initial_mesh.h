#pragma once
// A job's initial mesh (JobSpec::initial_mesh): found, read, checked and repaired, then
// put into the job's planning CRS; each tile's initial surface is it clipped to the
// tile's box (+ overlap), 3D kept. Every error names the spec's field and the file.
#include <string>

#include "core/mesh/mesh_clean.h"
#include "core/tiling/job_spec.h"
#include "core/tiling/tile_plan.h"
#include "core/tiling/tile_run.h"

namespace satmesh {

// The mesh file `path` names: the path itself, or for a directory or a tileset.json the
// mesh.ply beside it (a previous job's assembled result, in its output CRS, with the CRS
// in the file). Throws Error{kNotFound} naming the path when there is none.
std::string InitialMeshFile(const std::string& path);

struct InitialMesh {
  std::string file;       // InitialMeshFile(spec.initial_mesh.path)
  std::string crs;        // of `mesh`'s points
  PointMesh mesh;         // double coordinates in `crs`
  MeshDebris repaired;    // removed when read (CleanMesh)
  Eigen::Vector3d min{0, 0, 0}, max{0, 0, 0};  // bounding box in `crs`
};

// Reads the mesh in its own CRS (spec.initial_mesh.crs, else the file's, else
// spec.output_crs). Throws Error naming "initial.mesh" and the file: kNotFound
// (missing), else kInvalidArgument (a bad argument of the job: unreadable, NaN
// coordinates, zero faces, more than spec.initial_mesh.max_faces faces; no CRS or an
// unknown one, naming "initial.crs"). PLY/OBJ keep coordinates as floats about the bounding box's centre
// rounded to units: in degrees (EPSG:4326) that is ~3 mm.
InitialMesh ReadInitialMesh(const JobSpec& spec);

// The planning CRS of a job whose grid the mesh gives: outputs.crs if projected, else the
// mesh's if projected, else the UTM zone at the mesh's centre (geographic or ECEF meshes).
std::string MeshPlanCrs(const JobSpec& spec, const InitialMesh& mesh);

// The mesh in `crs` (x, y on the map, z ellipsoidal height; projected), repaired there
// (CleanMesh in metres: close vertices merged, degenerate and duplicate faces and
// unreferenced vertices dropped; non-manifold faces are dropped later by the coarse
// remeshing), its holes up to fill_holes_m across filled (FillHoles; 0: none). Throws Error{kInvalidArgument} naming the file when a point does not
// transform, when nothing is left after the repair, or when the surface faces down
// (more than twice as much area faces down as up, seen from above: inverted orientation).
InitialMesh InitialMeshIn(const InitialMesh& mesh, const std::string& crs, double fill_holes_m);

// The part of `mesh` (in the plan's CRS) inside `box`, debris-free (ClipToBox).
PointMesh ClipInitialMesh(const InitialMesh& mesh, const Box2d& box);

}  // namespace satmesh
