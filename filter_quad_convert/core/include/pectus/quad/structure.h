// Mesh structure modification operators of thesis 4.1.3 for triangle and quad meshes:
//  - edge swapping toward the ideal valence (6 for triangles, 4 for quads; boundary nodes: 4 and 3),
//  - node elimination of under-connected interior nodes (triangles: valence 3 -> one triangle; quads: valence 2
//    -> one quad, valence 3 -> two quads),
//  - edge dividing of long interior edges (triangles: the two triangles -> four; quads: the two quads -> three,
//    the new node at the edge's middle on the C1 surface).
// One pass: swaps, then eliminations, then divisions; passes repeat until nothing changes.
// Every operation is applied only if it keeps every element valid (alpha, beta > 0 along the local normal),
// does not lower the worst quality of the elements it replaces, improves the valence energy or the local
// quality, stays on the surface (nearly flat neighbourhood; removed nodes close to the new elements), and
// leaves the boundary as it is. Quad mode (the mesh holds quads): operators act on quads; triangles stay.
#pragma once
#include "pectus/c1/surface.h"
#include "pectus/quad/poly_mesh.h"

namespace pectus::quad {

struct StructureOptions {
  bool swap = true, eliminate = true, divide = true;
  double longEdgeFactor = 1.6;   ///< an edge longer than this times the mean edge length is divided
  double maxDihedralDeg = 30.0;  ///< operators act only where the elements' normals differ by at most this
  int maxPasses = 10;
};

struct StructureResult {
  PolyMesh mesh;
  std::size_t swaps = 0, eliminations = 0, divisions = 0;
  int passes = 0;
  PolyStats before, after;
  double seconds = 0;
};

/// `surface` places the new nodes of edge dividing (closest point of the edge midpoint); if null, the
/// midpoint of the straight edge is used. Throws what requirePolyMesh throws: InputError for NaN/Inf
/// vertices, TopologyError for elements other than triangles and quads, bad or repeated indices.
StructureResult improveStructure(const PolyMesh& m, const c1::C1Surface* surface, const StructureOptions& o);

}  // namespace pectus::quad
