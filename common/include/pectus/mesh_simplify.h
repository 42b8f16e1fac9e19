// Quadric edge-collapse decimation of a closed CMeshO to a target face count, topology preserving
// (link condition), with normal-flip and triangle-quality checks; with embeddingCell > 0 (mm, the cell of
// the face grid) no collapse may make the surface intersect itself (exact predicates, as CGAL's
// self_intersections tests a surface); `guarded`: only collapses touching these boxes are checked (empty:
// all; the regions hold the collapses that folded the surface in an unguarded run).
#pragma once
#include <vector>

#include "pectus/cmesh.h"

namespace pectus {
void decimateQuadric(CMeshO& m, int targetFaces, double embeddingCell = 0, const std::vector<vcg::Box3<Scalarm>>& guarded = {});

/// Decimates a closed, embedded (self-intersection-free) surface to `targetFaces` and keeps it embedded:
/// quadric decimation, checked; while the result intersects itself it is redone from the input with the
/// embedding guard around every place that folded so far (a collapse that would make two faces cross there
/// is refused; exact predicates); the last attempt guards every collapse. `edgeLength` (mm) sizes the
/// guard's grid and boxes. Returns the number of attempts redone; throws pectus::InternalError if even the
/// fully guarded decimation intersects itself.
int decimateEmbedded(CMeshO& m, int targetFaces, double edgeLength);
}
