// The one conversion between MeshLab's CMeshO and the cores' Surface (pectus/surface.h), with the index
// maps back into the CMeshO, and the exact self-intersection test (pectus/self_intersections.h) on a CMeshO.
#pragma once
#include <cstddef>
#include <functional>
#include <vector>

#include "pectus/cmesh.h"
#include "pectus/surface.h"

namespace pectus {

/// Which vertices and faces of a CMeshO surfaceOf takes. Deleted faces are always left out.
struct SurfaceOf {
  enum class Vertices {
    Live,         ///< every live vertex, in m.vert order
    All,          ///< every entry of m.vert, deleted ones included: Surface indices are m.vert indices
    UsedByFaces,  ///< the vertices the kept faces use, in the order the faces first use them
  };
  Vertices vertices = Vertices::Live;
  bool skipNonFiniteFaces = false;            ///< leave out faces with a NaN/Inf corner
  std::function<bool(std::size_t)> keepFace;  ///< keep face m.face[i] (all live faces when empty)
};

/// The surface of `m` as `how` says. `vertexOf` receives, per Surface vertex, its index in m.vert, and
/// `faceOf`, per Surface face, its index in m.face.
Surface surfaceOf(const CMeshO& m, const SurfaceOf& how = {}, std::vector<int>* vertexOf = nullptr,
                  std::vector<int>* faceOf = nullptr);

/// Replaces the content of `m` with `s` (and per-vertex normals if given, one per vertex of s).
void toMesh(const Surface& s, CMeshO& m, const std::vector<Eigen::Vector3d>* normals = nullptr);

/// Indices (into m.face) of the live faces that intersect another face of m other than along their shared
/// edge or vertex, by the project's one exact check (pectus/self_intersections.h: faces sharing a vertex
/// are tested too, which vcg's Clean::SelfIntersections skips). m must be a manifold surface; empty if none.
std::vector<int> selfIntersectingFaces(const CMeshO& m);

}  // namespace pectus
