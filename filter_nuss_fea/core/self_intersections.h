// Self-intersecting faces of a CMeshO by the project's one check (pectus/self_intersections.h: CGAL's
// exact Polygon_mesh_processing::self_intersections; faces sharing a vertex or an edge are tested too,
// which vcg's Clean::SelfIntersections skips for faces sharing a vertex). Host-free.
#pragma once
#include <vector>

#include "pectus/cmesh.h"

namespace pectus::ribcage {

/// Indices (into m.face) of the live faces that intersect another face of m other than along their shared
/// edge or vertex. m must be a manifold surface (as the generator's meshes are); empty if none.
std::vector<int> selfIntersectingFaces(const CMeshO& m);

}  // namespace pectus::ribcage
