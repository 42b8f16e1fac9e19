// Internal to the C1 surface core: mesh topology (vertex->faces, edges) with the manifold checks.
#pragma once
#include <array>
#include <vector>

#include "pectus/c1_surface.h"

namespace pectus::c1 {

struct Topology {
  struct Edge {
    int a, b;    ///< vertices, a < b
    int f0, f1;  ///< face*3 + local edge (local edge l is opposite local vertex l); f1 = -1 on the boundary
  };
  /// Throws TopologyError for invalid indices, duplicate faces, non-manifold edges or vertices, InputError
  /// for NaN/Inf coordinates.
  explicit Topology(const TriMesh& m);
  std::vector<int> vfStart, vf;             ///< CSR vertex -> faces
  std::vector<Edge> edges;
  std::vector<std::array<int, 3>> faceEdge; ///< per face: edge id of local edge l (-1 for a collapsed edge)
  std::vector<char> boundary;               ///< per vertex
};

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
