// Self-intersecting faces of a triangle mesh by CGAL's Polygon_mesh_processing::self_intersections (exact
// predicates; faces sharing a vertex or an edge are tested too, which vcg's Clean::SelfIntersections skips
// for faces sharing a vertex, so folds of neighbouring faces went unnoticed). Host-free.
#pragma once
#include <vector>

#include "pectus/cmesh.h"

namespace pectus::ribcage {

/// Indices (into m.face) of the live faces that intersect another face of m other than along their shared
/// edge or vertex. m must be a manifold surface (as the generator's meshes are); empty if none.
std::vector<int> selfIntersectingFaces(const CMeshO& m);

}  // namespace pectus::ribcage
