// Internal to the C1 surface core: the mesh topology's checks and the patch index.
#pragma once
#include <array>
#include <vector>

#include "pectus/c1/surface.h"

namespace pectus::c1 {

/// The mesh's topology (pectus/surface.h), checked for the C1 surface: throws TopologyError for invalid
/// indices, duplicate faces, non-manifold edges or vertices, InputError for NaN/Inf coordinates.
Topology checkedTopology(const TriMesh& m);

/// spatial grid of the patches' bounding boxes (closestPoint)
struct C1Surface::Index {
  Vec3 lo, hi;
  double cs = 1;
  int dim[3] = {1, 1, 1};
  std::vector<Vec3> bmin, bmax;          // per face
  std::vector<int> cellStart, cellFaces; // CSR
  int cell(int x, int y, int z) const { return (z * dim[1] + y) * dim[0] + x; }
};

}  // namespace pectus::c1
